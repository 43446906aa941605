"""A linear plant given as matrices (pendulum_lqg.model.lti) through the one loop: against the theory's
stationary covariances, against the cart-pole's own linear plant re-stated as matrices, and its
metrics, limits and failure rule."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest
from conftest import stationary_monte_carlo

from pendulum_lqg.core.loop import Simulator
from pendulum_lqg.core.metrics import summarize, summary_metrics
from pendulum_lqg.core.physics.linear import LinearPhysics
from pendulum_lqg.core.runner import run_episodes
from pendulum_lqg.core.scenario import Scenario
from pendulum_lqg.core.seeding import episode_generators, episode_seeds
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.model.lti import load_lti, lti_from_mapping
from pendulum_lqg.model.plant import STATE_NAMES, load_plant
from pendulum_lqg.policies.loading import build_policy
from pendulum_lqg.policies.lti import design_lti_policy, lti_theory

EXPERIMENTS = Path(__file__).resolve().parents[2] / "experiments" / "lti"
INF = math.inf


@pytest.fixture(scope="module")
def double_integrator():
    return load_lti(EXPERIMENTS / "double_integrator.toml")


def _scenario(plant, duration: float, **kw) -> Scenario:
    return Scenario(control_period=plant.control_period, duration=duration, plant="linear-zoh",
                    **kw)


@pytest.mark.parametrize("name", ["dlqr+kalman", "dlqr+luenberger"])
def test_double_integrator_monte_carlo_agrees_with_theory(double_integrator, name):
    """400 episodes × 40 s after a 10 s burn-in (7 time constants of the slowest pole, |z| =
    0.9929 at T = 0.01 s): every stationary variance of x, u and x̂ − x that ``theory`` gives lies
    inside the Monte Carlo's interval ±2.63·SE (the five together at 95 %, Bonferroni)."""
    plant = double_integrator
    scenario = _scenario(plant, 50.0, estimate0="true")
    policy = design_lti_policy(plant, name)
    mean, se = stationary_monte_carlo(plant, scenario, policy, episodes=400, burn_in=10.0,
                                       seed=5)
    th = lti_theory(plant, (name,))[name]
    expected = np.array([*(th.std[s] ** 2 for s in plant.state_names), th.u_std ** 2,
                         *(th.estimate_error_std[s] ** 2 for s in plant.state_names)])
    z = np.abs(mean - expected) / se
    assert np.all(z < 2.63), f"theory {expected} against Monte Carlo {mean} ± {se}: z = {z}"
    assert np.all(se < 0.02 * expected)      # the intervals are tight: the check can fail


def _cartpole_as_matrices(plant, scenario):
    """The cart-pole's linear-zoh plant at T = h (k = 1) re-stated as an LTI table: its (Φ, Γ),
    C = [I₂ 0], the state jump's covariance W·T per period, V, Q, R, x0 and the force limit."""
    phys = LinearPhysics(plant, "linear-zoh", 1)
    noise = scenario.noise
    return lti_from_mapping({
        "control_period": scenario.control_period, "Phi": phys.Phi.tolist(),
        "Gamma": phys.Gamma[:, None].tolist(), "C": [[1, 0, 0, 0], [0, 1, 0, 0]],
        "Wd": (np.asarray(noise.process_density) * scenario.control_period).tolist(),
        "V": list(noise.measurement_variance), "Q": list(scenario.cost_Q), "R": scenario.cost_R,
        "x0": list(scenario.x0), "x0_std": list(scenario.x0_std), "states": list(STATE_NAMES),
        "force_limit": 2.0})


