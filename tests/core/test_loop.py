"""The noisy closed loop on the MuJoCo model: stabilisation, optimal cost, equivalent code paths."""

from __future__ import annotations

import dataclasses
import json

import mujoco
import numpy as np
import pytest

from pendulum_lqg.core import rules
from pendulum_lqg.core.loop import Simulator
from pendulum_lqg.core.metrics import summarize, wilson_interval
from pendulum_lqg.core.noise import NoiseModel, NoiseStream
from pendulum_lqg.core.runner import MIN_SHARD_ROWS, run_episodes, shard_count
from pendulum_lqg.core.scenario import Scenario
from pendulum_lqg.core.seeding import episode_seed
from pendulum_lqg.errors import ConfigError, PendulumLQGError
from pendulum_lqg.names import OBSERVERS
from pendulum_lqg.policies.lqg import DesignSpec, design_policy

LECTURE = Scenario()


def _run(plant, scenario, controller, observer, episodes, seed=0, **kw):
    policy = design_policy(plant, scenario.control_period, scenario.noise,
                           DesignSpec(controller=controller, observer=observer))
    return run_episodes(plant, scenario, policy, seed=seed, episodes=range(episodes), **kw)


# ---- stabilisation -------------------------------------------------------------------------------
@pytest.mark.parametrize("episodes", [
    pytest.param(24, id="24"),                                    # the quick loop's sample
    pytest.param(200, id="200", marks=pytest.mark.slow)])         # the statistic
@pytest.mark.parametrize(("controller", "observer"), [
    ("lqr", "none"), ("dlqr", "none"), ("dlqr", "kalman"), ("dlqr", "kalman-predictor"),
    ("dlqr", "kalman-tv"), ("lqr", "kalman-bucy"), ("lqr", "kalman")])
def test_lqg_stabilises_the_lecture_scenario(plant, controller, observer, episodes):
    """≥ 99 % of 200 noisy lecture episodes balance (every one of the first 24, in the quick loop)."""
    rows = _run(plant, LECTURE, controller, observer, episodes).rows
    s = summarize(rows)
    assert s["success_rate"] >= 0.99, s["failures"]
    assert s["max_abs_theta"]["mean"] < 0.3


@pytest.mark.parametrize("controller", ["lqr", "dlqr"])
@pytest.mark.parametrize("observer", OBSERVERS)
def test_every_policy_stabilises_the_noise_free_case(plant, controller, observer):
    sc = LECTURE.replace(noise=NoiseModel.lecture(scale=0.0), duration=15.0)
    row = _run(plant, sc, controller, observer, 1).rows[0]
    assert row["success"], row
    assert row["settling_time"] < 15.0


@pytest.mark.parametrize("episodes", [
    pytest.param(24, id="24"),                                    # the quick loop's sample
    pytest.param(100, id="100", marks=pytest.mark.slow)])         # the statistic
def test_luenberger_default_poles_fail_under_the_lecture_noise(plant, episodes):
    """The deliberately slow default observer cannot hold the pole under the lecture noise."""
    s = summarize(_run(plant, LECTURE, "dlqr", "luenberger", episodes).rows)
    assert s["success_rate"] < 0.2
    kal = summarize(_run(plant, LECTURE, "dlqr", "kalman", episodes).rows)
    assert kal["rms_est_err_theta"]["mean"] < 0.5 * s["rms_est_err_theta"]["mean"]


def test_simulated_cost_matches_the_riccati_cost(plant):
    """dm_control's lqr_test idea: J = ∫xᵀQx + uᵀRu dt from x₀ equals x₀ᵀPx₀ (our J has no ½).

    The DLQR uses the exact sampled-data weights of this J, so P is the optimal continuous cost of
    the sampled linear loop; the MuJoCo run adds only nonlinearity and the integrator's O(h)."""
    x0 = (0.05, 0.02, 0.0, 0.0)
    sc = LECTURE.replace(noise=NoiseModel.lecture(scale=0.0), duration=30.0, x0=x0,
                         estimate0="true")
    policy = design_policy(plant, sc.control_period, sc.noise, DesignSpec("dlqr", "none"))
    row = run_episodes(plant, sc, policy, seed=0, episodes=[0]).rows[0]
    x0 = np.array(x0)
    expected = x0 @ policy.info["P_lqr"] @ x0
    assert row["cost"] == pytest.approx(expected, rel=0.02)
    assert row["cost"] == pytest.approx(expected, rel=2e-3)   # in fact much closer


