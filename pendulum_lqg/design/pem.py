r"""Prediction-error identification of the innovations form, consistent under feedback.

The model is the steady-state Kalman predictor of a structured linear system (Ljung, *System
Identification*, 2nd ed., §4.3 and §7):

.. math::
    \hat x_{k+1} = \Phi \hat x_k + \Gamma u_{k-d} + K_p e_k, \qquad
    e_k = y_k - C \hat x_k, \qquad \hat x_0 = x_0

with ``(Φ, Γ, C)`` the mechanical structure of :func:`~pendulum_lqg.design.sysid.structured_model`
(basis ``x = [y, ẏ]``, ``2p²`` numbers, ZOH at the period ``T``), ``d ≥ 0`` a delay of whole
periods between the force requested and its effect on the measured output, a free ``n × p``
predictor gain ``K_p`` and an initial state ``x₀`` shared by every episode. The parameters minimise
the sum of squared (weighted) innovations over every observed sample,

.. math:: V(\vartheta) = \sum_{\text{episodes}} \sum_{k \text{ observed}} \lVert W e_k(\vartheta)\rVert^2,

the direct prediction-error method. Because ``K_p`` models the noise, the estimate is consistent
when the data come from a closed loop (the input correlated with past noise), which an
output-error or a least-squares ARX fit is not (Ljung §13.4; Forssell & Ljung 1999). ``K_p`` is
the predictor gain ``Φ L`` of the current-form Kalman filter ``x̂_{k|k} = x̂_{k|k−1} + L e_k``
when the process and measurement noises are uncorrelated (:func:`filter_gain`), and the
innovations' covariance (:func:`innovation_covariance`) is ``C M Cᵀ + V`` of the model's noise.

Missing samples (``nan`` in ``y``: dropout, or not yet delivered through a measurement delay) are
handled as the Kalman predictor does: no correction that period, no term in the sum. Samples after
an episode ended (``valid`` false) freeze that episode's predictor.

The minimisation is Levenberg–Marquardt (Marquardt's diagonal scaling) on the normal equations.
The Jacobian ``∂e_k/∂ϑ = −C S_k`` comes from the exact sensitivity recursion

.. math::
    S_{k+1} = \Phi S_k + K_p \frac{\partial e_k}{\partial\vartheta}
              + \frac{\partial \Phi}{\partial\vartheta}\hat x_k
              + \frac{\partial \Gamma}{\partial\vartheta} u_{k-d}
              + \frac{\partial K_p}{\partial\vartheta} e_k,
    \qquad S_0 = \frac{\partial x_0}{\partial\vartheta}

run over every episode at once (arrays ``(E, n, P)``), with ``∂Φ/∂ϑ`` and ``∂Γ/∂ϑ`` the Fréchet
derivative of the ZOH exponential (``scipy.linalg.expm_frechet``). ``JᵀJ`` and ``Jᵀe`` are
accumulated block by block, so memory does not grow with the data (the Jacobian itself, rows ×
parameters, is never formed).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import msgspec
import numpy as np

from pendulum_lqg.design.sysid import structured_model, structured_size
from pendulum_lqg.errors import DesignError, ShapeError

__all__ = ["InnovationsModel", "PEMLayout", "filter_gain", "fit_delays", "fit_innovations",
           "innovation_covariance", "innovations", "structured_derivatives"]

#: rows of the Jacobian per product folded into ``JᵀJ``: BLAS libraries run products this small
#: on one thread, which on a shared machine is faster than a threaded product of a large block
_ROWS = 512


class InnovationsModel(msgspec.Struct, frozen=True):
    """An identified innovations-form model (see the module docstring).

    Attributes
    ----------
    params : (2p²,) the structured parameters ``[A₂₁ without its first column, A₂₂, b]``
    Phi, Gamma, C : (n, n), (n, 1), (p, n) the discrete model, ``n = 2p``
    A, B : its continuous generator (``Φ = e^{AT}``)
    K_p : (n, p) predictor gain, x0 : (n,) the shared initial state
    delay : periods between the requested force and its effect on ``y``
    dt : the period T [s]
    cost : mean of ``‖W e_k‖²`` over the observed samples at the optimum
    S : (p, p) the innovations' sample covariance
    samples : number of observed samples in the fit, iterations : Levenberg–Marquardt steps taken
    """

    params: np.ndarray
    Phi: np.ndarray
    Gamma: np.ndarray
    C: np.ndarray
    A: np.ndarray
    B: np.ndarray
    K_p: np.ndarray
    x0: np.ndarray
    delay: int
    dt: float
    cost: float
    S: np.ndarray
    samples: int
    iterations: int

    @property
    def L(self) -> np.ndarray:
        """(n, p) the current-form filter gain ``Φ⁻¹ K_p`` (:func:`filter_gain`)."""
        return filter_gain(self.Phi, self.K_p)

    def to_dict(self) -> dict[str, Any]:
        """The model as JSON-able lists and numbers."""
        out: dict[str, Any] = {k: getattr(self, k).tolist() for k in
                               ("params", "Phi", "Gamma", "A", "B", "K_p", "x0", "S")}
        out.update(L=self.L.tolist(), delay=self.delay, dt=self.dt, cost=self.cost,
                   samples=self.samples, iterations=self.iterations)
        return out


@dataclass(frozen=True)
class PEMLayout:
    """Which parameters a fit moves: the vector ``ϑ = [params[free], vec(K_p), x0]`` (the gain
    row-major, present when ``gain``; ``x0`` when ``initial``)."""

    free: np.ndarray
    n: int
    p: int
    gain: bool = True
    initial: bool = True
    index: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "index", np.flatnonzero(self.free))

    @property
    def size(self) -> int:
        return int(self.index.size + self.gain * self.n * self.p + self.initial * self.n)

    def pack(self, params: np.ndarray, K_p: np.ndarray, x0: np.ndarray) -> np.ndarray:
        parts = [params[self.index]]
        if self.gain:
            parts.append(K_p.ravel())
        if self.initial:
            parts.append(x0)
        return np.concatenate(parts)

    def unpack(self, theta: np.ndarray, params: np.ndarray, K_p: np.ndarray, x0: np.ndarray,
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(params, K_p, x0)`` with the free entries from ``theta``, the rest as given."""
        params = params.copy()
        k = self.index.size
        params[self.index] = theta[:k]
        if self.gain:
            K_p = theta[k:k + self.n * self.p].reshape(self.n, self.p)
            k += self.n * self.p
        if self.initial:
            x0 = theta[k:k + self.n]
        return params, K_p, x0


