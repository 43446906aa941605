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
from pendulum_lqg.linearize import linearize

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
