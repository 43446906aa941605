"""The closed-form loop (pendulum_lqg.policies.theory), stationary and over an episode from its
start, against closed-form answers, against a period-by-period propagation, and against the Monte
Carlo of the linear plant with every limit switched off."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from conftest import stationary_monte_carlo

from pendulum_lqg.core.scenario import Scenario
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.policies.loading import build_policy
from pendulum_lqg.policies.theory import (
    EpisodeStart,
    LinearEstimator,
    StationaryProblem,
    augmented_loop,
    lecture_theory,
    linear_estimator,
    noise_covariance,
    period_samples,
    policy_theory,
    stationary,
)

INF = float("inf")
STATES = ("p", "theta", "p_dot", "theta_dot")


def _free(plant_kind: str = "linear-zoh", duration: float = 10.0) -> Scenario:
    """The lecture scenario on a linear plant with every limit off, started at rest and known."""
    return Scenario(plant=plant_kind, theta_max=INF, track_limit=INF, force_limit=INF,
                    x0=(0.0, 0.0, 0.0, 0.0), estimate0="true", duration=duration)


# ---- closed-form answers ----------------------------------------------------------------------
def test_scalar_loop_matches_the_geometric_series():
    """x⁺ = a x + b u + w, u = −k x (full state): Var x = W/(1 − (a − bk)²), Var u = k² Var x,
    and the cost rate q Var x + r Var u (one physics step per period)."""
    a, b, k, W = 1.1, 1.0, 0.5, 0.3
    none = LinearEstimator(*(np.zeros((0, 0)),) * 5, full_state=True)
    prob = StationaryProblem(kind="linear-zoh", Phi=np.array([[a]]), Gamma=np.array([[b]]), k=1,
                             h=0.1, C=np.array([[1.0]]), K=np.array([[k]]), estimator=none,
                             Wd=np.array([[W]]), V=np.array([[0.0]]), Q=np.array([[2.0]]),
                             R=np.array([[3.0]]))
    res = stationary(prob, name="scalar", duration=5.0, state_names=("x",), units=("m",))
    var = W / (1 - (a - b * k) ** 2)
    assert res.spectral_radius == pytest.approx(0.6)
    assert res.std["x"] == pytest.approx(math.sqrt(var), rel=1e-12)
    assert res.u_std == pytest.approx(k * math.sqrt(var), rel=1e-12)
    assert res.cost_rate == pytest.approx(2.0 * var + 3.0 * k * k * var, rel=1e-12)
    assert res.cost_J == pytest.approx(5.0 * res.cost_rate)
    assert res.estimate_error_std["x"] == 0.0


def test_scalar_current_observer_error_variance():
    """A scalar current-form observer on x⁺ = a x + w, y = x + v with K = 0: the error of the prior
    e⁺ = a(1 − g) e − a g v + w has Var = (a²g²V + W)/(1 − a²(1 − g)²); the posterior error
    (1 − g) e + g v has Var (1 − g)² Var e + g² V."""
    a, g, W, V = 0.9, 0.4, 0.2, 0.5
    est = LinearEstimator(F=np.array([[a * (1 - g)]]), G_y=np.array([[a * g]]),
                          G_u=np.array([[1.0]]), H=np.array([[1 - g]]), D_y=np.array([[g]]))
    prob = StationaryProblem(kind="linear-zoh", Phi=np.array([[a]]), Gamma=np.array([[1.0]]),
                             k=1, h=1.0, C=np.array([[1.0]]), K=np.array([[0.0]]), estimator=est,
                             Wd=np.array([[W]]), V=np.array([[V]]), Q=np.eye(1), R=np.eye(1))
    res = stationary(prob, name="observer", duration=1.0, state_names=("x",), units=("m",))
    prior = (a * a * g * g * V + W) / (1 - a * a * (1 - g) ** 2)
    assert res.estimate_error_std["x"] == pytest.approx(math.sqrt((1 - g) ** 2 * prior
                                                                  + g * g * V), rel=1e-12)
    assert res.std["x"] == pytest.approx(math.sqrt(W / (1 - a * a)), rel=1e-12)


def test_separation_principle_in_the_eigenvalues(plant):
    """The augmented loop's eigenvalues are those of Φ − ΓK and of the observer (separation)."""
    scenario = _free()
    policy = build_policy("dlqr+kalman", plant=plant, scenario=scenario)
    res = policy_theory(plant, scenario, policy)
    expected = np.concatenate([policy.info["controller_poles"], policy.info["observer_poles"]])
    assert np.sort_complex(res.eigenvalues) == pytest.approx(np.sort_complex(expected), abs=1e-9)


