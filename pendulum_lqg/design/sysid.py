"""Nominal system identification: a linear model from logged (y, u) episodes by least squares.

The "nominal" (certainty-equivalent) recipe of Dean et al. and Recht's *A tour of reinforcement
learning*: fit a model to data by least squares, then design as if it were true. Here the
controller sees only ``y = C x + v`` (``C = [I₂ 0]``), so the state is not logged; the fit is the
open-loop Markov-parameter regression of Oymak & Ozay (2019), then a structured model fit:

1. **Markov parameters by least squares** (:func:`markov_parameters`). Many short episodes start
   from the same initial state ``x₀`` and are driven by a known random input. For ``k < H``,
   ``y_k = m_k + Σ_{j=1..k} G_j u_{k−j} + e_k`` with ``G_j = C Φ^{j−1} Γ`` and ``m_k = C Φ^k x₀``
   (a free intercept per time ``k``); ``e_k`` collects the process and measurement noise, which
   are independent of the input, so the least-squares estimate is unbiased however noisy ``y`` is
   (an ARX fit ``y_k ≈ Σ a_j y_{k−j} + …`` is not: its regressors carry the measurement noise).
2. **A structured fit of the Markov parameters** (:func:`fit_structured`). The cost weights ``Q``
   act on ``x = [p, θ, ṗ, θ̇] = [y, ẏ]``, so the model is sought in that basis, the structure of
   any mechanical system whose sensors read its positions: ``A = [[0, I], [A₂₁, A₂₂]]``,
   ``B = [0; b]``, ``C = [I 0]``, with no force depending on the cart's position (a level
   track: translation invariance), 8 numbers, sampled by ZOH, fitted to ``G_1 … G_{H−1}`` by
   nonlinear least squares. (An unstructured Ho–Kalman realisation is ill-posed here: over
   the half second an open-loop episode lasts, all four poles sit near ``z = 1`` and the fourth
   Hankel singular value is far below the estimates' noise.)
3. **Noise covariances by least squares** (:func:`noise_covariances`): the regression's residuals
   ``r_k = C Σ_{i<k} Φ^{k−1−i} w_i + v_k`` have ``E[r_k r_lᵀ] = C Φ^{k−l} P_l Cᵀ + δ_{kl} V``
   (``P_l = Σ_{i<l} Φ^i W Φ^{iᵀ}``), linear in a per-period process covariance ``W = q·I`` and a
   diagonal measurement covariance ``V``: a non-negative least-squares fit of the residuals'
   covariances at lags 0 and 1 over ``k``. (``x₀`` is taken as the same in every episode, as the
   suites draw it, ``x0_std = 0``.)

:func:`lqg_gains` then designs the LQG controller on the identified model with the project's design
functions, exactly as the built-in ``dlqr+kalman`` is designed on the true one.
"""

from __future__ import annotations

import msgspec
import numpy as np
from scipy.optimize import nnls

from pendulum_lqg import design
from pendulum_lqg.errors import ConfigError

__all__ = ["IdentifiedModel", "fit_structured", "identify", "lqg_gains", "markov_parameters",
           "noise_covariances", "structured_model", "structured_size"]


class IdentifiedModel(msgspec.Struct, frozen=True):
    """A model identified from data, in the basis ``x = [y, ẏ]``.

    Attributes
    ----------
    Phi, Gamma, C : the discrete model ``x⁺ = Φx + Γu + w``, ``y = Cx + v``
    A, B : its continuous generator (``Φ = e^{AT}``, ``Γ = ∫₀ᵀ e^{As} ds B``)
    W : per-period process-noise covariance (``q·I``), V : measurement-noise covariance (diagonal)
    markov : (H−1, p, m) the least-squares Markov parameters ``G_1 …``
    dt : the sample period T [s]
    """

    Phi: np.ndarray
    Gamma: np.ndarray
    C: np.ndarray
    A: np.ndarray
    B: np.ndarray
    W: np.ndarray
    V: np.ndarray
    markov: np.ndarray
    dt: float


def _regressors(U: np.ndarray) -> np.ndarray:
    """(E, H, H−1, m): row (e, k) holds ``u_{k−1}, …, u_{k−H+1}`` (zeros before the start)."""
    E, H, m = U.shape
    out = np.zeros((E, H, H - 1, m))
    for j in range(1, H):
        out[:, j:, j - 1, :] = U[:, :H - j, :]
    return out


