r"""The lecture's other observer designs: Ackermann, reduced order, and LMIs (decay rate, H₂, H∞).

Formulas and derivations: ``docs/observers.md`` (the observers beyond Luenberger and Kalman) and
``docs/theory.md`` §3.3.

* :func:`ackermann` — single-output pole placement, :math:`L = \varphi(A)\,\mathcal O^{-1} e_n`;
* :func:`reduced_order_observer` / :func:`dreduced_order_observer` — estimate only the unmeasured
  part ``w = R x`` after the change of variables ``[y; w] = [C; R] x``; error dynamics
  :math:`A_{22} - G A_{12}` (continuous) or :math:`\Phi_{22} - G\Phi_{12}` (discrete);
* :func:`lmi_observer` — a gain from the Lyapunov LMI with a prescribed decay rate α;
* :func:`h2_filter`, :func:`hinf_filter` — the H₂ (= Kalman–Bucy) and H∞ filters by LMIs.

The LMIs are solved with ``cvxpy`` and the Clarabel interior-point solver (imported on first use).
"""

from __future__ import annotations

import warnings
from typing import Any

import msgspec
import numpy as np
from numpy.typing import ArrayLike

from pendulum_lqg.design.checks import (
    as_matrix,
    as_poles,
    as_square,
    as_weight,
    design_function,
    require_detectable,
)
from pendulum_lqg.design.luenberger import ObserverResult, place_gain
from pendulum_lqg.errors import DesignError, ShapeError

#: Solver settings of the LMIs: Clarabel's tolerances (its defaults are 1e-8).
LMI_TOLERANCE = 1e-9
#: Strictness margin of the LMIs (``≺ 0`` is imposed as ``≼ −ε I``).
LMI_EPS = 1e-9


