"""The prediction-error fit of the innovations form (pendulum_lqg.design.pem) on a known linear
plant simulated in closed loop (plain numpy): its Jacobian against finite differences, the
predictor-to-filter gain relation against the Kalman design, and the recovery of the plant, the
noise model and a near-optimal controller from closed-loop data."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import solve_discrete_lyapunov

from pendulum_lqg import design
from pendulum_lqg.design import pem
from pendulum_lqg.design.sysid import structured_model

DT = 0.01
#: a cart-pole-like plant in the basis [y, ẏ]: p̈ = a θ + d ṗ + b_p u, θ̈ = c θ + e θ̇ + b_θ u
TRUE = np.array([-0.72, 15.8, -0.5, 0.0, 0.0, -0.2, 0.98, -1.46])
W, V = 4e-6 * np.eye(4), 0.01 * np.eye(2)


def _lqg(params: np.ndarray, W: np.ndarray, V: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    Phi, Gamma, C, A, B = structured_model(params, 2, DT)
    Qd, Rd, Nd = design.sampled_cost(A, B, np.eye(4), np.eye(1), DT)
    return design.dlqr(Phi, Gamma, Qd, Rd, N=Nd).K, design.dkalman(Phi, np.eye(4), C, W, V).L


def simulate(episodes: int, periods: int, *, dither: float, seed: int,
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Closed-loop episodes of the true plant under a cautious LQG (its Kalman filter designed
    for 100 × W) plus white force ``dither``, from x₀ = [0, 0.1, 0, 0]."""
    Phi, Gamma, C, _, _ = structured_model(TRUE, 2, DT)
    K, L = _lqg(TRUE, 100 * W, V)
    rng = np.random.default_rng(seed)
    x, xh = np.tile([0.0, 0.1, 0.0, 0.0], (episodes, 1)), np.zeros((episodes, 4))
    u = np.zeros((episodes, 1))
    Y, U = np.zeros((episodes, periods, 2)), np.zeros((episodes, periods, 1))
    for k in range(periods):
        Y[:, k] = x @ C.T + rng.standard_normal((episodes, 2)) @ np.sqrt(V)
        prior = xh @ Phi.T + u @ Gamma.T
        xh = prior + (Y[:, k] - prior @ C.T) @ L.T
        u = -xh @ K.T + dither * rng.standard_normal((episodes, 1))
        U[:, k] = u
        x = x @ Phi.T + u @ Gamma.T + rng.standard_normal((episodes, 4)) @ np.sqrt(W)
    return Y, U, np.ones((episodes, periods), dtype=bool)


def stationary_cost(params: np.ndarray, controller: dict) -> float:
    """The stationary cost per period ``E[xᵀQ_d x + 2xᵀN_d u + uᵀR_d u]`` of a state-space
    controller of ``z = [y, u_{k−1}]`` (:func:`~pendulum_lqg.scoreboard.linear.lqg_state_space`
    form) on the true plant, from one discrete Lyapunov equation of the loop."""
    Phi, Gamma, C, A, B = structured_model(TRUE, 2, DT)
    Qd, Rd, Nd = design.sampled_cost(A, B, np.eye(4), np.eye(1), DT)
    Ac, Bc, Cc, Dc = (np.asarray(controller[k]) for k in "ABCD")
    q = Ac.shape[0]
    urow = np.hstack([Dc[:, :2] @ C, Cc, Dc[:, 2:]])            # u = urow s + D_y v
    M = np.vstack([np.hstack([Phi, np.zeros((4, q + 1))]) + Gamma @ urow,
                   np.hstack([Bc[:, :2] @ C, Ac, Bc[:, 2:]]), urow])
    noise = np.zeros((5 + q, 6))
    noise[:4, :4], noise[:4, 4:] = np.eye(4), Gamma @ Dc[:, :2]
    noise[4:4 + q, 4:], noise[4 + q:, 4:] = Bc[:, :2], Dc[:, :2]
    assert np.abs(np.linalg.eigvals(M)).max() < 1, "the loop is unstable"
    S = solve_discrete_lyapunov(M, noise @ np.block([[W, np.zeros((4, 2))],
                                                     [np.zeros((2, 4)), V]]) @ noise.T)
    X = np.hstack([np.eye(4), np.zeros((4, q + 1))])
    Euu = urow @ S @ urow.T + Dc[:, :2] @ V @ Dc[:, :2].T
    return float(np.trace(Qd @ X @ S @ X.T) + np.trace(Rd @ Euu)
                 + 2 * np.trace(Nd.T @ X @ S @ urow.T))


def _controller(Phi, Gamma, A, B, L) -> dict:
    from pendulum_lqg.scoreboard.linear import lqg_state_space

    Qd, Rd, Nd = design.sampled_cost(A, B, np.eye(4), np.eye(1), DT)
    K = design.dlqr(Phi, Gamma, Qd, Rd, N=Nd).K
    return lqg_state_space(Phi, Gamma, np.hstack([np.eye(2), np.zeros((2, 2))]), K, L)


