"""LQG assembly: the 2n-state closed loop of plant, state feedback and observer.

Separation principle: the closed-loop eigenvalues are those of ``A − BK`` together with those of the
observer error dynamics, whatever the observer (Kalman or Luenberger) and whichever form.
"""

from __future__ import annotations

from typing import Literal

import msgspec
import numpy as np
from numpy.typing import ArrayLike

from pendulum_lqg.design.checks import as_loop, design_function
from pendulum_lqg.errors import DesignError


class LQGResult(msgspec.Struct, frozen=True):
    """Closed loop of plant + ``u = −K x̂`` + observer.

    Attributes
    ----------
    A_cl : (2n, 2n) closed-loop matrix, state ``[x; x̂]`` (continuous, predictor) or
        ``[x; x̄]`` (current form: x̄ is the a-priori estimate)
    poles : (2n,) its eigenvalues
    controller_poles : (n,) eig(A − BK)
    observer_poles : (n,) eig(A − LC) (continuous / predictor) or eig(Φ − LCΦ) (current)
    separation_error : max distance between ``poles`` and the union of the two sets (after
        optimal matching); ≈ 0 shows the separation principle
    """

    A_cl: np.ndarray
    poles: np.ndarray
    controller_poles: np.ndarray
    observer_poles: np.ndarray
    separation_error: float


def _match_error(a: np.ndarray, b: np.ndarray) -> float:
    from scipy.optimize import linear_sum_assignment

    cost = np.abs(a[:, None] - b[None, :])
    rows, cols = linear_sum_assignment(cost)
    return float(np.max(cost[rows, cols]))


@design_function()
def lqg(A: ArrayLike, B: ArrayLike, C: ArrayLike, K: ArrayLike, L: ArrayLike, *,
        form: Literal["continuous", "predictor", "current"] = "continuous") -> LQGResult:
    r"""Assemble the LQG closed loop and check the separation principle.

    * continuous: :math:`\dot x = Ax - BK\hat x`,
      :math:`\dot{\hat x} = LCx + (A - BK - LC)\hat x`;
    * predictor (discrete, A = Φ, B = Γ): the same matrix in z;
    * current (discrete): state :math:`[x; \bar x]` with :math:`\hat x = \bar x + L(Cx - C\bar x)`,
      :math:`x^+ = \Phi x - \Gamma K\hat x`, :math:`\bar x^+ = (\Phi - \Gamma K)\hat x`.

    Parameters
    ----------
    A : (n, n), B : (n, m), C : (p, n), K : (m, n), L : (n, p)
    form : which observer structure L belongs to

    Returns
    -------
    LQGResult
    """
    A, B, C, K, L = as_loop(A, B, C, K, L)
    n = A.shape[0]
    ctrl = np.linalg.eigvals(A - B @ K)
    if form in ("continuous", "predictor"):
        A_cl = np.block([[A, -B @ K], [L @ C, A - B @ K - L @ C]])
        obs = np.linalg.eigvals(A - L @ C)
    elif form == "current":
        LC = L @ C
        I_LC = np.eye(n) - LC
        A_cl = np.block([[A - B @ K @ LC, -B @ K @ I_LC],
                         [(A - B @ K) @ LC, (A - B @ K) @ I_LC]])
        obs = np.linalg.eigvals(A - LC @ A)
    else:
        raise DesignError(f"form: expected 'continuous', 'predictor' or 'current', got {form!r}")
    poles = np.linalg.eigvals(A_cl)
    return LQGResult(A_cl=A_cl, poles=poles, controller_poles=ctrl, observer_poles=obs,
                     separation_error=_match_error(poles, np.concatenate([ctrl, obs])))
