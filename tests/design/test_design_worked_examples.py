"""The lecture documents' worked examples not covered elsewhere (docs/tutorials/worked-examples.md).

Franklin's prescribed-degree-of-stability gains (seed 000, Ex. 2), the third-order plant's
observers (seed 000, Ex. 3), the double integrator's LQG compensator and loop transfer recovery
(seed 002), and Ackermann's example solved four ways (seed 004). Ogata's table and the closed-form
double-integrator designs are in test_design.py, Ackermann's function in test_observers.py.
"""

from __future__ import annotations

import math

import control
import numpy as np
import pytest
from scipy.linalg import solve_sylvester

from pendulum_lqg import design
from pendulum_lqg.analysis import margins

SQ2, SQ3 = math.sqrt(2), math.sqrt(3)

# ---- seed 000, Example 2 (Franklin) --------------------------------------------------------------
A_F = np.array([[-0.2, 0.1, 1.0], [-0.05, 0.0, 0.0], [0.0, 0.0, -1.0]])
B_F = np.array([[0.0, 1.0], [0.0, 0.7], [1.0, 0.0]])
TS_F = 0.2
R_F = np.diag([1 / 5**2, 1 / 10**2])
Q_AB, Q_C = np.diag([1 / 2**2, 1.0, 0.0]), np.diag([1 / 2**2, 0.0, 0.0])
FRANKLIN = {"a": (2.4, Q_AB, [[6.8137, -9.7876, 3.7946], [0.9548, 4.9424, 0.1045]]),
            "b": (5.0, Q_AB, [[3.5006, -5.0086, 2.3797], [1.1031, 4.3946, 0.1646]]),
            "c": (5.0, Q_C, [[1.9570, -2.6986, 1.7547], [2.9805, 0.6968, 0.5816]])}