def test_lti_restatement_of_the_cartpole_gives_its_episodes():
    """The same episodes, bit for bit: states, forces (saturated at 2 N), cost, every metric the
    two have in common, on the same seeds, through the same loop."""
    cart = load_plant()
    scenario = Scenario(control_period=cart.timestep, duration=1.0, plant="linear-zoh",
                        theta_max=INF, track_limit=INF, force_limit=2.0, x0_std=(0.1, 0.05, 0, 0),
                        estimate0="true")
    lti = _cartpole_as_matrices(cart, scenario)
    policy = build_policy("dlqr+kalman", plant=cart, scenario=scenario)
    a = run_episodes(cart, scenario, policy, seed=7, episodes=range(6), trajectory=True)
    b = run_episodes(lti, scenario, policy, seed=7, episodes=range(6), trajectory=True)
    common = [k for k in a.rows[0] if k in b.rows[0] and k != "settling_time"]
    assert len(common) == 18                                  # all but the settling time
    # to the last bit (json spells nan and keeps every digit of a float)
    assert json.dumps([[r[k] for k in common] for r in a.rows]) == \
        json.dumps([[r[k] for k in common] for r in b.rows])
    assert max(r["saturated_fraction"] for r in a.rows) > 0   # the force limit acts
    for ta, tb in zip(a.trajectories, b.trajectories, strict=True):
        for field in ("x", "y", "u", "x_hat", "cost"):
            np.testing.assert_array_equal(getattr(ta, field), getattr(tb, field))


def test_lti_metrics_are_named_after_the_file(double_integrator):
    plant = double_integrator
    rows = run_episodes(plant, _scenario(plant, 2.0), design_lti_policy(plant, "dlqr+kalman"),
                        seed=1, episodes=range(3)).rows
    assert list(rows[0])[7:] == ["rms_position", "max_abs_position", "rms_velocity",
                                 "max_abs_velocity", "rms_u", "max_abs_u", "saturated_fraction",
                                 "rms_est_err_position", "rms_est_err_velocity"]
    s = summarize(rows, summary_metrics(tuple(rows[0])))
    assert s["successes"] == 3 and s["rms_position"]["mean"] > 0
    # unnamed states: x1, x2 (as the theory names them); outputs y1
    bare = lti_from_mapping({"control_period": 0.1, "A": [[0, 1], [0, 0]], "B": [[0], [1]],
                             "C": [[1, 0]]})
    lay = bare.layout(Scenario(control_period=0.1, plant="linear-zoh"))
    assert lay.states == ("x1", "x2") and lay.outputs == ("y1",)


def test_lti_limits_off_unless_declared_and_force_limit_from_the_file():
    """No declared limit: an open-loop unstable plant (ẋ = x) runs until it diverges (|x| > 10⁶,
    at t = ln 10⁶ ≈ 13.8 s from x0 = 1). A declared limit |x| ≤ 2 ends it at ln 2 as
    ``state_limit``. The file's force limit saturates u."""
    table = {"control_period": 0.01, "A": [[1.0]], "B": [[1.0]], "C": [[1.0]], "x0": [1.0],
             "R": 1.0}
    free = lti_from_mapping(table)
    sc = Scenario(control_period=0.01, duration=20.0, plant="linear-zoh", noise=_quiet())
    lay = free.layout(sc)
    assert lay.state_limits.tolist() == [INF] and lay.covariances[0].shape == (1, 1)
    zero = _ZeroForce()
    row = run_episodes(free, sc, zero, seed=0, episodes=[0]).rows[0]
    assert row["failure_reason"] == "diverged"
    assert row["time_to_failure"] == pytest.approx(math.log(1e6), abs=0.011)
    bounded = lti_from_mapping({**table, "state_limits": [2.0]})
    row = run_episodes(bounded, sc, zero, seed=0, episodes=[0]).rows[0]
    assert row["failure_reason"] == "state_limit"
    assert row["time_to_failure"] == pytest.approx(math.log(2.0), abs=0.011)
    assert row["max_abs_x1"] > 2.0                            # the sample that crossed
    saturated = lti_from_mapping({**table, "force_limit": 0.5, "A": [[-1.0]]})
    row = run_episodes(saturated, sc, _ZeroForce(100.0), seed=0, episodes=[0]).rows[0]
    assert row["max_abs_u"] == 0.5 and row["saturated_fraction"] == 1.0
    # the scenario's own force limit, when it sets one, is the limit in force
    row = run_episodes(saturated, sc.replace(force_limit=0.25), _ZeroForce(100.0), seed=0,
                       episodes=[0]).rows[0]
    assert row["max_abs_u"] == 0.25