# ---- equivalent code paths -----------------------------------------------------------------------
def _dump(rows):
    return json.dumps(rows, sort_keys=True)


@pytest.mark.parametrize("observer", ["kalman", "luenberger", "kalman-tv", "kalman-bucy"])
def test_batched_equals_single_episode_path(plant, observer):
    """Bit-identical: rollout batch vs plain mj_step loop, any batch composition, any threads."""
    sc = LECTURE.replace(duration=4.0)
    policy = lambda: design_policy(plant, sc.control_period, sc.noise, DesignSpec("dlqr", observer))  # noqa: E731
    batch = run_episodes(plant, sc, policy(), seed=7, episodes=range(8), nthread=2).rows
    single = [run_episodes(plant, sc, policy(), seed=7, episodes=[e], backend="step").rows[0]
              for e in range(8)]
    subset = run_episodes(plant, sc, policy(), seed=7, episodes=[5, 1], nthread=1).rows
    assert _dump(batch) == _dump(single)
    assert _dump([batch[5], batch[1]]) == _dump(subset)


def test_sharded_batches_and_the_single_row_path_equal_one_batch(plant):
    """A batch split into shards (threads), one batch on one thread, and each episode alone on
    the single-row path give bit-identical rows and trajectories — failures included (the
    noise is 5× the lecture's: about a third of the episodes fail)."""
    sc = LECTURE.replace(duration=1.5, noise=dataclasses.replace(LECTURE.noise, scale=5.0))
    pol = lambda: design_policy(plant, sc.control_period, sc.noise, DesignSpec("dlqr", "kalman"))  # noqa: E731
    n = 2 * MIN_SHARD_ROWS + 3
    assert shard_count(n, 2, "rollout", pol()) == 2
    assert shard_count(n, 1, "rollout", pol()) == 1
    sharded = run_episodes(plant, sc, pol(), seed=5, episodes=range(n), nthread=2,
                           trajectory=True)
    whole = run_episodes(plant, sc, pol(), seed=5, episodes=range(n), nthread=1, trajectory=True)
    assert _dump(sharded.rows) == _dump(whole.rows)
    assert 0 < sum(r["success"] for r in whole.rows) < n          # both outcomes are exercised
    # each shard's (start, end) since the run's start, in shard order; one for one batch
    assert len(sharded.shard_seconds) == 2 and len(whole.shard_seconds) == 1
    assert all(0 <= a < b for a, b in sharded.shard_seconds + whole.shard_seconds)
    for a, b in zip(sharded.trajectories, whole.trajectories, strict=True):
        assert a.episode == b.episode
        assert np.array_equal(a.states, b.states) and np.array_equal(a.u, b.u)
    failed = [e for e, r in enumerate(whole.rows) if not r["success"]][:2]
    for e in [0, *failed]:
        alone = run_episodes(plant, sc, pol(), seed=5, episodes=[e]).rows[0]   # single-row path
        assert _dump([alone]) == _dump([whole.rows[e]])


EXTREME_STARTS = [(0, 0, 0, 1e300), (0, 0, 1e300, 0), (1e300, 0, 0, 0), (0, 0, 0, -1e300),
                  (0, 0, 0, 1e15), (0, 0, 0, 1e8), (0, 0.1, 0, 1e6), (0, 0.1, 0, 1e5),
                  (0, 0, 0, 3e5), (0, 3.0, 0, 0), (0.5, 0, 30, 0), (0, 0.4, 0, 50), (0, 0, 0, 0)]


@pytest.mark.filterwarnings("ignore::RuntimeWarning")
def test_backends_agree_on_failures_from_extreme_initial_states(plant):
    """MuJoCo resets its data after an instability (θ̇₀ = 1e300 …): ``mujoco.rollout`` stops there,
    the mj_step loop now does the same, so both call it ``diverged`` with identical rows; the
    batch, the single-row path and the step backend agree on every case."""
    sc = LECTURE.replace(duration=0.2)
    pol = lambda: design_policy(plant, sc.control_period, sc.noise, DesignSpec("dlqr", "kalman"))  # noqa: E731
    x0 = np.array(EXTREME_STARTS, dtype=float)
    n = len(x0)
    batch = run_episodes(plant, sc, pol(), seed=0, episodes=range(n), initial_states=x0).rows
    for e in range(n):
        one = x0[e:e + 1]
        step = run_episodes(plant, sc, pol(), seed=0, episodes=[e], backend="step",
                            initial_states=one).rows[0]
        single = run_episodes(plant, sc, pol(), seed=0, episodes=[e], initial_states=one).rows[0]
        assert _dump([batch[e]]) == _dump([step]) == _dump([single]), EXTREME_STARTS[e]
    reasons = [r["failure_reason"] for r in batch]
    assert reasons[:7] == ["diverged"] * 7
    assert reasons[7:10] == ["pole_fell"] * 3 and reasons[10] == "track_limit"
    assert batch[-1]["success"]