def test_unstable_loop_reports_infinite_spread(plant):
    """An open loop (K = 0) of the upright pendulum is unstable: no stationary spread."""
    scenario = _free()
    policy = build_policy("dlqr+none", plant=plant, scenario=scenario)
    policy.K = np.zeros_like(policy.K)
    res = policy_theory(plant, scenario, policy)
    assert not res.stable and res.spectral_radius > 1
    assert res.std["theta"] == INF and res.cost_rate == INF
    assert res.verdict.startswith("unstable")


def test_lecture_answer_luenberger_stable_but_beyond_the_track(plant):
    """The issue's numbers: the Luenberger LQG loop is stable (radius 0.996 at T = 0.01 s) and its
    stationary std of p exceeds the ±2.4 m track; the Kalman loop's stays inside it."""
    res = lecture_theory(("dlqr+luenberger", "dlqr+kalman"), plant=plant)
    lu, ka = res["dlqr+luenberger"], res["dlqr+kalman"]
    assert lu.stable and lu.spectral_radius == pytest.approx(0.996, abs=5e-4)
    assert lu.std["p"] > plant.track_limit
    assert "exceeds the track" in lu.verdict
    assert ka.stable and ka.std["p"] < plant.track_limit / 3


def test_time_varying_kalman_is_its_steady_state(plant):
    """Stationary: the filter at its steady gain. Over the episode: its own gains first (the
    filter starts from M0 and trusts the first samples more), so its estimate error differs from
    the steady filter's, and the schedule ends where the gain is the steady one."""
    res = lecture_theory(("dlqr+kalman", "dlqr+kalman-tv"), plant=plant)
    assert res["dlqr+kalman-tv"].std == res["dlqr+kalman"].std
    assert "steady-state" in res["dlqr+kalman-tv"].notes[0]
    tv, steady = res["dlqr+kalman-tv"].episode, res["dlqr+kalman"].episode
    assert tv.estimate_error_rms["theta"] != pytest.approx(steady.estimate_error_rms["theta"],
                                                           rel=1e-3)
    policy = build_policy("dlqr+kalman-tv", plant=plant, scenario=Scenario())
    sched = linear_estimator(policy).schedule
    assert 0 < len(sched) < 100_000
    assert np.allclose(sched[-1].D_y, policy.info["L"], rtol=1e-9, atol=1e-12)


def test_theory_refuses_what_it_does_not_model(plant):
    with pytest.raises(ConfigError, match="actuator_delay"):
        sc = Scenario(actuator_delay=0.01)
        policy_theory(plant, sc, build_policy("dlqr+kalman", plant=plant, scenario=sc))
    with pytest.raises(ConfigError, match="plugin"):
        lecture_theory(("my_ctrl.py:make",), plant=plant)


# ---- Monte Carlo of the linear plant, limits off ----------------------------------------------
def _stationary_monte_carlo(plant, scenario, policy, *, episodes: int, burn_in: float,
                            seed: int) -> dict[str, tuple[float, float]]:
    """:func:`conftest.stationary_monte_carlo` on the ``step`` backend, by name: the mean and
    standard error of each of p², …, u², (p̂ − p)², …"""
    mean, se = stationary_monte_carlo(plant, scenario, policy, episodes=episodes,
                                      burn_in=burn_in, seed=seed, backend="step")
    names = [*STATES, "u", *(f"err_{s}" for s in STATES)]
    return {k: (float(m), float(s)) for k, m, s in zip(names, mean, se, strict=True)}