def structured_derivatives(params: np.ndarray, p: int, dt: float,
                           ) -> tuple[np.ndarray, np.ndarray]:
    """``(∂Φ/∂params, ∂Γ/∂params)`` of :func:`~pendulum_lqg.design.sysid.structured_model`,
    shapes (2p², n, n) and (2p², n, 1): the Fréchet derivative of ``exp([[A, B], [0, 0]] T)``
    in the direction of each parameter (``A``, ``B`` are affine in them)."""
    from scipy.linalg import expm_frechet

    count = structured_size(p)
    n = 2 * p
    _, _, _, A0, B0 = structured_model(np.zeros(count), p, dt)
    _, _, _, A, B = structured_model(params, p, dt)
    block = np.zeros((n + 1, n + 1))
    block[:n, :n], block[:n, n:] = A, B
    dPhi, dGamma = np.zeros((count, n, n)), np.zeros((count, n, 1))
    for j in range(count):
        _, _, _, Aj, Bj = structured_model(np.eye(count)[j], p, dt)
        direction = np.zeros((n + 1, n + 1))
        direction[:n, :n], direction[:n, n:] = Aj - A0, Bj - B0
        _, D = expm_frechet(block * dt, direction * dt)
        dPhi[j], dGamma[j] = D[:n, :n], D[:n, n:]
    return dPhi, dGamma


