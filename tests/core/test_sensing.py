"""Realistic sensing and actuation: delays, dropouts, actuator lag, parameter randomisation, and the
delay-aware Kalman filter (``kalman-delay``)."""

from __future__ import annotations

import json
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from conftest import assert_close_to_stored
from scipy.linalg import solve_discrete_are

import pendulum_lqg
from pendulum_lqg import design
from pendulum_lqg.bench.experiments import parse_spec
from pendulum_lqg.cli import main
from pendulum_lqg.core.loop import Simulator
from pendulum_lqg.core.noise import NoiseModel
from pendulum_lqg.core.runner import run_episodes
from pendulum_lqg.core.scenario import Scenario
from pendulum_lqg.core.seeding import child_generator, episode_seed
from pendulum_lqg.envs.agent import LQGAgent
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.model.interface import discretize_zoh
from pendulum_lqg.model.linearize import linearize
from pendulum_lqg.model.overrides import ModelOverrides
from pendulum_lqg.model.plant import load_plant
from pendulum_lqg.policies.estimators import (
    CurrentEstimator,
    DelayKalman,
    PredictorEstimator,
    TimeVaryingKalman,
)
from pendulum_lqg.policies.loading import build_policy
from pendulum_lqg.policies.lqg import DesignSpec, design_policy, per_sample_process_covariance

ID = pendulum_lqg.ENV_ID           # reading it registers the id
BASELINE = Path(__file__).parents[1] / "data" / "pre_delay_baseline.json"
RANDOMIZE = {"pole_mass_scale": (0.5, 2.0), "pole_length_scale": (0.8, 1.25),
             "cart_mass_scale": (0.7, 1.3)}


# ---- zero features: today's numbers, bit for bit ----------------------------------------------------
def _baseline_runs(plant) -> dict[str, object]:
    """The runs stored in ``tests/data/pre_delay_baseline.json`` (made with main's code just before
    this work was merged, commit 89e2e1c, before
    the sensing-and-actuation fields existed), here with every new field given explicitly as 0."""
    zero = {"measurement_delay": 0.0, "actuator_delay": 0.0, "dropout": 0.0, "actuator_tau": 0.0,
            "randomize": {}}
    cases = {
        "state": Scenario(duration=2.0, x0_std=(0.05, 0.05, 0.05, 0.05), **zero),
        "force": Scenario(duration=2.0, noise=NoiseModel(process="force",
                                                         process_density=(0.02, 0.002)),
                          x0_std=(0.05, 0.05, 0.0, 0.0), **zero),
    }
    runs = {}
    for cname, sc in cases.items():
        for pol in ("dlqr+kalman", "dlqr+luenberger", "dlqr+kalman-predictor", "dlqr+kalman-tv",
                    "lqr+kalman-bucy", "dlqr+none"):
            p = build_policy(pol, plant=plant, scenario=sc)
            rows = run_episodes(plant, sc, p, seed=5, episodes=range(6)).rows
            runs[f"{cname}/{pol}"] = [{k: (float(v).hex() if isinstance(v, float) else v)
                                       for k, v in r.items()} for r in rows]
    envs = gym.make_vec(ID, num_envs=4, duration=0.5, x0_std=(0.3, 0.2, 0.3, 0.3), **zero)
    agent = LQGAgent(envs, observer="kalman")
    obs, _ = envs.reset(seed=7)
    agent.reset()
    trace = []
    for _ in range(120):
        a = agent.act(obs)
        obs, r, term, trunc, _ = envs.step(a)
        agent.reset(np.nonzero(term | trunc)[0])
        trace.append([float(v).hex() for v in np.concatenate([obs.ravel(), r, a.ravel()])])
    return {"runs": runs, "vector_env": trace}


def test_zero_delay_dropout_lag_reproduce_the_stored_pre_feature_numbers(plant):
    """Stored on another machine: the floats to the stored tolerance, the outcomes exactly."""
    stored = json.loads(BASELINE.read_text())
    now = _baseline_runs(plant)
    assert_close_to_stored(now["runs"], stored["runs"], "runs")       # every metric of every episode
    assert_close_to_stored(now["vector_env"], stored["vector_env"], "vector_env")  # obs, rewards, actions
    failed = [r for rows in stored["runs"].values() for r in rows if not r["success"]]
    assert failed, "the stored runs include failures, whose reason and time must match exactly"


