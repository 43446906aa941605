"""Luenberger observers by pole placement (duality with state feedback)."""

from __future__ import annotations

from typing import Literal

import msgspec
import numpy as np
from numpy.typing import ArrayLike

from pendulum_lqg.design.checks import as_matrix, as_poles, as_positive, as_square, design_function
from pendulum_lqg.errors import DesignError

#: The project's default continuous-time observer poles (deliberately slow; see docs/theory.md §3.1).
DEFAULT_OBSERVER_POLES: tuple[float, ...] = (-0.4, -0.5, -0.6, -0.7)


class ObserverResult(msgspec.Struct, frozen=True):
    """A pole-placement observer.

    Attributes
    ----------
    L : (n, p) gain
    poles : (n,) complex, achieved error poles (s-plane if continuous, z-plane if discrete)
    form : "continuous", "current" or "predictor"
    """

    L: np.ndarray
    poles: np.ndarray
    form: str


def place_gain(A: np.ndarray, C: np.ndarray, poles: np.ndarray, what: str) -> np.ndarray:
    n = A.shape[0]
    obs = np.vstack([C @ np.linalg.matrix_power(A, k) for k in range(n)])
    if np.linalg.matrix_rank(obs) < n:
        raise DesignError(f"{what}: pair is not observable, so its observer poles cannot be "
                          "placed arbitrarily")
    # Redundant outputs (rank C < p) would make scipy's place_poles fail: place on the row space
    # C_r = U_rᵀ C and map back, L = L_r U_rᵀ, so that L C = L_r C_r.
    U, sv, _ = np.linalg.svd(C, full_matrices=False)
    rank = int(np.sum(sv > 1e-10 * max(1.0, sv[0])))
    U_r = U[:, :rank]
    C_r = U_r.T @ C
    mult = max(int(np.sum(np.abs(poles - p) < 1e-12 * max(1.0, abs(p)))) for p in poles)
    if mult > rank:
        raise DesignError(f"poles: a pole is repeated {mult} times but rank C is only {rank} "
                          "(multiplicity must not exceed rank C)")
    # scipy.signal is heavy to import: only when an observer is placed
    from scipy.signal import place_poles

    try:       # Tits–Yang, as python-control's place (a wrapper of this call) uses
        L_r = place_poles(A.T, C_r.T, poles, method="YT").gain_matrix.T
    except ValueError as exc:  # place_poles reports numerical failures this way
        raise DesignError(f"poles: pole placement failed: {exc}") from exc
    return L_r @ U_r.T


@design_function('the poles')
def luenberger(A: ArrayLike, C: ArrayLike, poles: ArrayLike) -> ObserverResult:
    r"""Continuous full-order Luenberger observer :math:`\dot{\hat x} = A\hat x + Bu + L(y - C\hat x)`.

    Places the eigenvalues of :math:`A - LC` by duality: :math:`L = \mathrm{place}(A^T, C^T, p)^T`.

    Parameters
    ----------
    A : (n, n), C : (p, n), poles : (n,) desired eigenvalues of ``A − LC`` (closed under
        conjugation; a pole may repeat at most rank C times)

    Returns
    -------
    ObserverResult with ``L`` (n, p) and the achieved ``poles``.

    References
    ----------
    Luenberger (1966); docs/theory.md §3.1.
    """
    A = as_square("A", A)
    n = A.shape[0]
    C = as_matrix("C", C, (None, n))
    poles = as_poles("poles", poles, n)
    L = place_gain(A, C, poles, "(A, C)")
    return ObserverResult(L=L, poles=np.linalg.eigvals(A - L @ C), form="continuous")


@design_function('the poles')
def dluenberger(Phi: ArrayLike, C: ArrayLike, poles: ArrayLike, *,
                form: Literal["current", "predictor"] = "current",
                dt: float | None = None) -> ObserverResult:
    r"""Discrete Luenberger observer, current-estimate (filter) or predictor form.

    * predictor: :math:`\hat x_{n+1} = \Phi\hat x_n + \Gamma u_n + L(y_n - C\hat x_n)`, error
      poles :math:`\mathrm{eig}(\Phi - LC)`, :math:`L = \mathrm{place}(\Phi^T, C^T, z)^T`;
    * current: :math:`\hat x_n = \bar x_n + L(y_n - C\bar x_n)`,
      :math:`\bar x_{n+1} = \Phi\hat x_n + \Gamma u_n`, error poles
      :math:`\mathrm{eig}(\Phi - LC\Phi)`, :math:`L = \mathrm{place}(\Phi^T, (C\Phi)^T, z)^T`.

    Parameters
    ----------
    Phi : (n, n), C : (p, n)
    poles : (n,) desired poles. **z-plane** poles if ``dt`` is None; if ``dt`` is given they are
        **s-plane** poles mapped by ``z = e^{s·dt}``.
    form : "current" (default) or "predictor"
    dt : float, optional sample period used to map s-plane poles

    Returns
    -------
    ObserverResult with ``L`` (n, p) and the achieved z-plane ``poles``.
    """
    Phi = as_square("Phi", Phi)
    n = Phi.shape[0]
    C = as_matrix("C", C, (None, n))
    poles = as_poles("poles", poles, n)
    if dt is not None:
        poles = np.exp(poles * as_positive("dt", dt))
    if form == "predictor":
        L = place_gain(Phi, C, poles, "(Phi, C)")
        achieved = np.linalg.eigvals(Phi - L @ C)
    elif form == "current":
        L = place_gain(Phi, C @ Phi, poles, "(Phi, C·Phi)")
        achieved = np.linalg.eigvals(Phi - L @ C @ Phi)
    else:
        raise DesignError(f"form: expected 'current' or 'predictor', got {form!r}")
    return ObserverResult(L=L, poles=achieved, form=form)
