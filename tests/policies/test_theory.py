"""The stationary closed-form loop (pendulum_lqg.policies.theory) against closed-form answers and
against the Monte Carlo of the linear plant with every limit switched off (the episode's theory:
test_episode_theory.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from conftest import stationary_monte_carlo

from pendulum_lqg.core.scenario import Scenario
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.policies.closed_loop import LinearEstimator, StationaryProblem, linear_estimator
from pendulum_lqg.policies.loading import build_policy
from pendulum_lqg.policies.theory import lecture_theory, policy_theory, stationary

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


def test_cross_term_and_inputs_of_a_scalar_loop_in_closed_form():
    """x⁺ = a x + b u + w, u = −k x (full state): E[x u] = −k Var x, so the cost rate with a
    cross term n is (q − 2 n k + r k²) Var x; one input gives no per-input keys."""
    a, b, k, W, q, n, r = 1.1, 1.0, 0.5, 0.3, 2.0, 0.4, 3.0
    none = LinearEstimator(*(np.zeros((0, 0)),) * 5, full_state=True)
    prob = StationaryProblem(kind="linear-zoh", Phi=np.array([[a]]), Gamma=np.array([[b]]), k=1,
                             h=0.1, C=np.array([[1.0]]), K=np.array([[k]]), estimator=none,
                             Wd=np.array([[W]]), V=np.array([[0.0]]), Q=np.array([[q]]),
                             R=np.array([[r]]), N=np.array([[n]]))
    res = stationary(prob, name="scalar", duration=5.0, state_names=("x",), units=("m",))
    var = W / (1 - (a - b * k) ** 2)
    assert res.cost_rate == pytest.approx((q - 2 * n * k + r * k * k) * var, rel=1e-12)
    assert res.u_std_by_input == {} and "u_std_by_input" not in res.to_dict()


def test_two_inputs_have_their_own_std():
    """Two decoupled scalar loops side by side (inputs f1, f2): each input's std is its own loop's
    k_j √(W_j / (1 − c_j²)), under the input's name; u_std stays the first's."""
    a, b, k, W = np.array([1.1, 0.9]), np.array([1.0, 2.0]), np.array([0.5, 0.2]), np.array([0.3, 0.1])
    none = LinearEstimator(*(np.zeros((0, 0)),) * 5, full_state=True)
    prob = StationaryProblem(kind="linear-zoh", Phi=np.diag(a), Gamma=np.diag(b), k=1, h=0.1,
                             C=np.eye(2), K=np.diag(k), estimator=none, Wd=np.diag(W),
                             V=np.zeros((2, 2)), Q=np.eye(2), R=np.eye(2), inputs=("f1", "f2"))
    res = stationary(prob, name="two", duration=5.0, state_names=("x1", "x2"), units=("", ""))
    std = k * np.sqrt(W / (1 - (a - b * k) ** 2))
    assert list(res.u_std_by_input) == ["f1", "f2"]
    assert [res.u_std_by_input["f1"], res.u_std_by_input["f2"]] == pytest.approx(std, rel=1e-12)
    assert res.u_std == res.u_std_by_input["f1"]
    assert res.to_dict()["u_std_by_input"] == res.u_std_by_input