def test_rollout_chunks_are_a_multiple_of_the_threads():
    from pendulum_lqg.bench.perf import rollout_chunk

    assert rollout_chunk(64, 2, 10) == 32                 # not 30 + 30 + 4
    assert rollout_chunk(1024, 2, 10) == 52               # 20 chunks, ten per thread
    assert rollout_chunk(8, 2, 10) == 8                   # too small to split
    assert rollout_chunk(100, 1, 10) is None
    assert rollout_chunk(640, 4, 10) == 32                # 20 chunks: five per thread


@pytest.mark.parametrize("episodes", [
    pytest.param(24, id="24"),                                    # the quick loop's sample
    pytest.param(100, id="100", marks=pytest.mark.slow)])         # the statistic
def test_force_noise_paths_agree_and_kalman_stabilises(plant, episodes):
    noise = NoiseModel(process="force", process_density=(1e-3, 1e-4), measurement_variance=1e-4)
    sc = LECTURE.replace(noise=noise, duration=4.0)
    pol = lambda: design_policy(plant, sc.control_period, noise, DesignSpec("dlqr", "kalman"))  # noqa: E731
    batch = run_episodes(plant, sc, pol(), seed=1, episodes=range(3)).rows
    single = [run_episodes(plant, sc, pol(), seed=1, episodes=[e], backend="step").rows[0]
              for e in range(3)]
    single_row = [run_episodes(plant, sc, pol(), seed=1, episodes=[e]).rows[0] for e in range(3)]
    assert _dump(batch) == _dump(single) == _dump(single_row)
    s = summarize(run_episodes(plant, sc.replace(duration=10.0), pol(), seed=2,
                               episodes=range(episodes)).rows)
    assert s["success_rate"] >= 0.99


def test_same_seed_same_results_and_seeds_differ(plant):
    a = _run(plant, LECTURE.replace(duration=2.0), "dlqr", "kalman", 4, seed=3).rows
    b = _run(plant, LECTURE.replace(duration=2.0), "dlqr", "kalman", 4, seed=3).rows
    c = _run(plant, LECTURE.replace(duration=2.0), "dlqr", "kalman", 4, seed=4).rows
    assert _dump(a) == _dump(b)
    assert a[0]["cost"] != c[0]["cost"]
    assert [r["seed"] for r in a] == [episode_seed(3, e) for e in range(4)]
    assert len({r["seed"] for r in a}) == 4


# ---- noise units ---------------------------------------------------------------------------------
def test_lecture_noise_conversion():
    """x ← x + T·w, w ~ N(0, 0.04 I) at T = 0.01 s  ⇔  density W = 0.04·T·I, jump covariance W·T."""
    noise = NoiseModel.lecture()
    np.testing.assert_allclose(noise.W, 0.04 * 0.01 * np.eye(4))
    np.testing.assert_allclose(noise.V, 0.01 * np.eye(2))
    stream = NoiseStream(noise, steps_per_period=10, dt=0.01, h=0.001)
    np.testing.assert_allclose(stream.proc_std, 0.01 * np.sqrt(0.04))     # T·σ_w
    np.testing.assert_allclose(stream.meas_std, 0.1)
    stream.reset([np.random.default_rng(0)])
    jumps = np.array([stream.draw(np.arange(1))[0][0] for _ in range(20000)])
    # off-diagonal sampling s.e. is 4e-6/√20000 ≈ 3e-8: allow 5 s.e.
    np.testing.assert_allclose(np.cov(jumps.T), noise.W * 0.01, rtol=0.05, atol=1.5e-7)
    half = NoiseStream(noise.with_scale(0.5), steps_per_period=10, dt=0.01, h=0.001)
    np.testing.assert_allclose(half.meas_std, 0.05)


