"""The design layer against closed-form answers and published tables (docs/theory.md §5)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pendulum_lqg import design
from pendulum_lqg.errors import DesignError, PendulumLQGError, ShapeError

SQ2, SQ3 = math.sqrt(2), math.sqrt(3)
A_DI = np.array([[0.0, 1.0], [0.0, 0.0]])
B_DI = np.array([[0.0], [1.0]])
C_DI = np.array([[1.0, 0.0]])
PHI_OGATA = np.array([[1.0, 1.0], [1.0, 0.0]])
GAMMA_OGATA = np.array([[1.0], [0.0]])


# ---- worked example 1: scalar plant --------------------------------------------------------------
def test_scalar_lqr_matches_closed_form():
    r = design.lqr([[1.0]], [[1.0]], [[1.0]], [[1.0]])
    assert r.P[0, 0] == pytest.approx(1 + SQ2, abs=1e-12)
    assert r.K[0, 0] == pytest.approx(1 + SQ2, abs=1e-12)
    assert r.K[0, 0] == pytest.approx(2.414, abs=5e-4)
    assert r.poles[0].real == pytest.approx(-SQ2, abs=1e-12)


# ---- worked example 2: double integrator ---------------------------------------------------------
def test_double_integrator_lqr():
    r = design.lqr(A_DI, B_DI, C_DI.T @ C_DI, 1.0)
    np.testing.assert_allclose(r.P, [[SQ2, 1], [1, SQ2]], atol=1e-12)
    np.testing.assert_allclose(r.K, [[1, SQ2]], atol=1e-12)
    expected = SQ2 / 2 * np.array([-1 + 1j, -1 - 1j])
    np.testing.assert_allclose(np.sort_complex(r.poles), np.sort_complex(expected), atol=1e-12)


def test_double_integrator_kalman_bucy():
    k = design.kalman(A_DI, np.eye(2), C_DI, np.eye(2), 1.0)
    np.testing.assert_allclose(k.P, [[SQ3, 1], [1, SQ3]], atol=1e-12)
    np.testing.assert_allclose(k.L, [[SQ3], [1]], atol=1e-12)
    expected = np.array([-SQ3 + 1j, -SQ3 - 1j]) / 2
    np.testing.assert_allclose(np.sort_complex(k.poles), np.sort_complex(expected), atol=1e-12)


# ---- worked example 3: Ogata's finite-horizon problem --------------------------------------------
def test_ogata_finite_horizon_table():
    fh = design.finite_horizon_dlqr(PHI_OGATA, GAMMA_OGATA, np.eye(2), 1.0, np.eye(2), 8)
    assert fh.K.shape == (8, 1, 2) and fh.P.shape == (9, 2, 2)
    np.testing.assert_allclose(fh.P[0], [[3.7913, 1.0000], [1.0000, 1.7913]], atol=5e-5)
    np.testing.assert_allclose(fh.K[0], [[1.0000, 0.7913]], atol=5e-5)
    np.testing.assert_allclose(fh.K[7], [[0.5, 0.5]], atol=1e-12)
    np.testing.assert_allclose(fh.P[7], [[2.5, 0.5], [0.5, 1.5]], atol=1e-12)
    np.testing.assert_allclose(fh.P[8], np.eye(2), atol=0)
    x, u = fh.simulate(PHI_OGATA, GAMMA_OGATA, [1.0, 0.0])
    published = [-1, -0.7913, -0.2087, -0.1651, -0.0435, -0.0342, -0.0087, -0.0057]
    np.testing.assert_allclose(u.ravel(), published, atol=5e-5)
    np.testing.assert_allclose(x[8], [0.0057, 0.0015], atol=5e-5)
    # optimal cost ½x₀ᵀP₀x₀ equals the cost summed along the optimal trajectory
    cost = 0.5 * sum(x[k] @ x[k] + u[k] @ u[k] for k in range(8)) + 0.5 * x[8] @ x[8]
    assert cost == pytest.approx(0.5 * x[0] @ fh.P[0] @ x[0], rel=1e-12)


def test_ogata_stationary_dlqr():
    r = design.dlqr(PHI_OGATA, GAMMA_OGATA, np.eye(2), 1.0)
    np.testing.assert_allclose(r.K, [[1.0000, 0.7913]], atol=5e-5)
    # DARE residual
    P, F, G = r.P, PHI_OGATA, GAMMA_OGATA
    resid = F.T @ (P - P @ G @ np.linalg.solve(1 + G.T @ P @ G, G.T @ P)) @ F + np.eye(2) - P
    assert np.max(np.abs(resid)) < 1e-10
    # the finite-horizon gain converges to it
    fh = design.finite_horizon_dlqr(PHI_OGATA, GAMMA_OGATA, np.eye(2), 1.0, np.eye(2), 60)
    np.testing.assert_allclose(fh.K[0], r.K, atol=1e-10)


def test_pincer_places_poles_inside_radius():
    alpha = 100 ** (0.1 / 1.0)          # 1 % settling in 1 s at T = 0.1 s
    plain = design.dlqr(PHI_OGATA, GAMMA_OGATA, np.eye(2), 1.0)
    pincer = design.dlqr(PHI_OGATA, GAMMA_OGATA, np.eye(2), 1.0, alpha=alpha)
    assert np.max(np.abs(pincer.poles)) < 1 / alpha
    np.testing.assert_allclose(pincer.poles, np.linalg.eigvals(PHI_OGATA - GAMMA_OGATA @ pincer.K))
    assert not np.allclose(plain.K, pincer.K)


def test_bryson_rule():
    Q, R = design.bryson([0.5, 0.1, np.inf, 2.0], [10.0])
    np.testing.assert_allclose(np.diag(Q), [4.0, 100.0, 0.0, 0.25])
    np.testing.assert_allclose(R, [[0.01]])


def test_cross_weight_matches_python_control():
    import control

    N = np.array([[0.1], [0.2]])
    r = design.lqr(A_DI, B_DI, np.eye(2), 1.0, N=N)
    K, _, _ = control.lqr(A_DI, B_DI, np.eye(2), 1.0, N)
    np.testing.assert_allclose(r.K, K, atol=1e-10)


# ---- discrete Kalman: filter vs predictor gain ---------------------------------------------------
def test_dkalman_filter_and_predictor_gains():
    import control

    Phi, _ = design.zoh(A_DI, B_DI, 0.1)
    W, V = np.diag([1e-3, 1e-2]), np.array([[0.05]])
    kf = design.dkalman(Phi, np.eye(2), C_DI, W, V)
    L_dlqe, M_dlqe, _ = control.dlqe(Phi, np.eye(2), C_DI, W, V)
    np.testing.assert_allclose(kf.L_pred, L_dlqe, atol=1e-10)     # dlqe = predictor gain
    np.testing.assert_allclose(kf.M, M_dlqe, atol=1e-10)
    np.testing.assert_allclose(kf.L, kf.M @ C_DI.T @ np.linalg.inv(C_DI @ kf.M @ C_DI.T + V))
    np.testing.assert_allclose(kf.L_pred, Phi @ kf.L, atol=1e-14)
    assert not np.allclose(kf.L, kf.L_pred)
    np.testing.assert_allclose(kf.L, kf.P @ C_DI.T @ np.linalg.inv(V), atol=1e-10)
    # time-varying recursion converges to the steady-state filter
    tv = design.kalman_tv(Phi, np.eye(2), C_DI, W, V, np.eye(2), 400)
    np.testing.assert_allclose(tv.L[-1], kf.L, atol=1e-9)
    np.testing.assert_allclose(tv.M[-1], kf.M, atol=1e-9)
    np.testing.assert_allclose(tv.L[0], np.eye(2) @ C_DI.T @ np.linalg.inv(C_DI @ C_DI.T + V))


# ---- Luenberger ----------------------------------------------------------------------------------
def test_luenberger_places_poles():
    A = np.array([[0, 1, 0, 0], [0, 0, -0.7, 0], [0, 0, 0, 1], [0, 0, 15.8, 0]], dtype=float)
    C = np.array([[1, 0, 0, 0], [0, 0, 1, 0]], dtype=float)
    obs = design.luenberger(A, C, design.DEFAULT_OBSERVER_POLES)
    np.testing.assert_allclose(np.sort(obs.poles.real), [-0.7, -0.6, -0.5, -0.4], atol=1e-9)
    Phi, _ = design.zoh(A, np.zeros((4, 1)), 0.05)
    cur = design.dluenberger(Phi, C, [-0.4, -0.5, -0.6, -0.7], form="current", dt=0.05)
    np.testing.assert_allclose(np.sort(cur.poles.real), np.sort(np.exp(0.05 * np.array(
        [-0.4, -0.5, -0.6, -0.7]))), atol=1e-9)
    np.testing.assert_allclose(np.sort(np.linalg.eigvals(Phi - cur.L @ C @ Phi).real),
                               np.sort(cur.poles.real), atol=1e-12)
    pred = design.dluenberger(Phi, C, [0.1, 0.2, 0.3 + 0.1j, 0.3 - 0.1j], form="predictor")
    np.testing.assert_allclose(np.sort_complex(pred.poles),
                               np.sort_complex(np.array([0.1, 0.2, 0.3 - 0.1j, 0.3 + 0.1j])),
                               atol=1e-9)


def test_lqg_separation_double_integrator():
    K = design.lqr(A_DI, B_DI, C_DI.T @ C_DI, 1.0).K
    L = design.kalman(A_DI, np.eye(2), C_DI, np.eye(2), 1.0).L
    res = design.lqg(A_DI, B_DI, C_DI, K, L)
    assert res.A_cl.shape == (4, 4)
    # eigenvalues of the non-normal 4×4 closed loop are only conditioned to ~1e-8 here
    assert res.separation_error < 1e-6
    np.testing.assert_allclose(np.sort_complex(res.controller_poles),
                               np.sort_complex(SQ2 / 2 * np.array([-1 - 1j, -1 + 1j])), atol=1e-12)


def test_sampled_cost_is_exact_for_zoh():
    """x_nᵀQd x_n + 2x_nᵀNd u + uᵀRd u equals the integral of the continuous cost over a period."""
    from scipy.integrate import solve_ivp

    A, B, Q, R, T = A_DI, B_DI, np.diag([1.0, 0.5]), np.array([[2.0]]), 0.3
    Qd, Rd, Nd = design.sampled_cost(A, B, Q, R, T)
    x0, u = np.array([0.7, -0.2]), np.array([0.4])

    def f(t, z):
        x = z[:2]
        return np.concatenate([A @ x + B @ u, [x @ Q @ x + u @ R @ u]])

    sol = solve_ivp(f, (0, T), np.concatenate([x0, [0.0]]), rtol=1e-12, atol=1e-14)
    exact = sol.y[2, -1]
    assert x0 @ Qd @ x0 + 2 * x0 @ Nd @ u + u @ Rd @ u == pytest.approx(exact, rel=1e-9)


def test_process_noise_covariance_limits():
    A = np.array([[0.0, 1.0], [2.0, -0.3]])
    Qd = design.process_noise_covariance(A, np.eye(2), np.diag([1.0, 2.0]), 1e-4)
    np.testing.assert_allclose(Qd, np.diag([1.0, 2.0]) * 1e-4, rtol=1e-3, atol=1e-7)  # ≈ W·T
    Qd0 = design.process_noise_covariance(np.zeros((2, 2)), np.eye(2), np.eye(2), 0.5)
    np.testing.assert_allclose(Qd0, 0.5 * np.eye(2), atol=1e-14)             # exact for A = 0


# ---- refused input, one test per class, with its message -----------------------------------------
@pytest.mark.parametrize(
    ("call", "exc", "message"),
    [
        (lambda: design.lqr(A_DI, B_DI, np.eye(3), 1.0), ShapeError,
         "Incompatible dimensions of Q; expected (2, 2) but found (3, 3)"),
        (lambda: design.lqr(A_DI, np.ones((3, 1)), np.eye(2), 1.0), ShapeError,
         "Incompatible dimensions of B; expected (2, 1) but found (3, 1)"),
        (lambda: design.lqr(A_DI, B_DI, [[1, 0.5], [0, 1]], 1.0), DesignError,
         "Q: must be symmetric"),
        (lambda: design.lqr(A_DI, B_DI, [[1, 0], [0, -1]], 1.0), DesignError,
         "Q: must be positive semi-definite; smallest eigenvalue -1"),
        (lambda: design.lqr(A_DI, B_DI, np.eye(2), 0.0), DesignError,
         "R: must be positive definite"),
        (lambda: design.kalman(A_DI, np.eye(2), C_DI, np.eye(2), -1.0), DesignError,
         "V: must be positive definite"),
        (lambda: design.kalman(A_DI, np.eye(2), C_DI, -np.eye(2), 1.0), DesignError,
         "W: must be positive semi-definite"),
        (lambda: design.lqr([[1.0, 0], [0, 2.0]], [[1.0], [0.0]], np.eye(2), 1.0), DesignError,
         "(A, B): pair is not stabilisable (uncontrollable unstable mode(s) 2"),
        (lambda: design.kalman([[1.0, 0], [0, -1.0]], np.eye(2), [[0.0, 1.0]], np.eye(2), 1.0),
         DesignError, "(A, C): pair is not detectable (unobservable unstable mode(s) 1"),
        (lambda: design.dkalman([[1.5, 0], [0, 0.5]], np.eye(2), [[0.0, 1.0]], np.eye(2), 1.0),
         DesignError, "(Phi, C): pair is not detectable (unobservable non-decaying mode(s) 1.5"),
        (lambda: design.luenberger(A_DI, C_DI, [-1.0]), ShapeError,
         "poles: expected 2 poles, found 1"),
        (lambda: design.luenberger(A_DI, C_DI, [-1 + 1j, -2.0]), DesignError,
         "poles: pole -1+1j has no complex-conjugate partner"),
        (lambda: design.luenberger(A_DI, C_DI, [-1.0, -1.0]), DesignError,
         "poles: a pole is repeated 2 times but rank C is only 1"),
        (lambda: design.lqr(A_DI, B_DI, [[1, 0], [0, np.nan]], 1.0), DesignError,
         "Q: contains non-finite entries"),
        (lambda: design.dlqr(PHI_OGATA, GAMMA_OGATA, np.eye(2), 1.0, alpha=0.5), DesignError,
         "alpha: expected a finite number ≥ 1"),
        (lambda: design.finite_horizon_dlqr(PHI_OGATA, GAMMA_OGATA, np.eye(2), 1.0, np.eye(2), 0),
         DesignError, "horizon: expected an integer ≥ 1"),
        (lambda: design.dluenberger(PHI_OGATA, [[1.0, 0.0]], [0.1, 0.2], form="filter"),
         DesignError, "form: expected 'current' or 'predictor'"),
        (lambda: design.bryson([0.0, 1.0], [1.0]), DesignError, "max_state: every entry"),
    ],
)
def test_refused_inputs(call, exc, message):
    with pytest.raises(exc) as info:
        call()
    assert str(info.value).startswith(message), str(info.value)
    assert isinstance(info.value, ValueError) and isinstance(info.value, PendulumLQGError)
    assert "\n" not in str(info.value)