def _data(Y: np.ndarray, U: np.ndarray, valid: np.ndarray, delay: int,
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Checked ``(y with nan → 0, u delayed by d (zeros before the start), observed, valid)``."""
    Y, U = np.asarray(Y, dtype=float), np.asarray(U, dtype=float)
    if Y.ndim != 3 or U.ndim != 3 or U.shape[:2] != Y.shape[:2] or U.shape[2] != 1:
        raise ShapeError(f"Y, U: expected (E, H, p) and (E, H, 1) arrays, got {Y.shape} and "
                         f"{U.shape}")
    valid = np.asarray(valid, dtype=bool)
    if valid.shape != Y.shape[:2]:
        raise ShapeError(f"valid: expected shape {Y.shape[:2]}, got {valid.shape}")
    if isinstance(delay, bool) or not isinstance(delay, int | np.integer) or delay < 0:
        raise ShapeError(f"delay: expected a whole number of periods ≥ 0, got {delay!r}")
    observed = valid & np.isfinite(Y).all(axis=2)
    Ud = np.zeros_like(U)
    Ud[:, delay:] = U[:, :U.shape[1] - delay]
    return np.where(observed[..., None], Y, 0.0), Ud, observed, valid


def _accumulate(JtJ: np.ndarray, Jte: np.ndarray, J: np.ndarray, e: np.ndarray) -> None:
    """``JᵀJ += JᵀJ`` and ``Jᵀe += Jᵀe`` of rows ``J`` (r, P), ``e`` (r,), in place."""
    for start in range(0, J.shape[0], _ROWS):
        block = J[start:start + _ROWS]
        JtJ += block.T @ block
        Jte += block.T @ e[start:start + _ROWS]


def _predict(Phi: np.ndarray, Gamma: np.ndarray, C: np.ndarray, K_p: np.ndarray,
             x0: np.ndarray, data: tuple[np.ndarray, ...]) -> np.ndarray:
    """The innovations (E, H, p; 0 where not observed) of the predictor on every episode."""
    Y, Ud, observed, valid = data
    E, H, p = Y.shape
    obs = observed.astype(float)[..., None]
    ended = np.logical_not(valid.all(axis=0))
    xh, out = np.tile(x0, (E, 1)), np.zeros((E, H, p))
    for k in range(H):
        e = out[:, k] = (Y[:, k] - xh @ C.T) * obs[:, k]
        x_next = xh @ Phi.T + Ud[:, k] @ Gamma.T + e @ K_p.T
        xh = np.where(valid[:, k, None], x_next, xh) if ended[k] else x_next
    return out


def _normal_equations(Phi: np.ndarray, Gamma: np.ndarray, C: np.ndarray, K_p: np.ndarray,
                      x0: np.ndarray, data: tuple[np.ndarray, ...], weights: np.ndarray,
                      layout: PEMLayout, dPhi: np.ndarray, dGamma: np.ndarray,
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The innovations (as :func:`_predict`) and ``JᵀJ``, ``Jᵀe`` of the weighted innovations
    ``W e_k``, from the sensitivity recursion (module docstring); ``dPhi``, ``dGamma``: the
    derivatives of the free structured parameters."""
    Y, Ud, observed, valid = data
    E, H, p = Y.shape
    n, P, k_s = Phi.shape[0], layout.size, layout.index.size
    obs = observed.astype(float)[..., None]
    ended = np.logical_not(valid.all(axis=0))
    # ∂Φ/∂ϑ_j x̂ + ∂Γ/∂ϑ_j u for every j: x̂ @ Dx + u @ Du → (E, n·k_s), column a·k_s + j
    Dx = dPhi.transpose(2, 1, 0).reshape(n, n * k_s)
    Du = dGamma.transpose(2, 1, 0).reshape(1, n * k_s)
    Cw, Kw = weights[:, None] * C, K_p / weights                 # J rows of W e: −W C S
    S = np.zeros((n, E, P))                   # sensitivities, state-major: (n, E·P) products
    if layout.initial:
        S[:, :, P - n:] = np.eye(n)[:, None, :]
    steps = max(1, _ROWS // (p * E))          # periods per product folded into JᵀJ
    Jb, eb = np.zeros((steps, p, E, P)), np.zeros((steps, p, E))
    JtJ, Jte = np.zeros((P, P)), np.zeros(P)
    eye = np.arange(n)
    xh, out = np.tile(x0, (E, 1)), np.zeros((E, H, p))
    for k in range(H):
        e = out[:, k] = (Y[:, k] - xh @ C.T) * obs[:, k]
        slot = k % steps
        eb[slot] = (e * weights).T
        Jw = Jb[slot] = (-(Cw @ S.reshape(n, -1))).reshape(p, E, P) * obs[None, :, k]
        if slot == steps - 1 or k == H - 1:
            _accumulate(JtJ, Jte, Jb[:slot + 1].reshape(-1, P), eb[:slot + 1].ravel())
        x_next = xh @ Phi.T + Ud[:, k] @ Gamma.T + e @ K_p.T
        S_next = (Phi @ S.reshape(n, -1) + Kw @ Jw.reshape(p, -1)).reshape(n, E, P)
        S_next[:, :, :k_s] += (xh @ Dx + Ud[:, k] @ Du).reshape(E, n, k_s).transpose(1, 0, 2)
        if layout.gain:                       # ∂(K_p e)/∂K_p[a, b] = e_b 1_a
            S_next[:, :, k_s:k_s + n * p].reshape(n, E, n, p)[eye, :, eye, :] += e
        if ended[k]:
            alive = valid[:, k, None]
            S, xh = np.where(alive.T[..., None], S_next, S), np.where(alive, x_next, xh)
        else:
            S, xh = S_next, x_next
    return out, JtJ, Jte


def innovations(Phi: np.ndarray, Gamma: np.ndarray, C: np.ndarray, K_p: np.ndarray,
                x0: np.ndarray, Y: np.ndarray, U: np.ndarray, valid: np.ndarray, *,
                delay: int = 0) -> np.ndarray:
    """The one-step prediction errors ``e_k = y_k − C x̂_k`` (E, H, p) of the predictor
    (module docstring) on episodes ``Y`` (E, H, p; ``nan`` = missing), ``U`` (E, H, 1), ``valid``
    (E, H); ``nan`` where a sample is missing or after its episode ended."""
    data = _data(Y, U, valid, delay)
    e = _predict(np.asarray(Phi, float), np.asarray(Gamma, float), np.asarray(C, float),
                 np.asarray(K_p, float), np.asarray(x0, float), data)
    return np.where(data[2][..., None], e, np.nan)


def innovation_covariance(e: np.ndarray) -> np.ndarray:
    """(p, p) sample covariance ``mean(e eᵀ)`` of innovations ``e`` (E, H, p), over the samples
    without ``nan`` (the innovations of a predictor have zero mean)."""
    flat = np.asarray(e, dtype=float).reshape(-1, np.shape(e)[-1])
    flat = flat[np.isfinite(flat).all(axis=1)]
    if flat.shape[0] == 0:
        raise DesignError("innovation_covariance: no observed sample")
    return flat.T @ flat / flat.shape[0]


def filter_gain(Phi: np.ndarray, K_p: np.ndarray) -> np.ndarray:
    """The current-form filter gain ``L = Φ⁻¹ K_p`` (n, p) of a predictor gain ``K_p``.

    With uncorrelated process and measurement noise the steady-state Kalman predictor gain is
    ``K_p = Φ M Cᵀ (C M Cᵀ + V)⁻¹ = Φ L`` (:func:`~pendulum_lqg.design.dkalman`'s ``L_pred``),
    exactly; ``Φ = e^{AT}`` is always invertible."""
    return np.linalg.solve(np.asarray(Phi, float), np.asarray(K_p, float))


def fit_innovations(Y: np.ndarray, U: np.ndarray, valid: np.ndarray, dt: float, *,
                    params: np.ndarray, K_p: np.ndarray, x0: np.ndarray, delay: int = 0,
                    free: np.ndarray | None = None, gain: bool = True, initial: bool = True,
                    weights: np.ndarray | None = None, max_iterations: int = 60,
                    rtol: float = 1e-6, atol: float = 0.0) -> InnovationsModel:
    """The prediction-error estimate of the innovations form (module docstring) from episodes
    ``Y`` (E, H, p; ``nan`` = missing sample), ``U`` (E, H, 1) the applied force, ``valid``
    (E, H) the samples logged before each episode ended.

    Parameters
    ----------
    dt : the period T [s]
    params : (2p²,) start (and the value of the fixed entries), K_p : (n, p) start, x0 : (n,) start
    delay : whole periods between the force and its effect on ``y``
    free : (2p²,) bool, which structured parameters move (default all)
    gain : fit ``K_p`` (False: keep it, e.g. 0 for an output-error fit of open-loop data)
    initial : fit ``x0``
    weights : (p,) per-output weights ``W`` of the innovations (default 1)
    max_iterations, rtol, atol : stop after that many steps, or when a step lowers the cost
        ``Σ‖W e_k‖²`` by less than ``rtol`` of it or less than ``atol`` (with ``W`` the inverse
        innovation std, the cost is in χ² units: a step of 0.05 changes no decision)
    """
    data = _data(Y, U, valid, delay)
    p = data[0].shape[2]
    n = 2 * p
    params = np.asarray(params, float).copy()
    K_p, x0 = np.asarray(K_p, float).reshape(n, p), np.asarray(x0, float).reshape(n)
    mask = np.ones(params.size, bool) if free is None else np.asarray(free, bool)
    if params.size != structured_size(p) or mask.shape != params.shape:
        raise ShapeError(f"params, free: expected {structured_size(p)} entries, got "
                         f"{params.size} and {mask.size}")
    w = np.ones(p) if weights is None else np.asarray(weights, float)
    layout = PEMLayout(mask, n, p, gain=gain, initial=initial)
    count = int(data[2].sum())
    if count <= layout.size:
        raise DesignError(f"fit_innovations: {count} observed samples for {layout.size} parameters")

    def evaluate(theta: np.ndarray, jac: bool) -> tuple[float, tuple[Any, ...]]:
        pr, Kp, x = layout.unpack(theta, params, K_p, x0)
        Phi, Gamma, C, _, _ = structured_model(pr, p, dt)
        with np.errstate(over="ignore", invalid="ignore"):
            if jac:
                dPhi, dGamma = structured_derivatives(pr, p, dt)
                e, JtJ, Jte = _normal_equations(Phi, Gamma, C, Kp, x, data, w, layout,
                                                dPhi[layout.index], dGamma[layout.index])
            else:
                e, JtJ, Jte = _predict(Phi, Gamma, C, Kp, x, data), None, None
            cost = float(np.sum((e * w) ** 2))
        return (cost if np.isfinite(cost) else np.inf), (JtJ, Jte, pr, Kp, x, e)

    cost, best, steps = _levenberg_marquardt(evaluate, layout.pack(params, K_p, x0),
                                             max_iterations=max_iterations, rtol=rtol,
                                             atol=atol)
    _, _, pr, Kp, x, e = best
    Phi, Gamma, C, A, B = structured_model(pr, p, dt)
    e = np.where(data[2][..., None], e, np.nan)
    return InnovationsModel(params=pr, Phi=Phi, Gamma=Gamma, C=C, A=A, B=B, K_p=Kp, x0=x,
                            delay=int(delay), dt=float(dt), cost=cost / count,
                            S=innovation_covariance(e), samples=count, iterations=steps)


def _levenberg_marquardt(evaluate: Any, theta: np.ndarray, *, max_iterations: int, rtol: float,
                         atol: float) -> tuple[float, tuple[Any, ...], int]:
    """Minimise the cost of ``evaluate(θ, jac) -> (cost, (JᵀJ, Jᵀe, …))`` (``JᵀJ``, ``Jᵀe`` when
    ``jac``) from ``θ`` by Levenberg–Marquardt with Marquardt's scaling ``diag(JᵀJ)``; a trial
    step runs the predictor only, an accepted one the sensitivities too. Returns the cost, the
    last accepted evaluation and the number of accepted steps."""
    cost, best = evaluate(theta, True)
    if not np.isfinite(cost):
        raise DesignError("fit_innovations: the starting predictor diverges on the data "
                          "(start from a stabilising K_p)")
    damping, steps = 1e-3, 0
    for _ in range(max_iterations):
        JtJ, Jte = best[0], best[1]
        scale = np.maximum(np.diag(JtJ), 1e-12 * max(np.diag(JtJ).max(), 1e-300))
        try:
            step = np.linalg.solve(JtJ + damping * np.diag(scale), -Jte)
        except np.linalg.LinAlgError:
            damping *= 10.0
            continue
        trial, _ = evaluate(theta + step, False)
        if trial < cost:
            theta, steps = theta + step, steps + 1
            reduction = cost - trial
            cost, best = evaluate(theta, True)
            damping = max(damping / 3.0, 1e-10)
            if reduction <= max(rtol * cost, atol):
                break
        else:
            damping *= 4.0
            if damping > 1e10:
                break
    return cost, best, steps


def fit_delays(Y: np.ndarray, U: np.ndarray, valid: np.ndarray, dt: float, *,
               delays: range | list[int], params: np.ndarray, K_p: np.ndarray, x0: np.ndarray,
               free: np.ndarray | None = None, gain: bool = True, initial: bool = True,
               weights: np.ndarray | None = None, max_iterations: int = 60, atol: float = 0.0,
               ) -> tuple[InnovationsModel, dict[int, float]]:
    """The best :func:`fit_innovations` over the candidate ``delays`` — the lowest cost, i.e. the
    smallest innovations on the same samples (every candidate has as many parameters) — and
    every candidate's cost (``inf`` where the fit failed). The other keywords are
    :func:`fit_innovations`'s, the same start for every candidate."""
    best: InnovationsModel | None = None
    costs: dict[int, float] = {}
    for d in delays:
        try:
            model = fit_innovations(Y, U, valid, dt, delay=int(d), params=params, K_p=K_p, x0=x0,
                                    free=free, gain=gain, initial=initial, weights=weights,
                                    max_iterations=max_iterations, atol=atol)
        except DesignError:
            costs[int(d)] = float("inf")
            continue
        costs[int(d)] = model.cost
        if best is None or model.cost < best.cost:
            best = model
    if best is None:
        raise DesignError(f"fit_delays: no candidate delay in {list(delays)} gave a fit")
    return best, costs