def test_noise_is_drawn_in_blocks_independent_of_batch_and_length():
    """An episode's noise is the same alone or in a batch, drawn with the batch's common cursor
    or per row, and its stream does not depend on N."""
    noise = NoiseModel.lecture()
    a = NoiseStream(noise, steps_per_period=10, dt=0.01, h=0.001)
    b = NoiseStream(noise, steps_per_period=10, dt=0.01, h=0.001)
    a.reset([np.random.default_rng(s) for s in (11, 12, 13)])
    b.reset([np.random.default_rng(12)])
    fresh = NoiseStream(noise, steps_per_period=10, dt=0.01, h=0.001)
    for i in range(800):                                     # crosses block boundaries
        if i == 450:                # row 0 restarts: the rows are at different positions now
            a.reset([np.random.default_rng(99)], rows=np.array([0]))
            fresh.reset([np.random.default_rng(99)])
        # the common cursor, then per row for chosen rows, then per row for every row
        za = a.draw() if i < 300 or i >= 400 else a.draw(np.arange(3))
        zb = b.draw(np.arange(1))
        np.testing.assert_array_equal(za[0][1], zb[0][0])
        np.testing.assert_array_equal(za[1][1], zb[1][0])
        if i >= 450:
            zf = fresh.draw()
            np.testing.assert_array_equal(za[0][0], zf[0][0])
            np.testing.assert_array_equal(za[1][0], zf[1][0])
    # in physical units: v = σ_v · z with the generator's own normals
    c = NoiseStream(noise, steps_per_period=10, dt=0.01, h=0.001)
    c.reset([np.random.default_rng(12)])
    z = np.random.default_rng(12).standard_normal((2, 6))
    w, v = c.draw()
    np.testing.assert_array_equal(w[0], z[0, :4] * c.proc_std)
    np.testing.assert_array_equal(v[0], z[0, 4:] * c.meas_std)


@pytest.mark.parametrize("process", ["state", "force"])
@pytest.mark.parametrize("horizon", [1, 5, 8, 9, 13, 16, 17, 200, 256, 300, 1000])
def test_noise_with_a_horizon_draws_the_same_numbers(horizon, process):
    """A batch run's stream (``horizon``: a ring topped up one group of rows per period) gives
    every period exactly the numbers of the fixed blocks, across ring wraps and dropped rows, and
    draws each episode's normals no further than the horizon."""
    noise = NoiseModel(process=process, process_density=(1e-3,) * (4 if process == "state" else 2))
    seeds = list(range(20, 37))                                      # 17 rows: uneven groups
    fixed = NoiseStream(noise, steps_per_period=3, dt=0.003, h=0.001)
    ring = NoiseStream(noise, steps_per_period=3, dt=0.003, h=0.001)
    fixed.reset([np.random.default_rng(s) for s in seeds])
    gens = [np.random.default_rng(s) for s in seeds]
    ring.reset(gens, horizon=horizon)
    rows = np.arange(len(seeds))
    for p in range(horizon):
        if p in (3, 140) and rows.size > 2:          # episodes end: both keep the same rows
            keep = np.arange(rows.size)[1::2]
            fixed.select(keep)
            ring.select(keep)
            rows = rows[keep]
        wf, vf = fixed.draw()
        wr, vr = ring.draw()
        np.testing.assert_array_equal(wr, wf)
        np.testing.assert_array_equal(vr, vf)
    with pytest.raises(PendulumLQGError, match="past the horizon"):
        ring.draw()
    # each episode drew exactly horizon periods: its generator is where a fresh one is after them
    for r in rows.tolist():
        ref = np.random.default_rng(seeds[r])
        ref.standard_normal(horizon * ring.width)
        assert gens[r].bit_generator.state == ref.bit_generator.state
    with pytest.raises(PendulumLQGError, match="per-row draws"):
        ring.draw(np.arange(1))


