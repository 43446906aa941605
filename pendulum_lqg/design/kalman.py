"""Kalman filters: continuous Kalman–Bucy, discrete steady-state (both gain forms), time-varying.

Noise conventions (docs/theory.md §3.7): the continuous design takes spectral densities ``W`` (of ``w`` in
``ẋ = Ax + Bu + Gw``) and ``V`` (of ``v`` in ``y = Cx + v``), units² · s. The discrete designs take
per-sample covariances ``E{w wᵀ} = W`` (of ``w[n]`` in ``x[n+1] = Φx + Γu + G w[n]``) and
``E{v vᵀ} = V``.
"""

from __future__ import annotations

import msgspec
import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import solve_continuous_are, solve_discrete_are

from pendulum_lqg.design.checks import (
    as_matrix,
    as_square,
    as_weight,
    design_function,
    require_detectable,
    require_noise_reaches_marginal_modes,
    require_stable,
)
from pendulum_lqg.errors import DesignError


class KalmanResult(msgspec.Struct, frozen=True):
    """Continuous Kalman–Bucy filter.

    Attributes
    ----------
    L : (n, p) array, gain in ``x̂̇ = Ax̂ + Bu + L(y − Cx̂)``
    P : (n, n) array, steady-state error covariance Σ
    poles : (n,) complex array, eigenvalues of ``A − LC``
    """

    L: np.ndarray
    P: np.ndarray
    poles: np.ndarray


class DKalmanResult(msgspec.Struct, frozen=True):
    """Discrete steady-state Kalman filter, in both forms.

    Attributes
    ----------
    L : (n, p) array, filter / current-estimate gain ``L = M Cᵀ(C M Cᵀ + V)⁻¹``;
        ``x̂[n] = x̄[n] + L(y[n] − C x̄[n])``, ``x̄[n+1] = Φ x̂[n] + Γ u[n]``
    L_pred : (n, p) array, predictor gain ``Φ L`` (what python-control's ``dlqe`` returns);
        ``x̂[n+1|n] = Φ x̂[n|n−1] + Γ u[n] + L_pred (y[n] − C x̂[n|n−1])``
    M : (n, n) array, a-priori covariance (before the measurement update)
    P : (n, n) array, a-posteriori covariance (after it), ``P = (I − LC) M``
    poles : (n,) complex array, error poles, eig(Φ − L_pred C) = eig(Φ(I − LC))
    """

    L: np.ndarray
    L_pred: np.ndarray
    M: np.ndarray
    P: np.ndarray
    poles: np.ndarray


def _observer_data(A: ArrayLike, G: ArrayLike, C: ArrayLike, W: ArrayLike, V: ArrayLike,
                   names: tuple[str, str]) -> tuple[np.ndarray, ...]:
    A = as_square(names[0], A)
    n = A.shape[0]
    G = as_matrix(names[1], G, (n, None))
    C = as_matrix("C", C, (None, n))
    W = as_weight("W", W, G.shape[1], definite=False)
    V = as_weight("V", V, C.shape[0], definite=True)
    return A, G, C, W, V



