"""Linear-quadratic regulators: continuous, discrete (with prescribed decay), finite horizon, Bryson.

Sign convention everywhere: ``u = −K x`` (MATLAB / python-control).
"""

from __future__ import annotations

import msgspec
import numpy as np
import scipy.linalg
from numpy.typing import ArrayLike

from pendulum_lqg.design.checks import (
    as_matrix,
    as_square,
    as_weight,
    design_function,
    require_cost_sees_marginal_modes,
    require_stabilizable,
    require_stable,
)
from pendulum_lqg.errors import DesignError
from pendulum_lqg.util.limits import MAX_RICCATI_FLOATS, check_at_most


class LQRResult(msgspec.Struct, frozen=True):
    """Result of an infinite-horizon LQR design.

    Attributes
    ----------
    K : (m, n) array, state-feedback gain, ``u = −K x``
    P : (n, n) array, Riccati solution; the optimal cost from x₀ is ``x₀ᵀ P x₀``
    poles : (n,) complex array, closed-loop poles of ``A − BK`` (or ``Φ − ΓK``)
    discrete : bool
    """

    K: np.ndarray
    P: np.ndarray
    poles: np.ndarray
    discrete: bool


def _plant(A: ArrayLike, B: ArrayLike, names: tuple[str, str]) -> tuple[np.ndarray, np.ndarray]:
    A = as_square(names[0], A)
    B = as_matrix(names[1], B, (A.shape[0], None))
    return A, B