def _check_inside(theory, mc: dict[str, tuple[float, float]], z: float = 1.96) -> None:
    """Every theoretical variance inside the Monte Carlo's interval mean ± z·SE (z = 1.96: each
    a 95 % interval; z = 2.77: the nine together at 95 %, Bonferroni)."""
    expected = {**{s: theory.std[s] ** 2 for s in STATES}, "u": theory.u_std ** 2,
                **{f"err_{s}": theory.estimate_error_std[s] ** 2 for s in STATES}}
    outside = {k: (expected[k], mc[k]) for k in expected
               if abs(mc[k][0] - expected[k]) > z * mc[k][1]}
    assert not outside, f"theory outside the interval ±{z}·SE: {outside}"


@pytest.mark.parametrize("name", ["dlqr+kalman", "dlqr+luenberger"])
@pytest.mark.slow
def test_monte_carlo_agrees_with_theory(plant, name):
    """2 000 episodes' worth (200 × 100 s after a 20 s burn-in, 8 time constants of the
    Luenberger loop) of the linear ZOH plant with the limits off: every variance of x, u and
    x̂ − x that the theory gives lies inside the Monte Carlo's 95 % interval."""
    scenario = _free(duration=120.0)
    policy = build_policy(name, plant=plant, scenario=scenario)
    mc = _stationary_monte_carlo(plant, scenario, policy, episodes=200, burn_in=20.0, seed=3)
    _check_inside(policy_theory(plant, scenario, policy), mc)


def test_monte_carlo_agrees_with_theory_quick(plant):
    """The quick version, Kalman on the lecture's Euler plant: 200 × 15 s after a 5 s burn-in
    (300 episodes' worth), the nine comparisons held to a joint 95 % level."""
    scenario = _free("linear-euler", duration=20.0)
    policy = build_policy("dlqr+kalman", plant=plant, scenario=scenario)
    mc = _stationary_monte_carlo(plant, scenario, policy, episodes=200, burn_in=5.0, seed=1)
    _check_inside(policy_theory(plant, scenario, policy), mc, z=2.77)


def _separation_gap(plant, name):
    """The largest distance from an eigenvalue of the theory's augmented loop to the nearest of
    Φ − ΓK and the observer's poles (0 when the separation principle holds)."""
    from pendulum_lqg.design import zoh
    from pendulum_lqg.model.linearize import linearize

    scenario = _free()
    policy = build_policy(name, plant=plant, scenario=scenario)
    res = policy_theory(plant, scenario, policy)
    lin = linearize(plant)
    Phi, Gamma = zoh(lin.A, lin.B, scenario.control_period)
    union = np.concatenate([np.linalg.eigvals(Phi - Gamma @ policy.K),
                            np.asarray(policy.info["observer_poles"])])
    assert res.stable and res.eigenvalues.size == union.size
    return max(np.min(np.abs(union - z)) for z in res.eigenvalues)


@pytest.mark.parametrize("name", ["dlqr+luenberger", "dlqr+kalman", "dlqr+kalman-predictor",
                                  "dlqr+kalman-tv", "dlqr+reduced-order", "dlqr+ackermann",
                                  "lqr+kalman"])
def test_discrete_observers_separate(plant, name):
    """Every observer built on the sampled plant's own (Φ, Γ) — current, predictor, reduced
    order, the time-varying filter at its steady gain — separates: the augmented loop's
    eigenvalues are those of Φ − ΓK and of the observer."""
    assert _separation_gap(plant, name) < 1e-8


@pytest.mark.parametrize("name", ["dlqr+kalman-bucy", "lqr+kalman-bucy", "lqr+luenberger-euler",
                                  "lqr+kalman-bucy-euler"])
