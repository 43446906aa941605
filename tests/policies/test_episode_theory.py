"""The expected RMS over an episode from x₀ and x̂₀ (pendulum_lqg.policies.episode_theory) against
a geometric sum, against the mean and covariance stepped period by period, and against the linear
Monte Carlo of a plant started away from zero (its 95 % interval, every state)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from pendulum_lqg.core.scenario import Scenario
from pendulum_lqg.policies.closed_loop import (
    LinearEstimator,
    StationaryProblem,
    augmented_loop,
    linear_estimator,
    noise_covariance,
    period_samples,
)
from pendulum_lqg.policies.episode_theory import EpisodeStart
from pendulum_lqg.policies.loading import build_policy
from pendulum_lqg.policies.theory import policy_theory, stationary

STATES = ("p", "theta", "p_dot", "theta_dot")


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


def test_episode_cost_with_a_cross_term_is_python_controls_optimal_cost():
    """Noise-free, full state, the gain of ``control.dlqr(Φ, Γ, Q, R, N)`` on the two-mass plant
    with a cross term: the episode's E[J] over a long horizon is T·x₀ᵀ S x₀ (S python-control's
    Riccati solution; the simulated cost is T Σ zᵀ [[Q, N], [Nᵀ, R]] z), to 1e-9."""
    import control

    from pendulum_lqg.model.lti import load_lti

    plant = load_lti(LTI / "two_mass.toml")
    N = np.array([[0.1, 0.0], [0.0, -0.1], [0.0, 0.0], [0.0, 0.0]])
    K, S, _ = control.dlqr(plant.Phi, plant.Gamma, plant.Q, plant.R, N)
    none = LinearEstimator(*(np.zeros((0, 0)),) * 5, full_state=True)
    T, n = plant.control_period, plant.n_states
    prob = StationaryProblem(kind="linear-zoh", Phi=plant.Phi, Gamma=plant.Gamma, k=1, h=T,
                             C=plant.C, K=np.asarray(K), estimator=none, Wd=np.zeros((n, n)),
                             V=np.zeros((2, 2)), Q=plant.Q, R=plant.R, N=N, inputs=("f1", "f2"))
    x0 = np.array([0.2, -0.2, 0.1, 0.0])
    start = EpisodeStart(x0=x0, x0_std=np.zeros(n), x_hat0=np.zeros(n))
    ep = stationary(prob, name="dlqr", duration=400.0, state_names=plant.state_names,
                    units=("",) * n, start=start).episode
    assert ep.cost_J == pytest.approx(T * x0 @ S @ x0, rel=1e-9)
    assert set(ep.u_rms_by_input) == {"f1", "f2"}


def test_two_input_episode_theory_is_the_noise_free_simulation():
    """The two-mass plant with a cross term under dlqr+none, no noise: the simulated cost and each
    input's RMS are the episode theory's (the loop is deterministic), to 1e-10."""
    import dataclasses

    from pendulum_lqg.core.noise import NoiseModel
    from pendulum_lqg.core.runner import run_episodes
    from pendulum_lqg.model.lti import load_lti
    from pendulum_lqg.policies.lti import design_lti_policy, lti_theory

    plant = load_lti(LTI / "two_mass.toml")
    N = np.array([[0.1, 0.0], [0.0, -0.1], [0.0, 0.0], [0.0, 0.0]])
    plant = dataclasses.replace(plant, N=N)
    sc = Scenario(control_period=plant.control_period, duration=2.0, plant="linear-zoh",
                  noise=NoiseModel(scale=0.0))
    row = run_episodes(plant, sc, design_lti_policy(plant, "dlqr+none"), seed=1,
                       episodes=[0]).rows[0]
    res = lti_theory(plant, ("dlqr+none",), noise_scale=0.0, duration=2.0)["dlqr+none"]
    ep = res.episode
    assert ep.cost_J == pytest.approx(row["cost"], rel=1e-10)
    for u in ("f1", "f2"):
        assert ep.u_rms_by_input[u] == pytest.approx(row[f"rms_{u}"], rel=1e-10)
    for s in plant.state_names:
        assert ep.rms[s] == pytest.approx(row[f"rms_{s}"], rel=1e-10)
    assert set(res.u_std_by_input) == {"f1", "f2"}