def markov_parameters(Y: np.ndarray, U: np.ndarray, valid: np.ndarray,
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The least-squares ``G_1 … G_{H−1}`` (H−1, p, m), intercepts ``m_k`` (H, p) and residuals
    (E, H, p; 0 where not ``valid``) of episodes ``Y`` (E, H, p) driven by ``U`` (E, H, m) from the
    same initial state; ``valid`` (E, H) marks the samples logged before an episode ended."""
    E, H, p = Y.shape
    m = U.shape[2]
    if H < 3 or valid.shape != (E, H):
        raise ConfigError(f"markov_parameters: expected episodes of ≥ 3 samples and a valid mask "
                          f"of shape {(E, H)}, got {H} samples and {valid.shape}")
    # the intercepts by Frisch–Waugh: regressors and targets centred per time k (over the episodes
    # valid at k), the same least squares as with a free m_k per k, without its H columns
    X = _regressors(U).reshape(E, H, (H - 1) * m)
    count = np.maximum(valid.sum(axis=0), 1)[:, None]
    x_mean = (X * valid[..., None]).sum(axis=0) / count
    y_mean = (Y * valid[..., None]).sum(axis=0) / count
    Xc, Yc = (X - x_mean)[valid], (Y - y_mean)[valid]
    theta, *_ = np.linalg.lstsq(Xc, Yc, rcond=None)
    residuals = np.zeros_like(Y)
    residuals[valid] = Yc - Xc @ theta
    intercepts = y_mean - x_mean @ theta
    G = theta.reshape(H - 1, m, p).transpose(0, 2, 1)
    return G, intercepts, residuals


def structured_model(params: np.ndarray, p: int, dt: float,
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(Φ, Γ, C, A, B)`` of the mechanical structure ``A = [[0, I], [A₂₁, A₂₂]]``,
    ``B = [0; b]``, ``C = [I 0]`` from ``params = [A₂₁ without its first column, A₂₂, b]``
    (row-major; ``2p²`` numbers, :func:`structured_size`), ZOH at ``dt``. The first column of
    ``A₂₁`` is 0: a cart on a level track is translation invariant, no force depends on its
    position ``p``. ``A`` and ``B`` are affine in ``params``."""
    A = np.zeros((2 * p, 2 * p))
    A[:p, p:] = np.eye(p)
    A[p:, 1:p] = params[:p * (p - 1)].reshape(p, p - 1)
    A[p:, p:] = params[p * (p - 1):p * (2 * p - 1)].reshape(p, p)
    B = np.zeros((2 * p, 1))
    B[p:, 0] = params[p * (2 * p - 1):]
    Phi, Gamma = design.zoh(A, B, dt)
    C = np.hstack([np.eye(p), np.zeros((p, p))])
    return Phi, Gamma, C, A, B


def structured_size(p: int) -> int:
    """The number of parameters of :func:`structured_model` with ``p`` outputs: ``2p²``."""
    return 2 * p * p


def _markov_of(Phi: np.ndarray, Gamma: np.ndarray, C: np.ndarray, count: int) -> np.ndarray:
    out, x = [], Gamma
    for _ in range(count):
        out.append(C @ x)
        x = Phi @ x
    return np.array(out)


def fit_structured(G: np.ndarray, m: np.ndarray, dt: float, u_rms: float,
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(Φ, Γ, C, A, B)`` of the model in the basis ``[y, ẏ]`` (the mechanical structure of
    :func:`structured_model`: the second half of the state is the derivative of ``y``) whose Markov parameters
    and free response fit the regression's ``G`` (N, p, 1) and intercepts ``m`` (N+1, p) best in
    least squares, with the initial state ``[m_0, ẏ_0]`` (``ẏ_0`` fitted too).

    Both are weighted as responses: ``m_k − C Φ^k x₀`` and ``u_rms · (G_j − C Φ^{j−1} Γ)`` (a
    Markov parameter's error is the response error over the input's rms). The free response
    carries most of what the short episodes say about ``A₂₁`` (the pole falls from ``x₀`` whatever
    the input), the Markov parameters what they say about ``b``. Levenberg–Marquardt starts from
    the double integrator ``A₂₁ = A₂₂ = 0``, ``ẏ_0 = 0``, ``b`` from ``G_j ≈ (j − ½) T² b``."""
    from scipy.optimize import least_squares

    N, p, _ = G.shape
    first = min(N, 10)
    lever = (np.arange(1, first + 1) - 0.5) * dt * dt
    b0 = lever @ G[:first, :, 0] / (lever @ lever)
    start = np.concatenate([np.zeros(p * (2 * p - 1)), b0, np.zeros(p)])
    scale = float(np.abs(m - m[0]).max() + u_rms * np.abs(G).max()) or 1.0

    def residual(params: np.ndarray) -> np.ndarray:
        Phi, Gamma, C, _, _ = structured_model(params[:-p], p, dt)
        x0 = np.concatenate([m[0], params[-p:]])
        free = _markov_of(Phi, x0[:, None], C, N + 1)[:, :, 0]
        forced = _markov_of(Phi, Gamma, C, N)
        return np.concatenate([(free - m).ravel(), u_rms * (forced - G).ravel()]) / scale

    fit = least_squares(residual, start, method="lm", x_scale="jac")
    return structured_model(fit.x[:-p], p, dt)


def noise_covariances(Phi: np.ndarray, C: np.ndarray, residuals: np.ndarray, valid: np.ndarray,
                      *, floor: float = 1e-9) -> tuple[np.ndarray, np.ndarray]:
    """``(W, V)``, ``W = q·I`` and ``V`` diagonal, fitting the residuals' covariances at lags 0
    and 1 (see the module docstring) by non-negative least squares; ``q`` and ``V``'s entries are
    at least ``floor`` (a filter needs ``V > 0``, and a zero ``W`` would trust the model forever).
    One process-noise level: the short episodes cannot tell the noise of each state apart."""
    _, H, p = residuals.shape
    n = Phi.shape[0]
    powers = [np.eye(n)]
    for _ in range(H):
        powers.append(Phi @ powers[-1])
    # P_l per unit diagonal entry i of W: Σ_{j<l} Φ^j e_i e_iᵀ Φ^{jᵀ}
    P = np.zeros((H, n, n, n))
    for k in range(1, H):
        cols = powers[k - 1]
        P[k] = P[k - 1] + np.einsum("ai,bi->iab", cols, cols)
    rows, targets = [], []
    for lag in (0, 1):
        for k in range(lag, H):
            both = valid[:, k] & valid[:, k - lag]
            if both.sum() < 10:
                continue
            emp = residuals[both, k].T @ residuals[both, k - lag] / both.sum()
            feats = np.einsum("ab,ibc,dc->iad", C @ powers[lag], P[k - lag], C)
            for a in range(p):
                for b in range(p):
                    v = np.zeros(p)
                    if lag == 0 and a == b:
                        v[a] = 1.0
                    rows.append(np.concatenate([[feats[:, a, b].sum()], v]))
                    targets.append(emp[a, b])
    coef, _ = nnls(np.array(rows), np.array(targets))
    return max(coef[0], floor) * np.eye(n), np.diag(np.maximum(coef[1:], floor))


def identify(Y: np.ndarray, U: np.ndarray, valid: np.ndarray, dt: float) -> IdentifiedModel:
    """The model of the episodes ``Y`` (E, H, p), ``U`` (E, H, 1) (see :func:`markov_parameters`)
    in the basis ``[y, ẏ]`` (:func:`fit_structured`), with its noise covariances."""
    G, m, residuals = markov_parameters(Y, U, valid)
    u_rms = float(np.sqrt(np.mean(U[valid] ** 2)))
    Phi, Gamma, C, A, B = fit_structured(G, m, dt, u_rms)
    W, V = noise_covariances(Phi, C, residuals, valid)
    return IdentifiedModel(Phi=Phi, Gamma=Gamma, C=C, A=A, B=B, W=W, V=V, markov=G, dt=float(dt))


def lqg_gains(model: IdentifiedModel, Q: np.ndarray, R: np.ndarray,
              ) -> tuple[np.ndarray, np.ndarray]:
    """``(K, L)`` of the LQG design on ``model``: the discrete LQR of the exact sampled cost
    (:func:`~pendulum_lqg.design.sampled_cost` of ``J = ∫ xᵀQx + uᵀRu dt``) and the steady-state
    Kalman filter gain (current form) for the model's ``W`` and ``V`` — the design
    :func:`~pendulum_lqg.policies.lqg.design_policy` makes for ``dlqr+kalman``."""
    Qd, Rd, Nd = design.sampled_cost(model.A, model.B, Q, R, model.dt)
    K = design.dlqr(model.Phi, model.Gamma, Qd, Rd, N=Nd).K
    L = design.dkalman(model.Phi, np.eye(model.Phi.shape[0]), model.C, model.W, model.V).L
    return K, L