def measurement_update(M: np.ndarray, C: np.ndarray, V: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The Kalman measurement update of an a-priori covariance ``M``: the filter gain
    ``L = M Cᵀ S⁻¹`` (``S = C M Cᵀ + V``, the innovation covariance; equal to ``P Cᵀ V⁻¹``) and the
    a-posteriori covariance in Joseph form ``P = (I − LC) M (I − LC)ᵀ + L V Lᵀ`` (stays symmetric
    positive semi-definite under rounding). The one implementation: the steady-state and
    time-varying designs and the runtime time-varying filter all call it."""
    S = C @ M @ C.T + V
    L = np.linalg.solve(S, C @ M).T
    return L, joseph_update(M, L, C, V)


def joseph_update(M: np.ndarray, L: np.ndarray, C: np.ndarray, V: np.ndarray) -> np.ndarray:
    """The a-posteriori covariance ``P = (I − LC) M (I − LC)ᵀ + L V Lᵀ`` of ``x̂ = x̄ + L(y − C x̄)``
    for any gain ``L`` (exact for every gain, not only the optimal one: the estimate error is
    ``(I − LC)(x̄ − x) + L v``), ``M`` the a-priori covariance, ``V`` the measurement noise's."""
    I_LC = np.eye(M.shape[0]) - L @ C
    return I_LC @ M @ I_LC.T + L @ V @ L.T

@design_function('W and V')
def kalman(A: ArrayLike, G: ArrayLike, C: ArrayLike, W: ArrayLike, V: ArrayLike) -> KalmanResult:
    r"""Continuous steady-state Kalman–Bucy filter (python-control / MATLAB ``lqe``).

    .. math::
        A\Sigma + \Sigma A^T + GWG^T - \Sigma C^TV^{-1}C\Sigma = 0,\qquad L = \Sigma C^TV^{-1}

    Parameters
    ----------
    A : (n, n), G : (n, q) noise input, C : (p, n)
    W : (q, q) process-noise spectral density (PSD), V : (p, p) measurement-noise density (PD)

    Returns
    -------
    KalmanResult with ``L`` (n, p), ``P`` = Σ (n, n), ``poles`` of ``A − LC``.

    References
    ----------
    Kalman & Bucy (1961). docs/theory.md §5.2: Σ = [[√3, 1], [1, √3]], L = [√3, 1]ᵀ.
    """
    A, G, C, W, V = _observer_data(A, G, C, W, V, ("A", "G"))
    require_detectable(A, C, discrete=False, names="(A, C)")
    GWG = G @ W @ G.T
    require_noise_reaches_marginal_modes(A, GWG, discrete=False, names="A")
    S = solve_continuous_are(A.T, C.T, GWG, V)
    S = 0.5 * (S + S.T)
    L = S @ C.T @ np.linalg.inv(V)
    poles = np.linalg.eigvals(A - L @ C)
    require_stable(poles, discrete=False, what="kalman")
    return KalmanResult(L=L, P=S, poles=poles)


@design_function('W and V')
def dkalman(Phi: ArrayLike, G: ArrayLike, C: ArrayLike, W: ArrayLike, V: ArrayLike,
            ) -> DKalmanResult:
    r"""Discrete steady-state Kalman filter; filter (current-estimate) and predictor gains.

    The a-priori covariance solves the DARE dual to LQR (Φ→Φᵀ, Γ→Cᵀ, Q→GWGᵀ, R→V):

    .. math::
        M = \Phi\left(M - MC^T(CMC^T + V)^{-1}CM\right)\Phi^T + GWG^T

    and :math:`L = MC^T(CMC^T+V)^{-1}`, :math:`P = (I - LC)M`, :math:`L_{pred} = \Phi L`.

    Parameters
    ----------
    Phi : (n, n), G : (n, q) noise input, C : (p, n)
    W : (q, q) per-sample process-noise covariance (PSD), V : (p, p) per-sample measurement
        covariance (PD)

    Returns
    -------
    DKalmanResult with ``L``, ``L_pred`` (n, p), ``M``, ``P`` (n, n), ``poles``.

    Notes
    -----
    python-control's ``dlqe`` returns only ``L_pred``; using it as a filter gain is a common bug.
    """
    Phi, G, C, W, V = _observer_data(Phi, G, C, W, V, ("Phi", "G"))
    require_detectable(Phi, C, discrete=True, names="(Phi, C)")
    GWG = G @ W @ G.T
    require_noise_reaches_marginal_modes(Phi, GWG, discrete=True, names="Phi")
    M = solve_discrete_are(Phi.T, C.T, GWG, V)
    M = 0.5 * (M + M.T)
    L, P = measurement_update(M, C, V)
    P = 0.5 * (P + P.T)
    L_pred = Phi @ L
    poles = np.linalg.eigvals(Phi - L_pred @ C)
    require_stable(poles, discrete=True, what="dkalman")
    return DKalmanResult(L=L, L_pred=L_pred, M=M, P=P, poles=poles)


class TimeVaryingKalmanGains(msgspec.Struct, frozen=True):
    """Gains and covariances of the time-varying Kalman filter over a horizon.

    Attributes
    ----------
    L : (steps, n, p) filter gains ``L[n] = P[n] Cᵀ V⁻¹``
    M : (steps, n, n) a-priori covariances ``M[n]`` (``M[0]`` as given)
    P : (steps, n, n) a-posteriori covariances ``P[n]``
    """

    L: np.ndarray
    M: np.ndarray
    P: np.ndarray


@design_function('W, V and M0')
def kalman_tv(Phi: ArrayLike, G: ArrayLike, C: ArrayLike, W: ArrayLike, V: ArrayLike,
              M0: ArrayLike, steps: int) -> TimeVaryingKalmanGains:
    r"""Time-varying discrete Kalman filter gains from an initial covariance.

    .. math::
        P_n = M_n - M_nC^T(CM_nC^T + V)^{-1}CM_n,\quad L_n = P_nC^TV^{-1},\quad
        M_{n+1} = \Phi P_n \Phi^T + GWG^T

    The gains do not depend on the data, so one recursion serves every episode of a batch;
    ``L[n]`` converges to :func:`dkalman`'s ``L``.
    """
    Phi, G, C, W, V = _observer_data(Phi, G, C, W, V, ("Phi", "G"))
    n = Phi.shape[0]
    M0 = as_weight("M0", M0, n, definite=False)
    if isinstance(steps, bool) or not isinstance(steps, int | np.integer) or steps < 1:
        raise DesignError(f"steps: expected an integer ≥ 1, got {steps!r}")
    p = C.shape[0]
    GWG = G @ W @ G.T
    Ls, Ms, Ps = np.zeros((steps, n, p)), np.zeros((steps, n, n)), np.zeros((steps, n, n))
    M = M0
    for k in range(steps):
        Ms[k] = M
        Lk, P = measurement_update(M, C, V)
        Ls[k], Ps[k] = Lk, 0.5 * (P + P.T)
        M = Phi @ Ps[k] @ Phi.T + GWG
    return TimeVaryingKalmanGains(L=Ls, M=Ms, P=Ps)