def test_lti_full_noise_covariance_has_its_covariance(double_integrator):
    """The double integrator's state jump has a full covariance (Van Loan, off-diagonal T²/2):
    the drawn jumps' sample covariance matches it (20 000 draws, 4 % ≈ 4 standard errors)."""
    plant = double_integrator
    sc = _scenario(plant, 10.0)
    with Simulator(plant, sc, streamed_metrics=False) as sim:
        sim.reset(episode_generators(episode_seeds(0, range(20_000))))
        w, v = sim.noise.draw()
    Wd = plant.process_covariance()
    np.testing.assert_allclose(np.cov(w.T), Wd, rtol=0.04, atol=0.04 * Wd[0, 0])
    assert np.var(v) == pytest.approx(plant.V[0, 0], rel=0.04)


def test_lti_plant_refuses_what_its_loop_cannot_run(double_integrator):
    plant = double_integrator
    with pytest.raises(ConfigError, match="control_period: the LTI plant"):
        Simulator(plant, Scenario(control_period=0.02, plant="linear-zoh"))
    with pytest.raises(ConfigError, match="plant: an LTI plant runs"):
        Simulator(plant, Scenario(control_period=0.01, plant="linear-euler"))
    two = load_lti(EXPERIMENTS / "two_mass.toml")
    with pytest.raises(ConfigError, match="actuator_tau: "):
        Simulator(two, Scenario(control_period=0.02, plant="linear-zoh", actuator_tau=0.05))


def test_two_input_actuator_delay_holds_each_input_back():
    """Actuator delay on a plant of two inputs: the delay line holds (n, d, m); noise-free under
    dlqr+none the command reaching the plant in period k is −K x_{k−2} (0 for the first two
    periods), both inputs, the plant follows x ← Φ x + Γ u exactly, the trajectory keeps the
    requested −K x_k and each input's RMS is the command's."""
    plant = load_lti(EXPERIMENTS / "two_mass.toml")
    sc = _scenario(plant, 1.0, noise=_quiet(), actuator_delay=0.04)
    policy = design_lti_policy(plant, "dlqr+none")
    with Simulator(plant, sc, streamed_metrics=False) as sim:
        assert sim.sensing.act_delay == 2
    res = run_episodes(plant, sc, policy, seed=1, episodes=[0], trajectory=True)
    tr, row = res.trajectories[0], res.rows[0]
    x, queue, xs, requested, applied = plant.x0, [np.zeros(2), np.zeros(2)], [], [], []
    for _ in range(50):
        xs.append(x)
        requested.append(-policy.K @ x)
        queue.append(requested[-1])
        applied.append(queue.pop(0))
        x = plant.Phi @ x + plant.Gamma @ applied[-1]
    applied = np.array(applied)
    np.testing.assert_allclose(tr.x, np.array(xs), rtol=0, atol=1e-14)
    np.testing.assert_allclose(tr.u, np.array(requested), rtol=0, atol=1e-14)
    assert np.all(applied[:2] == 0.0) and np.all(applied[2:] != 0.0)
    for j, name in enumerate(plant.input_names):
        assert row[f"rms_{name}"] == pytest.approx(np.sqrt(np.mean(applied[:, j] ** 2)),
                                                   rel=1e-12)