def test_emulated_observers_separate_only_approximately(plant, name):
    """A continuous observer run under sample-and-hold (ZOH of its ODE) or stepped by forward
    Euler predicts the plant with another model than the sampled plant's (Φ, Γ): its error is
    driven by the state, and the separation principle holds only to O(T) — the eigenvalues move,
    by less than 0.05 at T = 0.01 s."""
    gap = _separation_gap(plant, name)
    assert 1e-6 < gap < 0.05


# ---- the expected RMS over an episode from x₀ and x̂₀ ---------------------------------------------
LTI = Path(__file__).resolve().parents[2] / "experiments" / "lti"
#: the 97.5 % quantile of Student's t with 199 degrees of freedom (200 episodes)
T_199 = 1.971956544249395


def test_episode_of_a_scalar_loop_is_the_geometric_sum():
    """x⁺ = c x + w (full state, c = a − bk), x₀ = 2, one physics step a period:
    E[x_k²] = c^{2k} x₀² + W (1 − c^{2k})/(1 − c²); the episode's mean square is their mean over
    k = 0 … N−1 (and over k = s … N−1 after a burn-in of s periods)."""
    a, b, k, W, x0, N = 1.1, 1.0, 0.5, 0.3, 2.0, 40
    c = a - b * k
    none = LinearEstimator(*(np.zeros((0, 0)),) * 5, full_state=True)
    prob = StationaryProblem(kind="linear-zoh", Phi=np.array([[a]]), Gamma=np.array([[b]]), k=1,
                             h=0.1, C=np.array([[1.0]]), K=np.array([[k]]), estimator=none,
                             Wd=np.array([[W]]), V=np.array([[0.0]]), Q=np.array([[2.0]]),
                             R=np.array([[3.0]]))
    ex2 = np.array([c ** (2 * j) * x0 ** 2 + W * (1 - c ** (2 * j)) / (1 - c * c)
                    for j in range(N)])
    start = EpisodeStart(x0=np.array([x0]), x0_std=np.zeros(1), x_hat0=np.zeros(1))
    for burn, skip in ((0.0, 0), (1.0, 10)):
        ep = stationary(prob, name="scalar", duration=N * 0.1, state_names=("x",),
                        units=("m",), start=start, burn_in=burn).episode
        assert ep.skip == skip
        assert ep.rms["x"] == pytest.approx(math.sqrt(ex2[skip:].mean()), rel=1e-12)
        assert ep.u_rms == pytest.approx(k * math.sqrt(ex2[skip:].mean()), rel=1e-12)
        assert ep.cost_J == pytest.approx(0.1 * (2.0 + 3.0 * k * k) * ex2.sum(), rel=1e-12)


def _propagated(prob, start, periods):
    """The same second moments by brute force: mean and covariance of [x; ξ] stepped period by
    period, the read-outs summed over every period (x at each physics step, u, x̂ − x)."""
    maps, Phi_T, Gamma_T = period_samples(prob.kind, prob.Phi, prob.Gamma, prob.k)
    loop = augmented_loop(Phi_T, Gamma_T, prob.C, prob.K, prob.estimator)
    N = noise_covariance(prob)
    n = prob.Phi.shape[0]
    S = prob.estimator.start_map(n)
    m = np.concatenate([start.x0, S @ (start.x0 if start.x_hat0 is None else start.x_hat0)])
    J = np.vstack([np.eye(n), S if start.x_hat0 is None else 0 * S])
    P = J @ np.diag(start.x0_std ** 2) @ J.T
    x2, u2, e2 = np.zeros(n), 0.0, np.zeros(n)
    steady = loop
    for j in range(periods):                  # a varying gain: its own loop in each period
        sched = prob.estimator.schedule
        loop = augmented_loop(Phi_T, Gamma_T, prob.C, prob.K, sched[j]) if j < len(sched) \
            else steady
        Zs = np.vstack([np.hstack([np.eye(n), np.zeros((n, loop.A.shape[0] - n))]), loop.C_u])
        Ze = np.vstack([np.zeros((n, N.shape[0])), loop.D_u])
        M = P + np.outer(m, m)
        z = Zs @ M @ Zs.T + Ze @ N @ Ze.T
        x2 += np.mean([np.diag(T @ z @ T.T) for T in maps], axis=0)
        u2 += z[n, n]
        e2 += np.diag(loop.C_e @ M @ loop.C_e.T + loop.D_e @ N @ loop.D_e.T)
        m, P = loop.A @ m, loop.A @ P @ loop.A.T + loop.B @ N @ loop.B.T
    return np.sqrt(x2 / periods), math.sqrt(u2 / periods), np.sqrt(e2 / periods)