# ---- failures and divergence ---------------------------------------------------------------------
def test_a_diverging_row_fails_alone(plant):
    sc = LECTURE.replace(duration=1.0)
    gens = lambda: [np.random.default_rng(s) for s in (1, 2, 3)]  # noqa: E731
    with Simulator(plant, sc) as sim:
        sim.reset(gens())
        sim.measure()
        res = sim.step(np.array([0.0, np.nan, 0.0]))
        assert res.failed.tolist() == [False, True, False]
        ok_states = res.states[[0, 2]].copy()
    with Simulator(plant, sc, backend="step") as sim:
        sim.reset(gens())
        sim.measure()
        res2 = sim.step(np.array([0.0, 0.0, 0.0]))
    np.testing.assert_array_equal(ok_states, res2.states[[0, 2]])
    rows = sim.metrics.rows(np.arange(3))
    assert [r["failure_reason"] for r in rows] == ["", "", ""]


@pytest.mark.parametrize("backend", ["rollout", "step"])
def test_a_reused_row_detects_every_mujoco_reset(plant, backend):
    """A row whose simulation MuJoCo reset after an instability, then serves a new episode (the
    single env, a vector env's sub-env) that also blows up at the first physics step: the second
    reset is detected too (``diverged``), not read as a cart at rest upright."""
    sc = LECTURE.replace(duration=1.0, noise=NoiseModel.lecture(scale=0.0))
    bad = np.array([[0.0, 0.0, 0.0, 1e300]])          # MuJoCo resets it in the first step
    with Simulator(plant, sc, backend=backend, streamed_metrics=False) as sim:
        for _ in range(3):
            sim.reset([np.random.default_rng(0)], initial_states=bad)
            sim.measure()
            assert sim.step_one(0.0)[1] == rules.FAIL_DIVERGED


def test_absurd_noise_is_counted_as_divergence_and_the_batch_completes(plant):
    sc = LECTURE.replace(noise=NoiseModel.lecture(scale=1e9), duration=1.0)
    rows = _run(plant, sc, "dlqr", "kalman", 5).rows
    assert all(not r["success"] for r in rows)
    assert {r["failure_reason"] for r in rows} == {"diverged"}
    assert all(np.isfinite(r["cost"]) for r in rows)


def test_pole_and_track_failures_are_named(plant):
    sc = LECTURE.replace(noise=NoiseModel.lecture(scale=0.0), x0=(0.0, 0.6, 0.0, 0.0))
    row = _run(plant, sc, "dlqr", "none", 1).rows[0]
    assert row["failure_reason"] == "pole_fell" and row["time_to_failure"] == pytest.approx(0.001)
    sc = LECTURE.replace(noise=NoiseModel.lecture(scale=0.0), x0=(2.39, 0.0, 3.0, 0.0))
    row = _run(plant, sc, "dlqr", "none", 1).rows[0]
    assert row["failure_reason"] == "track_limit" and 0 < row["time_to_failure"] < 0.05


def test_scenario_validation():
    with pytest.raises(ConfigError, match="duration: expected a finite positive number"):
        Scenario(duration=-1.0)
    with pytest.raises(ConfigError, match="x0: expected 4 finite numbers"):
        Scenario(x0=(0.0, 0.1))
    with pytest.raises(ConfigError, match="noise_scale: expected a finite number ≥ 0"):
        NoiseModel(scale=-1.0)
    with pytest.raises(ConfigError, match="measurement_variance: expected 2 finite non-negative numbers"):
        NoiseModel(measurement_variance=(-0.01, 0.01))
    with pytest.raises(ConfigError, match="observer: unknown 'kalmann'; expected one of none"):
        DesignSpec(observer="kalmann")


def test_wilson_interval_reference_values():
    lo, hi = wilson_interval(95, 100)
    assert lo == pytest.approx(0.8882, abs=1e-4) and hi == pytest.approx(0.9785, abs=1e-4)
    lo, hi = wilson_interval(0, 10)
    assert lo == 0.0 and hi == pytest.approx(0.2775, abs=1e-4)


def test_max_abs_theta_of_a_failed_episode_includes_the_crossing_sample(plant):
    """A pole that fell past θ_max reads max |θ| > θ_max: exactly the first sample beyond it."""
    from pendulum_lqg.policies.loading import build_policy

    scenario = Scenario(x0=(0.0, 0.45, 0.0, 1.0), duration=2.0)
    policy = build_policy("dlqr+luenberger", plant=plant, scenario=scenario)
    for backend in ("rollout", "step"):
        res = run_episodes(plant, scenario, policy, seed=0, episodes=range(3), backend=backend,
                           trajectory=True)
        for row, tr in zip(res.rows, res.trajectories, strict=True):
            assert row["failure_reason"] == "pole_fell"
            theta = np.abs(tr.states[:, 1])
            first = int(np.argmax(theta > scenario.theta_max))
            assert row["max_abs_theta"] == theta[first] > scenario.theta_max
            assert row["time_to_failure"] == pytest.approx(tr.t_physics[first])