def _real_number(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        raise DesignError(f"{name}: expected a real number, got {value!r}")
    return float(value)


# ---- Ackermann ---------------------------------------------------------------------------------------
@design_function('the poles')
def ackermann(A: ArrayLike, C: ArrayLike, poles: ArrayLike) -> ObserverResult:
    r"""Single-output observer gain by Ackermann's formula.

    .. math::
        L = \varphi(A)\,\mathcal O^{-1} e_n,\qquad
        \mathcal O = \begin{bmatrix} C \\ CA \\ \vdots \\ CA^{n-1}\end{bmatrix},\qquad
        \varphi(s) = \prod_i (s - p_i)

    so that :math:`\det(sI - (A - LC)) = \varphi(s)` (the dual of Ackermann's state-feedback
    formula, through the observable canonical form).

    Parameters
    ----------
    A : (n, n); C : (1, n) — one output only; poles : n poles closed under conjugation

    Returns
    -------
    ObserverResult with ``L`` (n, 1) and the achieved ``poles`` of ``A − LC`` (form
    ``"continuous"``; the formula is the same for a discrete pair with z-plane poles).

    Raises
    ------
    ShapeError : ``C`` has more than one row (use :func:`~pendulum_lqg.design.luenberger`)
    DesignError : ``(A, C)`` is not observable
    """
    A = as_square("A", A)
    n = A.shape[0]
    C = as_matrix("C", C, (None, n))
    if C.shape[0] != 1:
        raise ShapeError(f"C: Ackermann's formula needs a single output, C of shape (1, {n}); "
                         f"found {C.shape} (use design.luenberger for several outputs)")
    p = as_poles("poles", poles, n)
    obs = np.vstack([C @ np.linalg.matrix_power(A, k) for k in range(n)])
    if np.linalg.matrix_rank(obs) < n:
        raise DesignError("ackermann: (A, C) is not observable, so its observer poles cannot be "
                          "placed")
    coeffs = np.real(np.poly(p))                       # φ(s) = s^n + a1 s^{n-1} + … + an
    phi_A = sum(c * np.linalg.matrix_power(A, n - i) for i, c in enumerate(coeffs))
    e_n = np.zeros((n, 1))
    e_n[-1, 0] = 1.0
    L = phi_A @ np.linalg.solve(obs, e_n)
    return ObserverResult(L=L, poles=np.linalg.eigvals(A - L @ C), form="continuous")


# ---- reduced order -----------------------------------------------------------------------------------
class ReducedOrderObserver(msgspec.Struct, frozen=True):
    r"""A reduced-order (minimal-order) observer of the unmeasured part ``w = R x``.

    With ``T = [C; R]`` (``[y; w] = T x``) the partitioned model is ``Ā = T A T⁻¹``,
    ``B̄ = T B``. The observer state ``z = ŵ − G y`` (dimension ``n − p``) follows

    continuous: ``ż = F z + H_y y + H_u u``; discrete: ``z[k+1] = F z[k] + H_y y[k] + H_u u[k]``

    and the estimate is ``x̂ = T⁻¹ [y; z + G y]``. Error ``w − ŵ`` obeys ``ė = F e``
    (``e[k+1] = F e[k]``), ``F = Ā₂₂ − G Ā₁₂``.

    Attributes
    ----------
    G : (n−p, p) observer gain; F : (n−p, n−p); H_y : (n−p, p); H_u : (n−p, m)
    T, T_inv : (n, n) change of variables and its inverse
    poles : eigenvalues of ``F`` (s- or z-plane); form : "continuous" or "discrete"
    """

    G: np.ndarray
    F: np.ndarray
    H_y: np.ndarray
    H_u: np.ndarray
    T: np.ndarray
    T_inv: np.ndarray
    poles: np.ndarray
    form: str

    def estimate(self, y: np.ndarray, z: np.ndarray) -> np.ndarray:
        """``x̂ = T⁻¹ [y; z + G y]`` for a batch ``y`` (N, p), ``z`` (N, n−p) → (N, n)."""
        w = z + y @ self.G.T
        return np.hstack([y, w]) @ self.T_inv.T


def _reduced(A: ArrayLike, B: ArrayLike, C: ArrayLike, poles: ArrayLike, form: str,
             ) -> ReducedOrderObserver:
    A = as_square("A", A)
    n = A.shape[0]
    B = as_matrix("B", B, (n, None))
    C = as_matrix("C", C, (None, n))
    p = C.shape[0]
    if np.linalg.matrix_rank(C) < p:
        raise DesignError(f"C: the reduced-order observer needs C of full row rank {p}")
    if p >= n:
        raise DesignError(f"C: {p} outputs measure the whole state (n = {n}); nothing to observe")
    # R: an orthonormal basis of the null space of C, so T = [C; R] is invertible
    R = np.linalg.svd(C)[2][p:]
    T = np.vstack([C, R])
    T_inv = np.linalg.inv(T)
    Ab, Bb = T @ A @ T_inv, T @ B
    A11, A12, A21, A22 = Ab[:p, :p], Ab[:p, p:], Ab[p:, :p], Ab[p:, p:]
    B1, B2 = Bb[:p], Bb[p:]
    q = as_poles("poles", poles, n - p)
    G = place_gain(A22, A12, q, "reduced-order observer: (A22, A12)")
    F = A22 - G @ A12
    H_y = F @ G + A21 - G @ A11
    H_u = B2 - G @ B1
    return ReducedOrderObserver(G=G, F=F, H_y=H_y, H_u=H_u, T=T, T_inv=T_inv,
                                poles=np.linalg.eigvals(F), form=form)


@design_function('the poles')
def reduced_order_observer(A: ArrayLike, B: ArrayLike, C: ArrayLike, poles: ArrayLike,
                           ) -> ReducedOrderObserver:
    r"""Continuous reduced-order Luenberger observer (Luenberger 1964; docs/theory.md §3.3).

    .. math::
        \dot z = (\bar A_{22} - G\bar A_{12}) z
                 + \big[(\bar A_{22} - G\bar A_{12})G + \bar A_{21} - G\bar A_{11}\big] y
                 + (\bar B_2 - G\bar B_1) u,\qquad \hat w = z + G y

    with ``G`` placing the ``n − p`` eigenvalues of :math:`\bar A_{22} - G\bar A_{12}` at
    ``poles`` (by duality, as :func:`~pendulum_lqg.design.luenberger`).

    Parameters
    ----------
    A : (n, n), B : (n, m), C : (p, n) of full row rank p < n; poles : n − p poles (s-plane)
    """
    return _reduced(A, B, C, poles, "continuous")


@design_function('the poles')
def dreduced_order_observer(Phi: ArrayLike, Gamma: ArrayLike, C: ArrayLike, poles: ArrayLike,
                            ) -> ReducedOrderObserver:
    r"""Discrete reduced-order observer: the same algebra on ``(Φ, Γ)``, z-plane ``poles``.

    .. math::
        z[k+1] = F z[k] + (F G + \bar\Phi_{21} - G\bar\Phi_{11})\,y[k]
                 + (\bar\Gamma_2 - G\bar\Gamma_1)\,u[k],\qquad \hat w[k] = z[k] + G y[k]

    The estimate ``x̂[k]`` uses the newest measurement ``y[k]`` directly for the measured part
    (a current-form estimator); the error ``w − ŵ`` obeys ``e[k+1] = F e[k]``.
    """
    return _reduced(Phi, Gamma, C, poles, "discrete")


# ---- LMIs ----------------------------------------------------------------------------------------
class LMIObserverResult(msgspec.Struct, frozen=True):
    """An observer gain found by an LMI.

    Attributes
    ----------
    L : (n, p) gain of ``x̂̇ = Ax̂ + Bu + L(y − Cx̂)``; poles : eigenvalues of ``A − LC``
    P : (n, n) the Lyapunov matrix of the certificate
    bound : the certified bound (decay rate α, H₂ cost ``trace Z ≥ trace Σ``, or γ of H∞)
    status : the solver's status (``"optimal"``)
    """

    L: np.ndarray
    poles: np.ndarray
    P: np.ndarray
    bound: float
    status: str


def _solve(problem: object, what: str) -> str:
    import cvxpy as cp

    try:
        with warnings.catch_warnings():   # "may be inaccurate": the status says so, checked below
            warnings.simplefilter("ignore", UserWarning)
            problem.solve(solver=cp.CLARABEL, tol_gap_abs=LMI_TOLERANCE,  # type: ignore[attr-defined]
                          tol_gap_rel=LMI_TOLERANCE, tol_feas=LMI_TOLERANCE)
    except cp.error.SolverError as exc:
        raise DesignError(f"{what}: the LMI solver failed: {' '.join(str(exc).split())}") from exc
    status = str(problem.status)  # type: ignore[attr-defined]
    if status not in ("optimal", "optimal_inaccurate"):
        raise DesignError(f"{what}: the LMI is {status} (no observer meets it)")
    return status


def _sym(X: Any) -> Any:
    return 0.5 * (X + X.T)


@design_function()
def lmi_observer(A: ArrayLike, C: ArrayLike, *, decay: float) -> LMIObserverResult:
    r"""Observer gain with every error pole at Re λ ≤ −α, from the Lyapunov LMI.

    .. math::
        (A - LC)^T P + P(A - LC) + 2\alpha P \prec 0,\qquad P \succ 0

    is linear in ``P`` and ``Y = PL``: :math:`A^TP + PA - C^TY^T - YC + 2\alpha P \prec 0`.
    ``V(e) = eᵀPe`` then decays at least as :math:`e^{-2\alpha t}`, so
    :math:`\|e(t)\| \le \kappa(P)^{1/2} e^{-\alpha t}\|e(0)\|`. Among the feasible gains the one
    with the smallest ``‖Y‖_F`` under ``P ⪰ I`` is returned (a bounded, well-conditioned gain).

    Parameters
    ----------
    A : (n, n), C : (p, n); decay : α ≥ 0 [1/s]
    """
    import cvxpy as cp

    A = as_square("A", A)
    n = A.shape[0]
    C = as_matrix("C", C, (None, n))
    alpha = _real_number("decay", decay)
    if not np.isfinite(alpha) or alpha < 0:
        raise DesignError(f"decay: expected a finite rate α ≥ 0, got {decay!r}")
    P = cp.Variable((n, n), symmetric=True)
    Y = cp.Variable((n, C.shape[0]))
    lyap = A.T @ P + P @ A - C.T @ Y.T - Y @ C + 2 * alpha * P
    cons = [_sym(lyap) << -LMI_EPS * np.eye(n), P >> np.eye(n)]
    prob = cp.Problem(cp.Minimize(cp.norm(Y, "fro")), cons)
    status = _solve(prob, "lmi_observer")
    Pv = np.asarray(P.value)
    L = np.linalg.solve(Pv, np.asarray(Y.value))
    poles = np.linalg.eigvals(A - L @ C)
    if poles.real.max() > -alpha + 1e-6 * max(1.0, alpha):    # an inaccurate solve must still hold
        raise DesignError(f"lmi_observer: the solver's gain misses the decay rate {alpha:g} "
                          f"(slowest pole {poles.real.max():.6g}; status {status})")
    return LMIObserverResult(L=L, poles=poles, P=Pv, bound=alpha, status=status)


def _filter_data(A: ArrayLike, G: ArrayLike, C: ArrayLike, W: ArrayLike, V: ArrayLike,
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
    """Checked data, with ``W`` and ``V`` both multiplied by ``k`` so the larger is 1.

    The optimal gains do not change when both noise densities are scaled by the same ``k``
    (``Σ → kΣ``, ``L = ΣCᵀV⁻¹`` unchanged; the H∞ bound scales by ``√k``), while the solver's
    tolerances, relative to O(1) data, become meaningful: the lecture's densities are ~1e-4.
    Returns ``A, C, G (kW)^{1/2}, (kV)^{1/2}, k``.
    """
    A = as_square("A", A)
    n = A.shape[0]
    G = as_matrix("G", G, (n, None))
    C = as_matrix("C", C, (None, n))
    W = as_weight("W", W, G.shape[1], definite=False)
    V = as_weight("V", V, C.shape[0], definite=True)
    require_detectable(A, C, discrete=False, names="(A, C)")
    k = 1.0 / max(np.abs(G @ W @ G.T).max(), np.abs(V).max())
    return A, C, G @ _sqrtm(k * W), _sqrtm(k * V), k


def _sqrtm(S: np.ndarray) -> np.ndarray:
    lam, U = np.linalg.eigh(0.5 * (S + S.T))
    return (U * np.sqrt(np.clip(lam, 0.0, None))) @ U.T


@design_function('W and V')
def h2_filter(A: ArrayLike, G: ArrayLike, C: ArrayLike, W: ArrayLike, V: ArrayLike,
              ) -> LMIObserverResult:
    r"""The H₂-optimal filter by LMIs — which is the Kalman–Bucy filter.

    The error :math:`\dot e = (A - LC)e + G w - L v` (``w``, ``v`` white with densities ``W``,
    ``V``) has the steady covariance Σ of :math:`(A-LC)\Sigma + \Sigma(A-LC)^T + GWG^T + LVL^T = 0`
    and H₂ cost ``trace Σ``. With ``P = X⁻¹`` for any ``X ≻ Σ`` and ``Y = PL``:

    .. math::
        \min \operatorname{trace} Z\quad\text{s.t.}\quad
        \begin{bmatrix} A^TP + PA - C^TY^T - YC & PGW^{1/2} & YV^{1/2}\\
                        \star & -I & 0\\ \star & 0 & -I\end{bmatrix} \prec 0,\qquad
        \begin{bmatrix} Z & I\\ I & P\end{bmatrix} \succeq 0

    (Schur complements: the first is the Lyapunov inequality of ``P⁻¹``, the second ``Z ⪰ P⁻¹``).
    At the optimum ``P⁻¹ = Σ`` of the Kalman–Bucy filter and ``L = ΣCᵀV⁻¹``; ``bound`` is the
    achieved ``trace Z``.

    Parameters
    ----------
    A : (n, n), G : (n, q), C : (p, n); W : (q, q) process density, V : (p, p) measurement density
    """
    import cvxpy as cp

    A, C, Gw, Vh, k = _filter_data(A, G, C, W, V)
    n, p, q = A.shape[0], C.shape[0], Gw.shape[1]
    P, Y = cp.Variable((n, n), symmetric=True), cp.Variable((n, p))
    Z = cp.Variable((n, n), symmetric=True)
    M = cp.bmat([[A.T @ P + P @ A - C.T @ Y.T - Y @ C, P @ Gw, Y @ Vh],
                 [(P @ Gw).T, -np.eye(q), np.zeros((q, p))],
                 [(Y @ Vh).T, np.zeros((p, q)), -np.eye(p)]])
    cons = [_sym(M) << -LMI_EPS * np.eye(n + q + p),
            cp.bmat([[Z, np.eye(n)], [np.eye(n), P]]) >> 0]
    prob = cp.Problem(cp.Minimize(cp.trace(Z)), cons)
    status = _solve(prob, "h2_filter")
    Pv = np.asarray(P.value)
    L = np.linalg.solve(Pv, np.asarray(Y.value))
    return LMIObserverResult(L=L, poles=np.linalg.eigvals(A - L @ C), P=Pv * k,
                             bound=float(prob.value) / k, status=status)


@design_function('W and V')
def hinf_filter(A: ArrayLike, G: ArrayLike, C: ArrayLike, W: ArrayLike, V: ArrayLike, *,
                gamma: float | None = None) -> LMIObserverResult:
    r"""The H∞ filter by LMIs: a gain bounding the worst-case gain from noise to estimation error.

    With normalised disturbances ``w = W^{1/2} d₁``, ``v = V^{1/2} d₂`` the error is
    :math:`\dot e = (A - LC)e + B_d d`, :math:`B_d = [GW^{1/2}, -LV^{1/2}]`, and the bounded-real
    lemma gives :math:`\|T_{ed}\|_\infty < \gamma` iff some ``P ≻ 0`` satisfies

    .. math::
        \begin{bmatrix} A^TP + PA - C^TY^T - YC + I & PGW^{1/2} & -YV^{1/2}\\
                        \star & -\gamma^2 I & 0\\ \star & 0 & -\gamma^2 I\end{bmatrix} \prec 0,
        \qquad Y = PL

    linear in ``(P, Y, γ²)``. ``gamma=None`` minimises γ; a number asks for feasibility at that γ
    (with the smallest ``‖Y‖_F``, a moderate gain).

    The LMI is not homogeneous in ``P`` (the ``+I`` of the error output), and its infimum over
    ``P ≻ 0`` is approached only as ``P → 0``, ``L → ∞`` — a high-gain filter that no sampled loop
    could run (on the cart-pole, gains of ~10⁹). Both problems are therefore solved over the
    normalised set ``P ⪰ I``, which bounds the gain: the returned γ is the smallest bound
    certified there — still a guaranteed bound on the error system's H∞ norm (checked by a
    frequency sweep in the tests), not the high-gain infimum.

    Returns
    -------
    LMIObserverResult with ``bound`` = the certified γ (the H∞ norm of ``T_ed`` is below it).
    """
    import cvxpy as cp

    A, C, Gw, Vh, k = _filter_data(A, G, C, W, V)
    n, p, q = A.shape[0], C.shape[0], Gw.shape[1]
    P, Y = cp.Variable((n, n), symmetric=True), cp.Variable((n, p))
    if gamma is None:
        g2 = cp.Variable(nonneg=True)
        objective = cp.Minimize(g2)
    else:
        g = _real_number("gamma", gamma)
        if not np.isfinite(g) or g <= 0:
            raise DesignError(f"gamma: expected a finite positive bound, got {gamma!r}")
        g2 = g * g * k  # type: ignore[assignment]   # a number here, a cvxpy Variable above
        objective = cp.Minimize(cp.norm(Y, "fro"))
    M = cp.bmat([[A.T @ P + P @ A - C.T @ Y.T - Y @ C + np.eye(n), P @ Gw, -Y @ Vh],
                 [(P @ Gw).T, -g2 * np.eye(q), np.zeros((q, p))],
                 [(-Y @ Vh).T, np.zeros((p, q)), -g2 * np.eye(p)]])
    cons = [_sym(M) << -LMI_EPS * np.eye(n + q + p), P >> np.eye(n)]
    prob = cp.Problem(objective, cons)
    status = _solve(prob, "hinf_filter")
    Pv = np.asarray(P.value)
    L = np.linalg.solve(Pv, np.asarray(Y.value))
    bound = float(np.sqrt(float(g2.value) / k)) if gamma is None else float(gamma)  # type: ignore[arg-type]
    return LMIObserverResult(L=L, poles=np.linalg.eigvals(A - L @ C), P=Pv, bound=bound,
                             status=status)