def test_two_input_plant_follows_its_closed_loop_and_full_cost_exactly():
    """Noise-free, unsaturated: the two-mass plant under dlqr+none is ``x ← (Φ − ΓK) x`` each
    period, u = −K x (n, 2), and the cost is ``Σ T [x; u]ᵀ [[Q, N], [Nᵀ, R]] [x; u]`` with its
    full Q and a cross term."""
    plant = load_lti(EXPERIMENTS / "two_mass.toml")
    N = np.array([[0.1, 0.0], [0.0, -0.1], [0.0, 0.0], [0.0, 0.0]])
    plant = dataclasses.replace(plant, N=N, x0=np.array([0.05, -0.02, 0.0, 0.01]))
    sc = _scenario(plant, 2.0, noise=_quiet())
    policy = design_lti_policy(plant, "dlqr+none")
    res = run_episodes(plant, sc, policy, seed=1, episodes=[0], trajectory=True)
    tr, row = res.trajectories[0], res.rows[0]
    x = plant.x0
    xs, us = [], []
    for _ in range(100):
        xs.append(x)
        us.append(-policy.K @ x)
        x = (plant.Phi - plant.Gamma @ policy.K) @ x
    xs, us = np.array(xs), np.array(us)
    np.testing.assert_allclose(tr.x, xs, rtol=0, atol=1e-14)
    np.testing.assert_allclose(tr.u, us, rtol=0, atol=1e-14)
    weight = np.block([[plant.Q, N], [N.T, plant.R]])
    z = np.hstack([xs, us])
    cost = plant.control_period * np.einsum("ni,ij,nj->", z, weight, z)
    assert row["cost"] == pytest.approx(cost, rel=1e-12)
    assert row["rms_f1"] == pytest.approx(np.sqrt(np.mean(us[:, 0] ** 2)), rel=1e-12)
    assert row["max_abs_f2"] == pytest.approx(np.max(np.abs(us[:, 1])), rel=1e-12)
    assert row["saturated_fraction"] == 0.0


def test_two_input_limits_saturate_each_input_on_its_own():
    """Per-input limits: f₁ ≤ 0.01 saturates from the start, f₂ ≤ 100 never does; the policy and
    the core clip each input to its own limit."""
    plant = load_lti(EXPERIMENTS / "two_mass.toml")
    plant = dataclasses.replace(plant, input_limits=np.array([0.01, 100.0]))
    res = run_episodes(plant, _scenario(plant, 1.0, noise=_quiet()),
                       design_lti_policy(plant, "dlqr+none"), seed=1, episodes=[0],
                       trajectory=True)
    tr, row = res.trajectories[0], res.rows[0]
    assert np.max(np.abs(tr.u[:, 0])) == pytest.approx(0.01)
    assert np.max(np.abs(tr.u[:, 1])) > 0.5
    assert row["max_abs_f1"] == pytest.approx(0.01) and row["saturated_fraction"] > 0


def _quiet():
    from pendulum_lqg.core.noise import NoiseModel

    return NoiseModel(scale=0.0)


class _ZeroForce:
    """A policy requesting a constant force (0 N by default)."""

    def __init__(self, force: float = 0.0) -> None:
        self.force = force

    def reset(self, n: int, **kw) -> None:
        self.n = n

    def act(self, y):
        return np.full(y.shape[0], self.force)


def test_lti_trajectories_have_the_plants_shapes(double_integrator):
    """Kept trajectories of a 2-state, 1-output plant: x (N, 2), y (N, 1), y_true = C x, the
    Kalman filter's covariance (N, 2, 2); the measurement is y_true plus noise of std √V = 10."""
    plant = double_integrator
    tr = run_episodes(plant, _scenario(plant, 5.0), design_lti_policy(plant, "dlqr+kalman"),
                      seed=4, episodes=[0], trajectory=True).trajectories[0]
    assert tr.x.shape == (500, 2) and tr.y.shape == (500, 1) and tr.P.shape == (500, 2, 2)
    np.testing.assert_array_equal(tr.y_true, tr.x @ plant.C.T)
    assert np.std(tr.y - tr.y_true) == pytest.approx(10.0, rel=0.1)
    assert tr.states.shape == (500, 2)


def test_lti_plant_takes_the_scenarios_sensing(double_integrator):
    """The delay line holds p = 1 output: with a 3-period measurement delay the policy's first
    three samples are nan (nothing has arrived), as on the cart-pole."""
    plant = double_integrator
    sc = _scenario(plant, 1.0, measurement_delay=0.03)
    with Simulator(plant, sc, streamed_metrics=False) as sim:
        sim.reset(episode_generators(episode_seeds(0, range(2))))
        ys = []
        for _ in range(4):
            ys.append(sim.measure())
            sim.step(np.zeros(2))
    assert all(y.shape == (2, 1) for y in ys)
    assert np.isnan(ys[0]).all() and np.isnan(ys[2]).all() and np.isfinite(ys[3]).all()