@pytest.mark.parametrize("changes", [
    {},
    {"measurement_delay": 0.02, "actuator_delay": 0.01, "actuator_tau": 0.02, "dropout": 0.2},
    {"randomize": {"pole_mass_scale": (0.8, 1.2)}},
], ids=["plain", "delays-lag-dropout", "randomized"])
def test_step_one_equals_step_on_one_row(plant, changes):
    """The single env's period (``step_one``) and ``step`` on one row: the same states, costs,
    failure codes and saturated forces, with realistic sensing and actuation too, and for a
    non-finite force (diverged at once)."""
    from pendulum_lqg.core.rules import FAIL_DIVERGED, FAIL_NONE

    sc = LECTURE.replace(duration=3.0, noise=dataclasses.replace(LECTURE.noise, scale=3.0),
                         **changes)
    sims = [Simulator(plant, sc, streamed_metrics=False) for _ in range(2)]
    for s in sims:
        s.reset([np.random.default_rng(7)])
    saturated = 0
    for j in range(sc.n_periods):
        u = float(np.sin(0.05 * j) * 12.0)            # saturates at ±10 N now and then
        y = [sims[0].measure_one(), sims[1].measure()[0]]
        assert np.array_equal(y[0], y[1], equal_nan=True)
        cost, reason, force = sims[0].step_one(u)
        res = sims[1].step(np.array([u]))
        assert cost == float(res.cost[0]) and reason == int(res.reason[0])
        assert force == float(res.requested[0]) == max(-10.0, min(10.0, u))
        saturated += abs(force) == 10.0
        assert np.array_equal(sims[0].x, sims[1].x) and np.array_equal(sims[0].t, sims[1].t)
        if reason != FAIL_NONE:
            break
    assert saturated > 0
    s = Simulator(plant, sc, streamed_metrics=False)
    s.reset([np.random.default_rng(1)])
    s.measure()
    assert s.step_one(float("nan"))[1] == FAIL_DIVERGED
    many = Simulator(plant, sc, streamed_metrics=False)
    many.reset([np.random.default_rng(1), np.random.default_rng(2)])
    with pytest.raises(PendulumLQGError, match="step_one: needs a one-row simulator"):
        many.step_one(0.0)


def _reset_mask(reset, n):
    """A backend's answer as a mask: ``None`` (no row reset) as n False, an array copied."""
    return np.zeros(n, dtype=bool) if reset is None else reset.copy()


def test_batch_physics_aligned_and_general_record_copies_agree(plant):
    """The shipped model's records go into the period buffer as one run per row (``aligned``);
    models with other qpos/qvel layouts take the general strided copy: both fill rows 1 … k with
    the same states and report the same MuJoCo resets (an instability in row 2)."""
    from pendulum_lqg.core.period import PeriodBuffer
    from pendulum_lqg.core.physics import BatchPhysics

    k, n = 10, 5
    rng = np.random.default_rng(3)
    x = rng.normal(scale=0.2, size=(n, 4))
    x[2, 3] = 1e300                                  # MuJoCo resets this row
    u = rng.uniform(-10, 10, n)
    bufs, resets = [], []
    for aligned in (True, False):
        phys = BatchPhysics(plant, n, 1, k, aligned=aligned)
        assert phys.aligned is aligned
        period = PeriodBuffer(n, k, np.ones(5))
        resets.append(_reset_mask(phys.advance(x, u, None, period.view(n)), n))
        bufs.append(period.buf)
    assert np.array_equal(bufs[0][:, 1:k + 1, :4], bufs[1][:, 1:k + 1, :4])
    assert np.array_equal(resets[0], resets[1]) and resets[0].tolist() == [False, False, True,
                                                                              False, False]
    assert np.all(np.abs(bufs[0][:, 1:k + 1, :4] - x[:, None, :])[[0, 1, 3, 4]] > 0)   # it moved