def _weights(Q: ArrayLike, R: ArrayLike, N: ArrayLike | None, n: int, m: int,
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    Q = as_weight("Q", Q, n, definite=False)
    R = as_weight("R", R, m, definite=True)
    N = np.zeros((n, m)) if N is None else as_matrix("N", N, (n, m))
    joint = np.block([[Q, N], [N.T, R]])
    if np.min(np.linalg.eigvalsh(joint)) < -1e-9 * max(1.0, np.max(np.abs(joint))):
        raise DesignError("N: the joint weight [[Q, N], [Nᵀ, R]] must be positive semi-definite")
    return Q, R, N


@design_function('Q and R')
def lqr(A: ArrayLike, B: ArrayLike, Q: ArrayLike, R: ArrayLike, *,
        N: ArrayLike | None = None) -> LQRResult:
    r"""Continuous infinite-horizon LQR.

    Minimises :math:`J = \int_0^\infty x^TQx + u^TRu + 2x^TNu\,dt` subject to
    :math:`\dot x = Ax + Bu`. Solves the CARE
    :math:`A^TP + PA - (PB + N)R^{-1}(B^TP + N^T) + Q = 0` and returns :math:`K = R^{-1}(B^TP + N^T)`.

    Parameters
    ----------
    A : (n, n) array
    B : (n, m) array
    Q : (n, n) array, symmetric positive semi-definite
    R : (m, m) array, symmetric positive definite
    N : (n, m) array, optional cross weight

    Returns
    -------
    LQRResult with ``K`` (m, n), ``P`` (n, n), ``poles`` of ``A − BK``.

    Raises
    ------
    ShapeError, DesignError (subclasses of ValueError)
        Wrong shapes, non-symmetric or indefinite weights, ``(A, B)`` not stabilisable.

    References
    ----------
    Kalman (1960); python-control ``lqr``. docs/theory.md §2, worked examples §5.1 and §5.2.
    """
    A, B = _plant(A, B, ("A", "B"))
    Q, R, N = _weights(Q, R, N, *B.shape)
    require_stabilizable(A, B, discrete=False, names="(A, B)")
    require_cost_sees_marginal_modes(A, B, Q, R, N, discrete=False, names="A")
    # The CARE with the cross weight, solved as python-control's lqr does without Slycot (the
    # generalised form with E = I, so that the gains are the same to the last bit).
    P = scipy.linalg.solve_continuous_are(A, B, Q, R, e=np.eye(A.shape[0]), s=N)
    K = np.linalg.solve(R, B.T @ P + N.T)                              # K = R⁻¹(BᵀP + Nᵀ)
    poles = np.linalg.eigvals(A - B @ K)
    require_stable(poles, discrete=False, what="lqr")
    return LQRResult(K=K, P=P, poles=poles, discrete=False)


@design_function('Q and R')
def dlqr(Phi: ArrayLike, Gamma: ArrayLike, Q: ArrayLike, R: ArrayLike, *,
         N: ArrayLike | None = None, alpha: float = 1.0) -> LQRResult:
    r"""Discrete infinite-horizon LQR, optionally with a prescribed degree of stability.

    Minimises :math:`J = \sum_{n\ge 0} x_n^TQx_n + u_n^TRu_n + 2x_n^TNu_n` subject to
    :math:`x_{n+1} = \Phi x_n + \Gamma u_n` (DARE; MATLAB / python-control ``dlqr``).

    With ``alpha > 1`` this is Franklin's "pincer" procedure: design on
    :math:`(\alpha\Phi, \alpha\Gamma)` and apply the gain to the real plant, which places every
    closed-loop pole inside the circle of radius :math:`1/\alpha`. For a 1 % settling time
    :math:`t_s` at period T choose :math:`\alpha = 100^{T/t_s}`.

    Parameters
    ----------
    Phi : (n, n) array
    Gamma : (n, m) array
    Q : (n, n) array, symmetric positive semi-definite
    R : (m, m) array, symmetric positive definite
    N : (n, m) array, optional cross weight
    alpha : float ≥ 1, prescribed decay factor

    Returns
    -------
    LQRResult; ``poles`` are those of the real closed loop ``Φ − ΓK``.
    """
    Phi, Gamma = _plant(Phi, Gamma, ("Phi", "Gamma"))
    Q, R, N = _weights(Q, R, N, *Gamma.shape)
    try:
        if isinstance(alpha, bool) or np.iscomplexobj(alpha):
            raise TypeError(alpha)
        alpha = float(alpha)
    except (TypeError, ValueError) as exc:
        raise DesignError(f"alpha: expected a number ≥ 1, got {alpha!r}") from exc
    if not np.isfinite(alpha) or alpha < 1.0:
        raise DesignError(f"alpha: expected a finite number ≥ 1, got {alpha!r}")
    Pa, Ga = alpha * Phi, alpha * Gamma
    require_stabilizable(Pa, Ga, discrete=True,
                         names="(Phi, Gamma)" if alpha == 1.0 else "(alpha·Phi, alpha·Gamma)")
    require_cost_sees_marginal_modes(Pa, Ga, Q, R, N, discrete=True,
                                     names="Phi" if alpha == 1.0 else "alpha·Phi")
    # The DARE with the cross weight, solved as python-control's dlqr does without Slycot.
    P = scipy.linalg.solve_discrete_are(Pa, Ga, Q, R, s=N)
    K = scipy.linalg.solve(Ga.T @ P @ Ga + R, Ga.T @ P @ Pa + N.T)      # (R + ΓᵀPΓ)⁻¹(ΓᵀPΦ + Nᵀ)
    require_stable(np.linalg.eigvals(Pa - Ga @ K), discrete=True, what="dlqr")
    poles = np.linalg.eigvals(Phi - Gamma @ K)
    return LQRResult(K=K, P=P, poles=poles, discrete=True)


class FiniteHorizonLQR(msgspec.Struct, frozen=True):
    """Time-varying LQR gains from the backward Riccati sweep.

    Attributes
    ----------
    K : (horizon, m, n) array, ``u[n] = −K[n] x[n]``
    P : (horizon + 1, n, n) array, ``P[horizon] = S``; the optimal cost of
        ``½ Σ (xᵀQx + uᵀRu) + ½ x[N]ᵀ S x[N]`` is ``½ x[0]ᵀ P[0] x[0]``
    """

    K: np.ndarray
    P: np.ndarray

    def simulate(self, Phi: ArrayLike, Gamma: ArrayLike, x0: ArrayLike,
                 ) -> tuple[np.ndarray, np.ndarray]:
        """Closed-loop trajectory: states (horizon + 1, n) and controls (horizon, m)."""
        Phi, Gamma = np.asarray(Phi, float), np.asarray(Gamma, float)
        horizon = self.K.shape[0]
        x = np.zeros((horizon + 1, Phi.shape[0]))
        u = np.zeros((horizon, Gamma.shape[1]))
        x[0] = np.asarray(x0, float).ravel()
        for k in range(horizon):
            u[k] = -self.K[k] @ x[k]
            x[k + 1] = Phi @ x[k] + Gamma @ u[k]
        return x, u


@design_function('Q, R and S')
def finite_horizon_dlqr(Phi: ArrayLike, Gamma: ArrayLike, Q: ArrayLike, R: ArrayLike,
                        S: ArrayLike, horizon: int) -> FiniteHorizonLQR:
    r"""Finite-horizon discrete LQR by the backward Riccati recursion (Bryson–Ho sweep).

    .. math::
        P_N = S,\quad K_{n-1} = (R + \Gamma^TP_n\Gamma)^{-1}\Gamma^TP_n\Phi,\quad
        M_n = P_n - P_n\Gamma(R + \Gamma^TP_n\Gamma)^{-1}\Gamma^TP_n,\quad
        P_{n-1} = \Phi^TM_n\Phi + Q

    Parameters
    ----------
    Phi : (n, n), Gamma : (n, m), Q : (n, n) PSD, R : (m, m) PD, S : (n, n) PSD terminal weight
    horizon : int ≥ 1, number of control steps N; at most
        :data:`~pendulum_lqg.util.limits.MAX_RICCATI_FLOATS` ``// n² − 1`` (every ``P[n]`` is kept)

    Returns
    -------
    FiniteHorizonLQR with ``K`` (horizon, m, n) and ``P`` (horizon + 1, n, n).

    References
    ----------
    Ogata, *Discrete-Time Control Systems*, §8-3 (docs/theory.md §5.3).
    """
    Phi, Gamma = _plant(Phi, Gamma, ("Phi", "Gamma"))
    n, m = Gamma.shape
    Q = as_weight("Q", Q, n, definite=False)
    R = as_weight("R", R, m, definite=True)
    S = as_weight("S", S, n, definite=False)
    if isinstance(horizon, bool) or not isinstance(horizon, int | np.integer) or horizon < 1:
        raise DesignError(f"horizon: expected an integer ≥ 1, got {horizon!r}")
    check_at_most("horizon", int(horizon), MAX_RICCATI_FLOATS // (n * n) - 1,
                  f"steps for n = {n} states: P keeps (horizon + 1)·n² floats, at most "
                  f"{MAX_RICCATI_FLOATS:,}", error=DesignError)
    P = np.zeros((horizon + 1, n, n))
    K = np.zeros((horizon, m, n))
    P[horizon] = S
    for k in range(horizon, 0, -1):
        Pn = P[k]
        H = R + Gamma.T @ Pn @ Gamma                                    # R + ΓᵀPΓ
        K[k - 1] = np.linalg.solve(H, Gamma.T @ Pn @ Phi)               # K[n−1]
        M = Pn - Pn @ Gamma @ np.linalg.solve(H, Gamma.T @ Pn)          # M[n]
        Pk = Phi.T @ M @ Phi + Q                                        # P[n−1]
        P[k - 1] = 0.5 * (Pk + Pk.T)
    return FiniteHorizonLQR(K=K, P=P)


@design_function()
def bryson(max_state: ArrayLike, max_input: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    r"""Bryson's rule: :math:`Q_{ii} = 1/x_{i,max}^2`, :math:`R_{jj} = 1/u_{j,max}^2`.

    Parameters
    ----------
    max_state : (n,) largest acceptable value of each state; ``inf`` gives a zero weight
    max_input : (m,) largest acceptable value of each input

    Returns
    -------
    Q : (n, n) diagonal, R : (m, m) diagonal
    """
    xs = np.atleast_1d(np.asarray(max_state, dtype=float))
    us = np.atleast_1d(np.asarray(max_input, dtype=float))
    for name, arr, allow_inf in (("max_state", xs, True), ("max_input", us, False)):
        if arr.ndim != 1 or arr.size == 0:
            raise DesignError(f"{name}: expected a non-empty 1-D sequence")
        if np.any(np.isnan(arr)) or np.any(arr <= 0) or (not allow_inf and np.any(np.isinf(arr))):
            raise DesignError(f"{name}: every entry must be a positive "
                              f"{'number (inf allowed)' if allow_inf else 'finite number'}")
    return np.diag(1.0 / xs**2), np.diag(1.0 / us**2)