@pytest.mark.parametrize("name, estimate0, duration", [
    ("dlqr+kalman", "zero", 3.0), ("dlqr+reduced-order", "zero", 3.0),
    ("dlqr+luenberger", "true", 3.0), ("lqr+kalman-bucy", "zero", 3.0),
    ("dlqr+kalman-tv", "zero", 3.0), ("dlqr+kalman-tv", "true", 15.0)])
def test_episode_closed_form_equals_the_period_by_period_propagation(plant, name, estimate0,
                                                                     duration):
    """The closed form (a Lyapunov equation and two matrix powers) against the mean and the
    covariance stepped period by period, from x₀ = [0.1, 0.1, 0, 0] with a spread, on the
    cart-pole's ZOH plant (10 physics steps a period): the same numbers to 1e-9. The
    time-varying Kalman filter's first periods go through its own gains in both (15 s: past the
    end of its schedule, then the steady loop in closed form)."""
    scenario = Scenario(plant="linear-zoh", x0=(0.1, 0.1, 0.0, 0.0), x0_std=(0.05, 0.02, 0.1, 0.0),
                        estimate0=estimate0, duration=duration)
    policy = build_policy(name, plant=plant, scenario=scenario)
    res = policy_theory(plant, scenario, policy)
    from pendulum_lqg.core.physics.linear import LinearPhysics
    from pendulum_lqg.model.linearize import linearize

    phys = LinearPhysics(plant, "linear-zoh", 10)
    prob = StationaryProblem(kind="linear-zoh", Phi=phys.Phi, Gamma=phys.Gamma[:, None], k=10,
                             h=plant.timestep, C=linearize(plant).C, K=policy.K,
                             estimator=linear_estimator(policy), Wd=scenario.noise.W * 0.01,
                             V=scenario.noise.V, Q=np.eye(4), R=np.eye(1))
    start = EpisodeStart(x0=np.array(scenario.x0), x0_std=np.array(scenario.x0_std),
                         x_hat0=None if estimate0 == "true" else np.zeros(4))
    x, u, e = _propagated(prob, start, round(duration / 0.01))
    ep = res.episode
    assert [ep.rms[s] for s in STATES] == pytest.approx(x, rel=1e-9)
    assert ep.u_rms == pytest.approx(u, rel=1e-9)
    assert [ep.estimate_error_rms[s] for s in STATES] == pytest.approx(e, rel=1e-9, abs=1e-15)


def _ms_interval(rows, key):
    """Mean of an episode metric's square over the episodes and its 95 % t half-width."""
    v = np.array([r[key] ** 2 for r in rows])
    return float(v.mean()), T_199 * float(v.std(ddof=1)) / math.sqrt(v.size)