def test_zero_features_are_bit_identical_to_the_plain_loop_in_one_run(plant):
    """Within one run, bit for bit: the new fields given as 0 and the plain scenario."""
    zero = {"measurement_delay": 0.0, "actuator_delay": 0.0, "dropout": 0.0, "actuator_tau": 0.0,
            "randomize": {}}
    plain = Scenario(duration=1.0, x0_std=(0.05, 0.05, 0.05, 0.05))
    explicit = Scenario(duration=1.0, x0_std=(0.05, 0.05, 0.05, 0.05), **zero)
    rows = [run_episodes(plant, sc, build_policy("dlqr+kalman", plant=plant, scenario=sc), seed=5,
                         episodes=range(6)).rows for sc in (plain, explicit)]
    assert repr(rows[0]) == repr(rows[1])        # repr: nan equals nan, floats to the last bit


def test_kalman_delay_without_delays_is_the_kalman_filter(plant):
    a = design_policy(plant, 0.01, NoiseModel.lecture(), DesignSpec(observer="kalman"))
    b = design_policy(plant, 0.01, NoiseModel.lecture(), DesignSpec(observer="kalman-delay"))
    np.testing.assert_allclose(b.estimator.gain, a.estimator.gain, rtol=1e-9, atol=1e-12)
    sc = Scenario(duration=3.0)
    ra = run_episodes(plant, sc, a, seed=1, episodes=range(8)).rows
    rb = run_episodes(plant, sc, b, seed=1, episodes=range(8)).rows
    np.testing.assert_allclose([r["cost"] for r in rb], [r["cost"] for r in ra], rtol=1e-8)


# ---- delay lines ------------------------------------------------------------------------------------
class _Replay:
    """A policy that plays a fixed force sequence whatever it measures (open loop)."""

    def __init__(self, forces: np.ndarray) -> None:
        self.forces = forces

    def reset(self, n: int) -> None:
        self.i, self.rows = 0, n

    def act(self, y: np.ndarray) -> np.ndarray:
        u = np.full(y.shape[0], self.forces[self.i])
        self.i += 1
        return u


@pytest.mark.parametrize("backend", ["rollout", "step"])
def test_a_measurement_delay_of_d_periods_shifts_the_measurements_by_d_samples(plant, backend):
    d, n = 3, 40
    forces = np.sin(np.arange(n) / 4.0)
    trajs = {}
    for delay in (0.0, d * 0.01):
        sc = Scenario(duration=n * 0.01, measurement_delay=delay, x0_std=(0.01,) * 4)
        trajs[delay] = run_episodes(plant, sc, _Replay(forces), seed=4, episodes=[0, 1],
                                    backend=backend, trajectory=True).trajectories
    for t0, td in zip(trajs[0.0], trajs[d * 0.01], strict=True):
        np.testing.assert_array_equal(td.x, t0.x)                  # open loop: same motion
        assert np.isnan(td.y[:d]).all()                            # nothing has arrived yet
        np.testing.assert_array_equal(td.y[d:], t0.y[:-d])         # the noisy samples, d later
    # closed loop, noise-free: the sample received at n is the state's output at n − d
    sc = Scenario(duration=1.0, measurement_delay=d * 0.01, noise=NoiseModel.lecture(scale=0.0))
    pol = build_policy("dlqr+kalman-delay", plant=plant, scenario=sc)
    tr = run_episodes(plant, sc, pol, seed=0, episodes=[0], backend=backend,
                      trajectory=True).trajectories[0]
    np.testing.assert_array_equal(tr.y[d:], tr.x[:-d, :2])
    assert tr.row["success"]


def test_an_actuator_delay_of_d_periods_applies_each_force_d_periods_later(plant):
    d, n = 4, 50
    forces = 3.0 * np.cos(np.arange(n) / 5.0)
    late = np.concatenate([np.zeros(d), forces])[:n]
    sc0 = Scenario(duration=n * 0.01, x0_std=(0.01,) * 4)
    scd = sc0.replace(actuator_delay=d * 0.01)
    a = run_episodes(plant, sc0, _Replay(late), seed=2, episodes=[0, 3], trajectory=True)
    b = run_episodes(plant, scd, _Replay(forces), seed=2, episodes=[0, 3], trajectory=True)
    for ta, tb in zip(a.trajectories, b.trajectories, strict=True):
        np.testing.assert_array_equal(tb.states, ta.states)
        np.testing.assert_array_equal(tb.y, ta.y)
    assert [r["cost"] for r in b.rows] == [r["cost"] for r in a.rows]