def _franklin(case: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    ts, Q, _ = FRANKLIN[case]
    Phi, Gamma = design.zoh(A_F, B_F, TS_F)
    alpha = 100 ** (TS_F / ts)
    return Phi, Gamma, design.dlqr(Phi, Gamma, Q, R_F, alpha=alpha).K, alpha


def test_franklin_sampled_plant_matches_the_printed_matrices():
    Phi, Gamma = design.zoh(A_F, B_F, TS_F)
    np.testing.assert_allclose(Phi, [[.9607, .0196, .1776], [-.0098, .9999, -.0009], [0, 0, .8187]],
                               atol=5e-5)
    np.testing.assert_allclose(Gamma, [[.0185, .1974], [-.0001, .1390], [.1813, 0]], atol=5e-5)


@pytest.mark.parametrize("case", ["a", "b", "c"])
def test_franklin_pincer_gains_match_the_printed_ones(case):
    Phi, Gamma, K, alpha = _franklin(case)
    np.testing.assert_allclose(K, FRANKLIN[case][2], atol=5e-5)
    assert alpha == pytest.approx({"a": 1.4678, "b": 1.2023, "c": 1.2023}[case], abs=5e-5)
    assert np.abs(np.linalg.eigvals(Phi - Gamma @ K)).max() < 1 / alpha


def _response(case: str, steps: int = 200) -> tuple[np.ndarray, np.ndarray]:
    Phi, Gamma, K, _ = _franklin(case)
    x, X, U = np.array([1.0, 0.0, 0.0]), [], []
    for _ in range(steps):
        u = -K @ x
        X.append(x)
        U.append(u)
        x = Phi @ x + Gamma @ u
    return np.array(X), np.array(U)


def _settling(x: np.ndarray) -> float:
    outside = np.nonzero(np.abs(x) > 0.01)[0]
    return TS_F * (outside[-1] + 1) if outside.size else 0.0


def test_franklin_claims_about_the_three_designs_hold():
    (_, Ua), (Xb, Ub), (_, Uc) = _response("a"), _response("b"), _response("c")
    assert np.abs(Ua[:, 0]).max() > 5                                   # (a) breaks |u₁| < 5
    assert np.abs(Ub[:, 0]).max() < 5 and np.abs(Ub[:, 1]).max() < 10    # (b) meets every spec
    assert np.abs(Xb[:, 0]).max() <= 2 and np.abs(Xb[:, 1]).max() < 1
    assert _settling(Xb[:, 0]) < 2.4 and _settling(Xb[:, 1]) < 8
    effort_b, effort_c = np.sum(Ub**2 @ np.diag(R_F)), np.sum(Uc**2 @ np.diag(R_F))
    assert effort_c < effort_b                                          # (c) lowers Σ uᵀRu …
    assert np.abs(Uc[:, 1]).max() > np.abs(Ub[:, 1]).max()              # … but asks more of u₂


# ---- seed 000, Example 3: G(s) = 70/((s+2)(s+5)(s+7)) ---------------------------------------------
A_3 = np.array([[-14.0, -59.0, -70.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
B_3 = np.array([[70.0], [0.0], [0.0]])
C_3 = np.array([[0.0, 0.0, 1.0]])
PSI_3 = np.array([[1.0], [0.0], [0.0]])
T_3 = 0.02


def test_third_order_plant_is_the_documents_transfer_function():
    num, den = control.ss2tf(A_3, B_3, C_3, 0).num[0][0], control.ss2tf(A_3, B_3, C_3, 0).den[0][0]
    np.testing.assert_allclose(np.trim_zeros(np.round(num, 9)), [70.0])
    np.testing.assert_allclose(den, np.poly([-2, -5, -7]))


def test_third_order_luenberger_time_varying_and_steady_kalman():
    Phi, _ = design.zoh(A_3, B_3, T_3)
    s = np.array([-21, -22 + 2j, -22 - 2j])
    luen = design.dluenberger(Phi, C_3, s, form="current", dt=T_3)
    np.testing.assert_allclose(np.real(np.poly(Phi - luen.L @ C_3 @ Phi)),
                               np.real(np.poly(np.exp(s * T_3))), atol=1e-12)
    W, V = np.array([[0.01]]), np.array([[0.01]])
    tv = design.kalman_tv(Phi, PSI_3, C_3, W, V, np.eye(3), 300)
    kf = design.dkalman(Phi, PSI_3, C_3, W, V)
    np.testing.assert_allclose(tv.L[0].ravel(), [0.0, 0.0, 1 / 1.01], atol=1e-12)  # M₀ = I
    np.testing.assert_allclose(tv.L[-1], kf.L, atol=1e-9)
    # MATLAB's dlqe gives the filter gain L; python-control's gives the predictor gain ΦL
    np.testing.assert_allclose(control.dlqe(Phi, PSI_3, C_3, W, V)[0], Phi @ kf.L, atol=1e-10)
    assert np.abs(np.linalg.eigvals(Phi - kf.L @ C_3 @ Phi)).max() < 1


# ---- seed 002: the double integrator's LQG compensator and LTR ---------------------------------
A_DI = np.array([[0.0, 1.0], [0.0, 0.0]])
B_DI = np.array([[0.0], [1.0]])
C_DI = np.array([[1.0, 0.0]])


def _di_gains() -> tuple[np.ndarray, np.ndarray]:
    K = design.lqr(A_DI, B_DI, C_DI.T @ C_DI, 1.0).K
    L = design.kalman(A_DI, np.eye(2), C_DI, np.eye(2), 1.0).L
    return K, L


def test_double_integrator_lqg_compensator_is_the_printed_one_before_rounding():
    K, L = _di_gains()
    tf = control.ss2tf(margins.lqg_compensator(A_DI, B_DI, C_DI, K, L))
    num, den = tf.num[0][0], tf.den[0][0]
    # 3.14(s + 0.31)/((s + 1.57)² + 1.4²) in the document: gain √2 + √3, zero 1/(√2 + √3)
    assert num[0] == pytest.approx(SQ2 + SQ3, abs=1e-9) and num[0] == pytest.approx(3.146, abs=5e-4)
    assert np.roots(num)[0] == pytest.approx(-1 / (SQ2 + SQ3), abs=1e-9)
    assert np.roots(num)[0] == pytest.approx(-0.318, abs=5e-4)
    poles = np.roots(den)
    np.testing.assert_allclose(poles.real, [-1.5731, -1.5731], atol=5e-5)
    np.testing.assert_allclose(np.abs(poles.imag), [1.4053, 1.4053], atol=5e-5)


def test_ltr_phase_margins_at_q_1_100_1000_approach_the_lq_margin():
    K, L = _di_gains()
    omega = margins.frequency_grid()
    lq = margins.loop_margins(margins.lq_loop(A_DI, B_DI, K), omega)
    wc = math.sqrt(1 + SQ2)          # |1 + √2 jω| = ω² at the crossover
    assert lq.omega_crossover == pytest.approx(wc, rel=1e-4)
    assert lq.phase_margin_deg == pytest.approx(math.degrees(math.atan(SQ2 * wc)), abs=1e-3)
    points = margins.ltr_sweep(A_DI, B_DI, C_DI, K, np.eye(1), [1, 100, 1000], omega=omega)
    pm = [p.margins.phase_margin_deg for p in points]
    np.testing.assert_allclose(pm, [32.75, 55.07, 61.79], atol=5e-3)
    assert pm[2] < lq.phase_margin_deg
    errors = [p.recovery_error for p in points]
    assert errors[0] > errors[1] > errors[2]
    seed = margins.loop_margins(margins.loop_through(margins.lqg_compensator(A_DI, B_DI, C_DI, K, L),
                                                     margins.plant(A_DI, B_DI, C_DI)), omega)
    assert seed.phase_margin_deg == pytest.approx(35.75, abs=5e-3)     # LQ has the larger margins


# ---- seed 004: L = [3, 17, 5] by the observable canonical form and a Sylvester equation ----------
A_4 = np.array([[-1.0, 1.0, -2.0], [0.0, -1.0, 1.0], [0.0, 0.0, -1.0]])
C_4 = np.array([[1.0, 0.0, 0.0]])


def test_ackermann_example_by_coefficients_canonical_form_and_sylvester():
    desired = np.real(np.poly([-2, -2 + 2j, -2 - 2j]))
    np.testing.assert_allclose(desired, [1, 6, 16, 16])
    a = np.real(np.poly(A_4))
    Ob = np.vstack([C_4, C_4 @ A_4, C_4 @ A_4 @ A_4])      # observability matrix
    # coefficient matching: det(sI − A + LC) is affine in L
    def char(L):
        return np.real(np.poly(A_4 - np.reshape(L, (3, 1)) @ C_4))[1:]
    J = np.column_stack([char(e) - char(np.zeros(3)) for e in np.eye(3)])
    L_match = np.linalg.solve(J, desired[1:] - char(np.zeros(3)))
    # observable canonical form: companion Ac with y = [0 0 1] z, x = S z, L = S (ã − a)
    Ac = np.column_stack([[0, 1, 0], [0, 0, 1], -a[:0:-1]]).astype(float)
    c = np.eye(3)[2]
    S = np.linalg.solve(Ob, np.vstack([c, c @ Ac, c @ Ac @ Ac]))
    np.testing.assert_allclose(np.linalg.solve(S, A_4 @ S), Ac, atol=1e-12)
    L_canon = S @ (desired - a)[:0:-1]
    # Sylvester: −F T + T A = L̄ C with eig(F) the observer poles, L = T⁻¹ L̄
    F = np.array([[-2.0, 0.0, 0.0], [0.0, -2.0, 2.0], [0.0, -2.0, -2.0]])
    Lb = np.array([[1.0], [0.0], [1.0]])
    T = solve_sylvester(-F, A_4, Lb @ C_4)
    L_syl = np.linalg.solve(T, Lb).ravel()
    for L in (L_match, L_canon, L_syl):
        np.testing.assert_allclose(L, [3.0, 17.0, 5.0], atol=1e-9)