def test_the_jacobian_is_the_finite_difference_of_the_innovations():
    """Two paths to ∂e/∂ϑ: the sensitivity recursion's JᵀJ and Jᵀe against central differences
    of the predictor, with a delay, weights, a gap of missing samples and an ended episode."""
    rng = np.random.default_rng(0)
    Y = 0.1 * rng.standard_normal((3, 120, 2))
    U = rng.standard_normal((3, 120, 1))
    valid = np.ones((3, 120), dtype=bool)
    valid[1, 90:] = False
    Y[2, 40:50] = np.nan
    params = TRUE + 0.1 * rng.standard_normal(8)
    K_p, x0 = 0.05 * rng.standard_normal((4, 2)), 0.1 * rng.standard_normal(4)
    layout = pem.PEMLayout(np.ones(8, dtype=bool), 4, 2)
    data, w = pem._data(Y, U, valid, 1), np.array([3.0, 7.0])

    def residuals(theta):
        pr, K, x = layout.unpack(theta, params, K_p, x0)
        Phi, Gamma, C, _, _ = structured_model(pr, 2, DT)
        return (pem._predict(Phi, Gamma, C, K, x, data) * w).ravel()

    theta = layout.pack(params, K_p, x0)
    J = np.array([(residuals(theta + h) - residuals(theta - h)) / 2e-6
                  for h in 1e-6 * np.eye(theta.size)]).T
    Phi, Gamma, C, _, _ = structured_model(params, 2, DT)
    dPhi, dGamma = pem.structured_derivatives(params, 2, DT)
    _, JtJ, Jte = pem._normal_equations(Phi, Gamma, C, K_p, x0, data, w, layout, dPhi, dGamma)
    np.testing.assert_allclose(JtJ, J.T @ J, rtol=1e-6, atol=1e-6 * np.abs(JtJ).max())
    np.testing.assert_allclose(Jte, J.T @ residuals(theta), rtol=1e-6,
                               atol=1e-6 * np.abs(Jte).max())


def test_the_filter_gain_of_the_kalman_predictor_gain_is_the_kalman_filter_gain():
    Phi, _, C, _, _ = structured_model(TRUE, 2, DT)
    kf = design.dkalman(Phi, np.eye(4), C, W, V)
    np.testing.assert_allclose(pem.filter_gain(Phi, kf.L_pred), kf.L, rtol=1e-10, atol=1e-14)


def test_missing_samples_and_ended_episodes_have_no_innovation():
    Y, U, valid = simulate(2, 60, dither=1.0, seed=3)
    Y[0, 10:13] = np.nan
    valid[1, 40:] = False
    Phi, Gamma, C, _, _ = structured_model(TRUE, 2, DT)
    K_p = design.dkalman(Phi, np.eye(4), C, W, V).L_pred
    e = pem.innovations(Phi, Gamma, C, K_p, np.array([0, 0.1, 0, 0]), Y, U, valid)
    assert np.isnan(e[0, 10:13]).all() and np.isnan(e[1, 40:]).all()
    assert np.isfinite(e[0, :10]).all() and np.isfinite(e[0, 13:]).all()
    # over the gap the predictor runs open loop: x̂₁₃ = Φ³ x̂₁₀ + Σ Φ^{12−j} Γ u_j (+ K_p e₁₀)
    x = np.array([0, 0.1, 0, 0.0])
    for k in range(10):
        x = Phi @ x + Gamma[:, 0] * U[0, k, 0] + K_p @ (Y[0, k] - C @ x)
    for k in range(10, 13):
        x = Phi @ x + Gamma[:, 0] * U[0, k, 0]
    np.testing.assert_allclose(e[0, 13], Y[0, 13] - C @ x, rtol=1e-12)


@pytest.fixture(scope="module")
def recovered():
    """The fit of 20 closed-loop episodes of 500 periods (10 000 samples), dither 3 N, from a
    start 20 % off on the stiffness terms and the input gains, without the velocity terms."""
    Y, U, valid = simulate(20, 500, dither=3.0, seed=0)
    start = TRUE * np.array([1.2, 1.2, 0, 0, 0, 0, 0.8, 0.8])
    Phi0, _, C, _, _ = structured_model(start, 2, DT)
    K_p0 = design.dkalman(Phi0, np.eye(4), C, W, V).L_pred
    return pem.fit_innovations(Y, U, valid, DT, params=start, K_p=K_p0, x0=np.zeros(4),
                               weights=np.array([10.0, 10.0]), atol=0.05)


def test_closed_loop_data_recover_the_noise_model(recovered):
    """The innovations' covariance within 3 % of the true predictor's ``C M Cᵀ + V``, the
    predictor gain within 0.05 of the true Kalman predictor gain (its entries reach 0.3)."""
    Phi, _, C, _, _ = structured_model(TRUE, 2, DT)
    kf = design.dkalman(Phi, np.eye(4), C, W, V)
    np.testing.assert_allclose(np.diag(recovered.S), np.diag(C @ kf.M @ C.T + V), rtol=0.03)
    assert np.abs(recovered.K_p - kf.L_pred).max() < 0.05


def test_closed_loop_data_recover_the_plant_and_a_near_optimal_controller(recovered):
    """The unstable pole within 5 %; the certainty-equivalent LQG (DLQR of the sampled cost on
    the fit, its filter gain Φ⁻¹K_p) within 3 % of the optimal stationary cost on the true
    plant."""
    Phi, Gamma, _, A, B = structured_model(TRUE, 2, DT)
    pole = np.linalg.eigvals(A).real.max()
    assert abs(np.linalg.eigvals(recovered.A).real.max() - pole) < 0.05 * pole
    optimum = stationary_cost(TRUE, _controller(Phi, Gamma, A, B, _lqg(TRUE, W, V)[1]))
    m = recovered
    learned = stationary_cost(TRUE, _controller(m.Phi, m.Gamma, m.A, m.B, m.L))
    assert optimum <= learned < 1.03 * optimum
    doc = m.to_dict()
    assert doc["delay"] == 0 and len(doc["params"]) == 8 and np.shape(doc["L"]) == (4, 2)