def test_backends_report_a_reset_of_one_row_and_none_when_calm(plant):
    """A one-row period: the batch backend answers by one float comparison, the ``mj_step`` backend
    by its loop; both return ``None`` for a calm row and ``[True]`` for a row MuJoCo reset, and the
    failure rule reads that as ``diverged`` at the period's last step."""
    from pendulum_lqg.core.period import PeriodBuffer
    from pendulum_lqg.core.physics import BatchPhysics, StepPhysics

    k = 10
    bounds = rules.failure_bounds(theta_max=0.5, track_limit=2.4, u_max=10.0)
    for phys in (BatchPhysics(plant, 1, 1, k), StepPhysics(plant, k)):
        period = PeriodBuffer(1, k, bounds)
        view = period.view(1)
        assert phys.advance(np.array([[0.0, 0.1, 0.0, 0.0]]), np.array([1.0]), None, view) is None
        reset = phys.advance(np.array([[0.0, 0.1, 0.0, 1e300]]), np.array([1.0]), None, view)
        assert reset is not None and reset.tolist() == [True], type(phys).__name__
        failed, reason, fail_step = rules.detect_failure(view, reset, theta_max=0.5, track_limit=2.4)
        assert failed.tolist() == [True] and reason.tolist() == [rules.FAIL_DIVERGED]
        assert fail_step is not None and fail_step.tolist() == [k - 1]     # the reset: the last step


@pytest.mark.parametrize("n", [1, 5])
def test_batch_physics_direct_and_public_rollout_agree(plant, n):
    """The held-force period through the batch's C++ core (``direct_call``, on MuJoCo 4.0) and
    through the public ``Batch.rollout``: the same states bit for bit and the same resets — for
    one row (recorded in place into the period buffer) and for several (an instability in one)."""
    from pendulum_lqg.core.period import PeriodBuffer
    from pendulum_lqg.core.physics import BatchPhysics
    from pendulum_lqg.core.physics.mujoco_batch import DIRECT_CALL

    assert DIRECT_CALL == mujoco.__version__.startswith("4.0.")
    k = 10
    rng = np.random.default_rng(4)
    x = rng.normal(scale=0.2, size=(n, 4))
    if n > 1:
        x[-1, 3] = 1e300                             # MuJoCo resets the last of several rows
    u = rng.uniform(-10, 10, n)
    bufs, resets = [], []
    for direct in (True, False):
        phys = BatchPhysics(plant, n, 1, k)
        phys.direct_call = direct
        period = PeriodBuffer(n, k, np.ones(5))
        for _ in range(2):                           # the second call reuses the cached views
            resets.append(_reset_mask(phys.advance(x, u, None, period.view(n)), n))
        bufs.append(period.buf.copy())
    assert np.array_equal(bufs[0], bufs[1])
    assert all(np.array_equal(r, resets[0]) for r in resets), resets
    assert resets[0].tolist() == [False] * (n - 1) + [n > 1]
    calm = slice(0, max(1, n - 1))                   # the rows MuJoCo did not reset
    assert np.all(bufs[0][calm, 1:k + 1, :4] != x[calm, None, :])                     # they moved


@pytest.mark.parametrize("rows", [1, 200])                 # a mask tested by its bytes; a reduced one
def test_the_fast_failure_check_sees_any_one_number_out_of_bounds(rows):
    """``all_inside`` is True exactly when every number of the period is strictly inside its bound:
    one number at its bound, or a nan, anywhere in the buffer makes it False."""
    from pendulum_lqg.core.period import SMALL_MASK, PeriodBuffer

    k = 10
    bounds = rules.failure_bounds(theta_max=0.5, track_limit=2.4, u_max=10.0)
    view = PeriodBuffer(rows, k, bounds).view(rows)
    assert view.small == (view.inside.size <= SMALL_MASK) and view.small == (rows == 1)
    rng = np.random.default_rng(5)
    view.buf[...] = rng.uniform(-0.99, 0.99, view.buf.shape) * bounds
    assert rules.all_inside(view)
    # (column, value): θ at θ_max, p at −track, a nan velocity, a force beyond 2·u_max
    for col, value in ((1, bounds[1]), (0, -bounds[0]), (2, np.nan), (4, 2 * bounds[4])):
        for row, step in [(0, 0), (rows - 1, k + 1), (rows // 2, k // 2)]:
            saved = view.buf[row, step, col]
            view.buf[row, step, col] = value
            assert not rules.all_inside(view), (col, value, row, step)
            view.buf[row, step, col] = saved
    assert rules.all_inside(view)