def test_delays_must_be_whole_control_periods():
    with pytest.raises(ConfigError, match=r"^measurement_delay: expected a whole number of "
                                          r"control periods \(T = 0.01 s\), got 0.015 s$"):
        Scenario(measurement_delay=0.015)
    with pytest.raises(ConfigError, match=r"^actuator_delay: expected a finite number ≥ 0"):
        Scenario(actuator_delay=-0.01)
    with pytest.raises(ConfigError, match=r"^dropout: expected a probability in \[0, 1\)"):
        Scenario(dropout=1.0)
    with pytest.raises(ConfigError, match=r"^randomize: unknown key 'pole_mas_scale'"):
        Scenario(randomize={"pole_mas_scale": (0.9, 1.1)})
    with pytest.raises(ConfigError, match=r"^randomize.cart_mass_scale: expected \[lo, hi\]"):
        Scenario(randomize={"cart_mass_scale": (1.2, 0.9)})
    assert Scenario(control_period=0.02, actuator_delay=0.06).actuator_delay_periods == 3


def test_cli_and_toml_take_the_fields_and_reject_bad_values(capsys):
    assert main(["run", "--episodes", "2", "--duration", "0.2", "--measurement-delay",
                 "0.015"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["error: measurement_delay: expected a whole number of control periods "
                   "(T = 0.01 s), got 0.015 s"]
    assert main(["run", "--episodes", "3", "--duration", "0.5", "--json", "--observer",
                 "kalman-delay", "--measurement-delay", "0.02", "--actuator-delay", "0.01",
                 "--dropout", "0.1", "--actuator-tau", "0.01", "--randomize",
                 "pole_mass_scale=0.9:1.1"]) == 0
    cfg = json.loads(capsys.readouterr().out)["config"]["scenario"]
    assert (cfg["measurement_delay"], cfg["actuator_delay"], cfg["dropout"],
            cfg["actuator_tau"], cfg["randomize"]) == (0.02, 0.01, 0.1, 0.01,
                                                       {"pole_mass_scale": [0.9, 1.1]})
    spec = parse_spec({"scenario": {"dropout": 0.2, "randomize": {"cart_mass_scale": [0.9, 1.1]}},
                       "grid": {"delay_kind": ["measurement", "actuator"], "delay": [0.0, 0.03]}})
    scs = [c.build()[0] for c in spec.configurations]
    assert [(s.measurement_delay_periods, s.actuator_delay_periods) for s in scs] == \
        [(0, 0), (3, 0), (0, 0), (0, 3)]
    assert all(s.dropout == 0.2 and s.randomize.cart_mass_scale == (0.9, 1.1) for s in scs)
    with pytest.raises(ConfigError, match=r"^grid.delay: give delay and delay_kind together"):
        parse_spec({"grid": {"delay": [0.0, 0.01]}})


# ---- kalman-delay: the Riccati solution of the augmented system --------------------------------------
def _delayed_linear_outputs(Phi, Gamma, C, u, x0, dm, da):
    """y_n = C x_{n−dm} (nan before) of x_{n+1} = Φ x_n + Γ u_{n−da} (0 before), by hand."""
    x, ys, xs = x0.copy(), [], []
    for n in range(len(u)):
        xs.append(x.copy())
        ys.append(C @ xs[n - dm] if n >= dm else np.full(C.shape[0], np.nan))
        x = Phi @ x + Gamma[:, 0] * (u[n - da] if n >= da else 0.0)
    return np.array(xs), np.array(ys)


@pytest.mark.parametrize(("dm", "da"), [(0, 0), (3, 0), (0, 2), (2, 3)])
def test_kalman_delay_is_the_riccati_solution_of_the_augmented_system(plant, dm, da):
    dt, noise = 0.01, NoiseModel.lecture()
    lin = linearize(plant)
    disc = discretize_zoh(lin, dt)
    Phi, Gamma, C = disc.Phi, disc.Gamma, lin.C
    aug = design.augment_delays(Phi, Gamma, C, measurement_delay=dm, actuator_delay=da)
    # the augmented model reproduces the delayed system simulated by hand
    rng = np.random.default_rng(0)
    u = rng.standard_normal(30)
    x0 = rng.standard_normal(4)
    xs, ys = _delayed_linear_outputs(Phi, Gamma, C, u, x0, dm, da)
    z = np.zeros(aug.Phi.shape[0])
    z[:4] = x0
    for n in range(30):
        np.testing.assert_allclose(z[:4], xs[n], atol=1e-9)
        if n >= dm:
            np.testing.assert_allclose(aug.C @ z, ys[n], atol=1e-9)
        if n + da < 30:       # the prediction over the actuator delay is the state d_a later
            np.testing.assert_allclose(aug.predict @ z, xs[n + da], atol=1e-9)
        z = aug.Phi @ z + aug.Gamma[:, 0] * u[n]
    # the policy's gain is the steady-state Kalman gain of (Φa, Ca) with noise on x only
    pol = design_policy(plant, dt, noise, DesignSpec(observer="kalman-delay"), delays=(dm, da))
    Qd = per_sample_process_covariance(lin, noise, dt)
    na = 4 + 2 * dm + da
    Qa = np.zeros((na, na))
    Qa[:4, :4] = Qd
    M = solve_discrete_are(aug.Phi.T, aug.C.T, Qa, noise.V)
    L = M @ aug.C.T @ np.linalg.inv(aug.C @ M @ aug.C.T + noise.V)
    est = pol.estimator
    assert isinstance(est, DelayKalman)
    np.testing.assert_allclose(est.gain, L, rtol=1e-7, atol=1e-12)
    np.testing.assert_allclose(est.M_augmented, M, rtol=1e-7, atol=1e-14)
    np.testing.assert_array_equal(est.predict, aug.predict)
    assert np.all(np.abs(np.linalg.eigvals(aug.Phi - aug.Phi @ L @ aug.C)) < 1)


def test_kalman_delay_tolerates_more_delay_than_kalman(plant):
    """At 80 ms of measurement delay the plain filter loses every episode, the augmented one
    keeps most (the full sweep: ``pendulum-lqg bench delay``)."""
    sc = Scenario(duration=5.0, measurement_delay=0.08)
    rate = {}
    for name in ("dlqr+kalman", "dlqr+kalman-delay"):
        rows = run_episodes(plant, sc, build_policy(name, plant=plant, scenario=sc), seed=0,
                            episodes=range(40)).rows
        rate[name] = np.mean([r["success"] for r in rows])
    assert rate["dlqr+kalman"] <= 0.2 and rate["dlqr+kalman-delay"] >= 0.8


# ---- dropouts --------------------------------------------------------------------------------------
def test_lost_samples_make_every_estimator_predict_only():
    Phi = np.array([[1.0, 0.1], [0.0, 1.0]])
    Gamma = np.array([[0.005], [0.1]])
    C = np.eye(2)
    L = np.array([[0.5, 0.0], [0.1, 0.4]])
    y = np.array([[1.0, 2.0], [np.nan, np.nan], [3.0, np.nan]])
    u = np.array([[1.0], [2.0], [3.0]])
    x0 = np.array([[0.1, 0.2], [0.3, 0.4], [0.5, 0.6]])
    cur = CurrentEstimator(Phi, Gamma, C, L)
    cur.reset(x0)
    xh = cur.estimate(y)
    np.testing.assert_array_equal(xh[1:], x0[1:])                      # prediction only
    np.testing.assert_array_equal(xh[0], x0[0] + L @ (y[0] - x0[0]))  # a normal update
    assert np.isnan(cur.innovation[1:]).any(axis=1).all()
    cur.update(u)
    np.testing.assert_array_equal(cur._prior[1], Phi @ x0[1] + Gamma @ u[1])
    Lp = Phi @ L
    pred = PredictorEstimator(Phi - Lp @ C, Gamma, Lp, C)
    pred.reset(x0)
    pred.estimate(y)
    pred.update(u)
    np.testing.assert_allclose(pred._prior[1:], x0[1:] @ Phi.T + u[1:] @ Gamma.T, rtol=1e-15)
    np.testing.assert_allclose(pred._prior[0], (Phi - Lp @ C) @ x0[0] + Gamma @ u[0] + Lp @ y[0])
    tv = TimeVaryingKalman(Phi, Gamma, C, 0.01 * np.eye(2), 0.1 * np.eye(2), np.eye(2))
    tv.reset(x0)
    np.testing.assert_array_equal(tv.estimate(y)[1:], x0[1:])
    dk = DelayKalman(Phi, Gamma, C, L, np.eye(2), P=np.eye(2), M=np.eye(2))
    dk.reset(x0)
    np.testing.assert_array_equal(dk.estimate(y)[1:], x0[1:])


def test_dropouts_lose_samples_at_the_given_rate_without_touching_the_noise(plant):
    n = 300
    forces = np.zeros(n)
    sc = Scenario(duration=n * 0.01, x0=(0.0, 0.0, 0.0, 0.0))
    a = run_episodes(plant, sc, _Replay(forces), seed=8, episodes=range(4), trajectory=True)
    b = run_episodes(plant, sc.replace(dropout=0.25), _Replay(forces), seed=8, episodes=range(4),
                     trajectory=True)
    lost = samples = 0
    for e, (ta, tb) in enumerate(zip(a.trajectories, b.trajectories, strict=True)):
        gone = np.isnan(tb.y).all(axis=1)
        assert (np.isnan(tb.y).any(axis=1) == gone).all()           # whole samples are lost
        np.testing.assert_array_equal(tb.y[~gone], ta.y[~gone])     # the same noise otherwise
        np.testing.assert_array_equal(tb.x, ta.x)
        # the losses are the child stream's uniforms below 0.25
        r = child_generator(np.random.default_rng(episode_seed(8, e))).random(len(tb.y))
        np.testing.assert_array_equal(gone, r < 0.25)
        lost, samples = lost + int(gone.sum()), samples + len(gone)
    assert samples > 400 and 0.2 < lost / samples < 0.3


# ---- actuator lag ----------------------------------------------------------------------------------
def test_actuator_lag_is_the_first_order_response_to_a_step(plant):
    tau = 0.023
    sc = Scenario(duration=1.0, actuator_tau=tau, noise=NoiseModel.lecture(scale=0.0),
                  x0=(0.0, 0.0, 0.0, 0.0))
    got = {}
    for backend in ("rollout", "step"):
        with Simulator(plant, sc, backend=backend, nthread=1) as sim:
            sim.reset([np.random.default_rng(0)])
            forces, states = [], []
            for _ in range(3):
                sim.measure()
                res = sim.step(np.array([4.0]))
                forces.append(res.forces[0].copy())
                states.append(res.states[0].copy())
        got[backend] = np.concatenate(forces), np.concatenate(states)
    f = got["rollout"][0]
    t_end = plant.timestep * np.arange(1, f.size + 1)   # the value at the end of each step
    np.testing.assert_allclose(f, 4.0 * (1.0 - np.exp(-t_end / tau)), rtol=1e-13, atol=1e-13)
    np.testing.assert_array_equal(got["step"][0], f)
    np.testing.assert_array_equal(got["step"][1], got["rollout"][1])   # bit for bit


# ---- every feature on: the batch, the single-episode path and the env agree ---------------------------
def _exact(rows: list[dict[str, object]]) -> list[dict[str, str]]:
    """Rows compared bit for bit (``repr`` of every value: nan equals nan)."""
    return [{k: repr(v) for k, v in r.items()} for r in rows]


def test_all_features_give_the_same_episodes_on_both_backends(plant):
    sc = Scenario(duration=1.5, x0_std=(0.05,) * 4, measurement_delay=0.02, actuator_delay=0.01,
                  dropout=0.1, actuator_tau=0.015, randomize=RANDOMIZE)
    pol = build_policy("dlqr+kalman-delay", plant=plant, scenario=sc)
    a = run_episodes(plant, sc, pol, seed=3, episodes=[0, 1, 2, 3, 4], backend="rollout").rows
    b = run_episodes(plant, sc, pol, seed=3, episodes=[4, 2], backend="step").rows
    assert _exact(b) == _exact([a[4], a[2]])


def test_randomised_parameters_are_the_same_in_batch_single_and_env_paths(plant):
    sc = Scenario(duration=1.0, randomize=RANDOMIZE)
    seeds = [episode_seed(6, e) for e in range(3)]
    with Simulator(plant, sc, backend="step") as sim:
        sim.reset([np.random.default_rng(s) for s in seeds])
        models = sim.sensing.row_models
    env = gym.make(ID, duration=1.0, randomize=RANDOMIZE)
    for s, m in zip(seeds, models, strict=True):
        r = child_generator(np.random.default_rng(s)).random(3)
        scale = {k: lo + (hi - lo) * ri for (k, (lo, hi)), ri in zip(RANDOMIZE.items(), r,
                                                                       strict=True)}
        want = load_plant(overrides=ModelOverrides(**scale))
        assert m.body("pole").mass[0] == want.pole_mass == pytest.approx(
            plant.pole_mass * scale["pole_mass_scale"], rel=1e-12)
        assert m.body("cart").mass[0] == want.cart_mass
        assert m.geom("pole").size[1] == pytest.approx(plant.pole_length / 2
                                                       * scale["pole_length_scale"], rel=1e-12)
        env.reset(seed=s)
        env_model = env.unwrapped._sim.sensing.row_models[0]
        for name in ("body_mass", "body_inertia", "geom_size", "body_ipos"):
            np.testing.assert_array_equal(getattr(env_model, name), getattr(m, name))
    # episodes: batch (rollout) = single-episode (step) = the env with the agent
    pol = build_policy("dlqr+kalman", plant=plant, scenario=sc)
    a = run_episodes(plant, sc, pol, seed=6, episodes=range(3)).rows
    b = [run_episodes(plant, sc, pol, seed=6, episodes=[e], backend="step").rows[0]
         for e in range(3)]
    assert _exact(a) == _exact(b)
    agent = LQGAgent(env, observer="kalman")
    for s, row in zip(seeds, a, strict=True):
        obs, _ = env.reset(seed=s)
        agent.reset()
        term = trunc = False
        while not (term or trunc):
            obs, _, term, trunc, info = env.step(agent.act(obs))
        assert (not term, info["running_cost"]) == (row["success"], row["cost"])
    # the noise stream is untouched: the first measurement is the one without randomisation
    y0 = {}
    for rnd in ({}, RANDOMIZE):
        with Simulator(plant, sc.replace(randomize=rnd)) as sim:
            sim.reset([np.random.default_rng(s) for s in seeds])
            y0[bool(rnd)] = sim.measure()
    np.testing.assert_array_equal(y0[True], y0[False])


@pytest.mark.parametrize("mode", [gym.vector.AutoresetMode.SAME_STEP,
                                  gym.vector.AutoresetMode.NEXT_STEP])
def test_vector_env_rows_restart_their_delay_lines_like_single_envs(mode):
    """Sub-envs end at different steps; each restarts its own delay lines, lag, dropout stream
    and randomised model exactly as a single env's reset does (in both autoreset modes)."""
    n = 4
    cfg = {"duration": 0.3, "x0_std": (0.5, 0.3, 0.5, 0.5), "measurement_delay": 0.03,
           "actuator_delay": 0.02, "dropout": 0.2, "actuator_tau": 0.01,
           "randomize": RANDOMIZE}
    native = gym.make_vec(ID, num_envs=n, autoreset_mode=mode, **cfg)
    sync = gym.make_vec(ID, num_envs=n, vectorization_mode="sync",
                        vector_kwargs={"autoreset_mode": mode}, **cfg)
    runs = []
    for envs in (native, sync):
        agent = LQGAgent(native, observer="kalman-delay")
        obs, _ = envs.reset(seed=3)
        agent.reset()
        actions, observations, ends = [], [], 0
        for _ in range(70):
            a = agent.act(obs)
            actions.append(a.copy())
            obs, _, term, trunc, _ = envs.step(a)
            observations.append(obs.copy())
            ends += int((term | trunc).sum())
            agent.reset(np.nonzero(term | trunc)[0])
        runs.append((np.array(actions), np.array(observations), ends))
    np.testing.assert_array_equal(runs[0][0], runs[1][0])
    np.testing.assert_array_equal(runs[0][1], runs[1][1])            # nan where nan
    assert runs[0][2] == runs[1][2] >= 2 * n
    assert np.isnan(runs[0][1]).any()