@pytest.mark.parametrize("name", ["dlqr+kalman", "dlqr+luenberger"])
@pytest.mark.parametrize("burn_in", [0.0, 2.0])
def test_episode_theory_agrees_with_the_linear_monte_carlo(name, burn_in):
    """The acceptance test of the expected RMS: the double integrator started away from zero
    (x₀ = [1, 0], x̂₀ = 0), 200 episodes of 10 s of the file's exact linear model, no limit. The
    mean over the episodes of each metric's square — RMS² of each state, of u, of each estimate
    error — has the theory's value inside its 95 % t-interval, with and without a burn-in; the
    stationary variance of the position lies outside it for the Kalman loop (the transient
    from x₀ and x̂₀ is what it misses)."""
    from pendulum_lqg.core.runner import run_episodes
    from pendulum_lqg.model.lti import load_lti
    from pendulum_lqg.policies.lti import design_lti_policy, lti_scenario, lti_theory

    plant = load_lti(LTI / "double_integrator.toml")
    assert list(plant.x0) == [1.0, 0.0]
    scenario = lti_scenario(plant, duration=10.0, burn_in=burn_in)
    res = lti_theory(plant, (name,), duration=10.0, burn_in=burn_in)[name]
    rows = run_episodes(plant, scenario, design_lti_policy(plant, name), seed=1,
                        episodes=range(200)).rows
    ep = res.episode
    expected = {**{f"rms_{s}": ep.rms[s] for s in plant.state_names}, "rms_u": ep.u_rms,
                **{f"rms_est_err_{s}": ep.estimate_error_rms[s] for s in plant.state_names}}
    outside = {}
    for key, value in expected.items():
        mean, half = _ms_interval(rows, key)
        if abs(mean - value ** 2) > half:
            outside[key] = (value ** 2, mean, half)
    assert not outside, f"theory outside the 95 % interval: {outside}"
    if name == "dlqr+kalman":
        mean, half = _ms_interval(rows, "rms_position")
        assert abs(mean - res.rms["position"] ** 2) > half


def test_burn_in_zero_leaves_every_metric_unchanged_and_a_burn_in_only_the_rms(plant):
    """burn_in = 0 is the loop of before, bit for bit; a burn-in changes the RMS columns only."""
    from pendulum_lqg.core.runner import run_episodes

    sc = Scenario(plant="linear-zoh", duration=1.0)
    policy = build_policy("dlqr+kalman", plant=plant, scenario=sc)
    a = run_episodes(plant, sc, policy, seed=5, episodes=range(3)).rows
    b = run_episodes(plant, sc.replace(burn_in=0.0), policy, seed=5, episodes=range(3)).rows
    c = run_episodes(plant, sc.replace(burn_in=0.5), policy, seed=5, episodes=range(3)).rows
    assert repr(a) == repr(b)                     # bit for bit (nan == nan here)
    for ra, rc in zip(a, c, strict=True):
        changed = {k for k in ra if repr(ra[k]) != repr(rc[k])}
        assert changed == {"rms_theta", "rms_p", "rms_u", *(f"rms_est_err_{s}" for s in STATES)}


@pytest.mark.parametrize("burn_in, message", [(1.0, "less than the episode"),
                                              (-0.1, "≥ 0"), (math.nan, "≥ 0")])
def test_burn_in_must_leave_part_of_the_episode(burn_in, message):
    with pytest.raises(ConfigError, match=f"burn_in: .*{message}"):
        Scenario(duration=1.0, burn_in=burn_in)


def test_theory_of_an_overflowing_noise_refuses_in_one_line():
    """scale² · W past the float range: one line naming the noise, never an OverflowError."""
    none = LinearEstimator(*(np.zeros((0, 0)),) * 5, full_state=True)
    prob = StationaryProblem(kind="linear-zoh", Phi=np.array([[0.5]]), Gamma=np.array([[1.0]]),
                             k=1, h=0.1, C=np.array([[1.0]]), K=np.array([[0.0]]),
                             estimator=none, Wd=np.array([[1e200 * 1e200]]),
                             V=np.array([[0.0]]), Q=np.eye(1), R=np.eye(1))
    with pytest.raises(ConfigError, match=r"noise_scale: .*overflow"):
        stationary(prob, name="x", duration=1.0, state_names=("x",), units=("",))
