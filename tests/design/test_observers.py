"""The lecture's remaining observer designs: Ackermann, reduced order, LMI (decay rate, H₂, H∞)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.linalg import expm

from pendulum_lqg.design import kalman
from pendulum_lqg.design.observers import (
    ackermann,
    dreduced_order_observer,
    h2_filter,
    hinf_filter,
    lmi_observer,
    reduced_order_observer,
)
from pendulum_lqg.errors import DesignError, ShapeError
from pendulum_lqg.model.linearize import linearize

LECTURE_W, LECTURE_V = 4e-4 * np.eye(4), 1e-4 * np.eye(2)   # state density; V·T density


@pytest.fixture(scope="module")
def cartpole(plant):
    lin = linearize(plant)
    return lin.A, lin.B, lin.C


def _sorted(z):
    z = np.asarray(z, dtype=complex)
    return z[np.lexsort((np.round(z.imag, 6), np.round(z.real, 6)))]


def test_ackermann_reproduces_the_seed_example():
    A = np.array([[-1.0, 1, -2], [0, -1, 1], [0, 0, -1]])
    C = np.array([[1.0, 0, 0]])
    res = ackermann(A, C, [-2, -2 + 2j, -2 - 2j])
    np.testing.assert_allclose(res.L.ravel(), [3.0, 17.0, 5.0], atol=1e-12)
    np.testing.assert_allclose(_sorted(res.poles), _sorted([-2, -2 + 2j, -2 - 2j]),
                               atol=1e-9)
    with pytest.raises(ShapeError, match="single output"):
        ackermann(A, np.eye(3)[:2], [-1, -2, -3])
    with pytest.raises(DesignError, match="not observable"):
        ackermann(np.diag([1.0, 2.0, 3.0]), [[1.0, 1.0, 0.0]], [-1, -2, -3])


def test_ackermann_on_the_cart_pole_from_the_cart_position(cartpole):
    A, _, C = cartpole
    poles = [-4.0, -3.0, -2.0, -1.0]
    res = ackermann(A, C[:1], poles)
    np.testing.assert_allclose(np.sort(res.poles.real), sorted(poles), atol=1e-8)


@pytest.mark.parametrize("poles", [[-4.0, -5.0], [-2 + 1j, -2 - 1j]])
def test_reduced_order_error_dynamics_have_exactly_the_requested_poles(cartpole, poles):
    A, B, C = cartpole
    obs = reduced_order_observer(A, B, C, poles)
    assert obs.F.shape == (2, 2) and obs.G.shape == (2, 2)
    np.testing.assert_allclose(_sorted(np.linalg.eigvals(obs.F)), _sorted(poles),
                               atol=1e-10)
    # the observer reconstructs x exactly once its error has died out (noise-free linear model)
    dt = 0.01
    Phi = expm(A * dt)
    dobs = dreduced_order_observer(Phi, _zoh_gamma(A, B, dt), C, np.exp(np.asarray(poles) * dt))
    np.testing.assert_allclose(_sorted(dobs.poles),
                               _sorted(np.exp(np.asarray(poles) * dt)), atol=1e-12)
    Gamma = _zoh_gamma(A, B, dt)
    x = np.array([0.1, 0.05, -0.2, 0.3])
    z = np.zeros((1, 2))
    for k in range(2000):
        u = np.array([np.sin(0.01 * k)])
        y = C @ x
        x_hat = dobs.estimate(y[None, :], z)[0]
        z = z @ dobs.F.T + y[None, :] @ dobs.H_y.T + u[None, :] @ dobs.H_u.T
        x = Phi @ x + Gamma @ u
    np.testing.assert_allclose(x_hat, np.linalg.solve(Phi, x - Gamma @ u), atol=1e-9)


def _zoh_gamma(A, B, dt):
    n, m = A.shape[0], B.shape[1]
    M = np.zeros((n + m, n + m))
    M[:n, :n], M[:n, n:] = A, B
    return expm(M * dt)[:n, n:]


@pytest.mark.parametrize("alpha", [0.5, 1.0, 2.0])
def test_decay_rate_observer_poles_satisfy_the_prescribed_rate(cartpole, alpha):
    A, _, C = cartpole
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")                  # cvxpy's "may be inaccurate" notes
        res = lmi_observer(A, C, decay=alpha)
    assert np.all(res.poles.real <= -alpha + 1e-6), res.poles
    assert np.all(np.linalg.eigvalsh(res.P) > 0)
    lyap = (A - res.L @ C).T @ res.P + res.P @ (A - res.L @ C) + 2 * alpha * res.P
    assert np.linalg.eigvalsh(0.5 * (lyap + lyap.T)).max() <= 1e-6 * np.abs(res.P).max()


def test_h2_filter_equals_kalman_bucy_on_the_cart_pole(cartpole):
    A, _, C = cartpole
    h2 = h2_filter(A, np.eye(4), C, LECTURE_W, LECTURE_V)
    kb = kalman(A, np.eye(4), C, LECTURE_W, LECTURE_V)
    assert h2.status == "optimal"
    np.testing.assert_allclose(h2.L, kb.L, rtol=1e-5, atol=1e-5 * np.abs(kb.L).max())
    assert h2.bound == pytest.approx(np.trace(kb.P), rel=1e-6)     # H₂ cost = trace Σ


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_h2_filter_equals_kalman_bucy_on_random_systems(seed):
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(4, 4))
    C = rng.normal(size=(2, 4))
    G = rng.normal(size=(4, 3))
    W = np.diag(rng.uniform(0.1, 2, 3))
    V = np.diag(rng.uniform(0.1, 2, 2))
    h2 = h2_filter(A, G, C, W, V)
    kb = kalman(A, G, C, W, V)
    # the H₂ cost converges to the solver's tolerance; the gain, at a flat (quadratic) optimum,
    # to about its square root
    assert h2.bound == pytest.approx(np.trace(kb.P), rel=1e-6)
    np.testing.assert_allclose(h2.L, kb.L, rtol=2e-3, atol=2e-3 * np.abs(kb.L).max())


def _hinf_norm(A, L, C, G, W, V, omegas):
    Bd = np.hstack([G @ _sqrt(W), -L @ _sqrt(V)])
    Acl = A - L @ C
    n = A.shape[0]
    return max(np.linalg.svd(np.linalg.solve(1j * w * np.eye(n) - Acl, Bd), compute_uv=False)[0]
               for w in omegas)


def _sqrt(S):
    lam, U = np.linalg.eigh(S)
    return (U * np.sqrt(lam)) @ U.T


def test_hinf_filter_gamma_bounds_the_error_system_norm(cartpole):
    A, _, C = cartpole
    G = np.eye(4)
    omegas = np.concatenate([[0.0], np.logspace(-3, 3, 3000)])
    best = hinf_filter(A, G, C, LECTURE_W, LECTURE_V)
    norm = _hinf_norm(A, best.L, C, G, LECTURE_W, LECTURE_V, omegas)
    assert norm <= best.bound * (1 + 1e-6)            # the certificate holds
    assert np.all(best.poles.real < 0)
    loose = hinf_filter(A, G, C, LECTURE_W, LECTURE_V, gamma=2 * best.bound)
    assert loose.bound == 2 * best.bound
    assert _hinf_norm(A, loose.L, C, G, LECTURE_W, LECTURE_V, omegas) <= loose.bound
    with pytest.raises(DesignError, match="infeasible"):
        hinf_filter(A, G, C, LECTURE_W, LECTURE_V, gamma=0.5 * best.bound)


# ---- the observers in the benchmark, and the lecture's linear simulation --------------------------
NEW_OBSERVERS = ("reduced-order", "ackermann", "lmi", "h2", "hinf")


@pytest.mark.parametrize("observer", NEW_OBSERVERS)
def test_every_new_observer_stabilises_the_noise_free_loop(plant, observer):
    from pendulum_lqg.core.metrics import summarize
    from pendulum_lqg.core.noise import NoiseModel
    from pendulum_lqg.core.runner import run_episodes
    from pendulum_lqg.core.scenario import Scenario
    from pendulum_lqg.policies.loading import build_policy

    scenario = Scenario(noise=NoiseModel.lecture(scale=0.0))         # θ₀ = 0.1, x̂₀ = 0
    assert scenario.x0_std == (0.0, 0.0, 0.0, 0.0)     # no noise, one start: every episode alike,
    with warnings.catch_warnings():                    # so two stand for any number
        warnings.simplefilter("ignore")
        policy = build_policy(f"dlqr+{observer}", plant=plant, scenario=scenario)
    s = summarize(run_episodes(plant, scenario, policy, seed=0, episodes=range(2)).rows)
    assert s["success_rate"] == 1.0
    assert np.isfinite(s["rms_est_err_p_dot"]["mean"])


def test_h2_policy_equals_the_kalman_bucy_policy(plant):
    from pendulum_lqg.core.scenario import Scenario
    from pendulum_lqg.policies.loading import build_policy

    scenario = Scenario()
    h2 = build_policy("lqr+h2", plant=plant, scenario=scenario)
    kb = build_policy("lqr+kalman-bucy", plant=plant, scenario=scenario)
    np.testing.assert_allclose(h2.info["L"], kb.info["L"], rtol=1e-5,
                               atol=1e-5 * np.abs(kb.info["L"]).max())


@pytest.mark.parametrize("kind", ["linear-zoh", "linear-euler"])
def test_linear_plants_follow_their_difference_equations(plant, kind):
    """x[n+1] = Φ x[n] + Γ u[n] (exact ZOH) or x + T(A x + B u) (the lecture's Euler), sampled."""
    from pendulum_lqg.core.noise import NoiseModel
    from pendulum_lqg.core.runner import run_episodes
    from pendulum_lqg.core.scenario import Scenario
    from pendulum_lqg.design import zoh
    from pendulum_lqg.policies.loading import build_policy

    scenario = Scenario(noise=NoiseModel.lecture(scale=0.0), plant=kind, duration=2.0)
    policy = build_policy("dlqr+kalman", plant=plant, scenario=scenario)
    tr = run_episodes(plant, scenario, policy, seed=0, episodes=[0], trajectory=True).trajectories[0]
    lin = linearize(plant)
    T = scenario.control_period
    x, u = tr.x, tr.u
    if kind == "linear-zoh":
        Phi, Gamma = zoh(lin.A, lin.B, T)
        expected = x[:-1] @ Phi.T + u[:-1, None] * Gamma[:, 0]
    else:
        expected = x[:-1] + T * (x[:-1] @ lin.A.T + u[:-1, None] * lin.B[:, 0])
    np.testing.assert_allclose(x[1:], expected, rtol=1e-9, atol=1e-12)
    # the same noise streams as MuJoCo: noisy runs differ only by the plant
    noisy = Scenario(plant=kind, duration=2.0)
    a = run_episodes(plant, noisy, policy, seed=0, episodes=[0], trajectory=True).trajectories[0]
    b = run_episodes(plant, noisy.replace(plant="mujoco"), policy, seed=0, episodes=[0],
                     trajectory=True).trajectories[0]
    np.testing.assert_array_equal(a.y[0] - a.x[0, :2], b.y[0] - b.x[0, :2])   # same v[0]


def test_linear_plant_refuses_force_noise():
    from pendulum_lqg.core.noise import NoiseModel
    from pendulum_lqg.core.scenario import Scenario
    from pendulum_lqg.errors import ConfigError

    with pytest.raises(ConfigError, match="plant: 'linear-euler' takes process noise on the state"):
        Scenario(plant="linear-euler",
                 noise=NoiseModel(process="force", process_density=(0.01, 0.001)))
    with pytest.raises(ConfigError, match="plant: expected one of mujoco, linear-zoh"):
        Scenario(plant="linear")
