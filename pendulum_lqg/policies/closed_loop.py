r"""The closed loop of a linear policy on a sampled linear plant, as matrices.

For a linear plant sampled at the control period T, a linear estimator and ``u = −K x̂`` driven by
the scenario's Gaussian noise, the plant state ``x`` and the estimator's state ``ξ`` form one
linear system (docs/theory.md §4.3)

.. math::
    s_{n+1} = \mathcal{A}\, s_n + \mathcal{B}\, e_n, \qquad s = \begin{bmatrix} x \\ \xi
    \end{bmatrix}, \quad e = \begin{bmatrix} w \\ v \end{bmatrix}, \quad
    \operatorname{E}[e e^T] = N = \begin{bmatrix} W T & 0 \\ 0 & V \end{bmatrix} s^2,

with W the state-noise density, V the per-sample measurement covariance and s the noise scale —
the jump ``δx ~ N(0, W·T)`` the simulator adds at the end of every period and the ``v`` of
``y = C x + v`` (:mod:`pendulum_lqg.core.noise`). This module forms :math:`\mathcal{A}`,
:math:`\mathcal{B}` and the read-outs of u and of ``x̂ − x`` (:func:`augmented_loop`), the
estimator of a built-in policy as a linear system (:func:`linear_estimator`), the states at the
physics steps inside a period (:func:`period_samples`) and the second moments of ``[x; u]`` and of
the estimation error from ``E[s sᵀ]`` (:func:`readouts`). The stationary answer is
:mod:`pendulum_lqg.policies.theory`'s, the one over an episode from its start
:mod:`pendulum_lqg.policies.episode_theory`'s.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from pendulum_lqg.errors import ConfigError


@dataclass(frozen=True)
class LinearEstimator:
    r"""An estimator as a linear system: :math:`\hat x = H\xi + D_y y`,
    :math:`\xi^+ = F\xi + G_y y + G_u u` (``full_state``: no estimator, :math:`\hat x = x`).

    Shapes for n states, p outputs, m inputs and q estimator states: F (q, q), G_y (q, p),
    G_u (q, m), H (n, q), D_y (n, p); S (q, n) maps the initial estimate to the estimator's
    initial state, :math:`\xi_0 = S\hat x_0` (``None``: :math:`\xi_0 = \hat x_0`, q = n).
    """

    F: np.ndarray
    G_y: np.ndarray
    G_u: np.ndarray
    H: np.ndarray
    D_y: np.ndarray
    full_state: bool = False
    note: str = ""
    S: np.ndarray | None = None
    #: the estimators of the first periods when the gain varies (the time-varying Kalman
    #: filter's, until its gain is the steady one); the periods after them use this one
    schedule: tuple[LinearEstimator, ...] = ()

    def start_map(self, n: int) -> np.ndarray:
        """``S`` (q, n): ξ₀ = S x̂₀ (q = 0 without an estimator)."""
        if self.full_state:
            return np.zeros((0, n))
        return np.eye(n) if self.S is None else self.S


def linear_estimator(policy: Any) -> LinearEstimator:
    """The built-in ``policy``'s estimator as a :class:`LinearEstimator`.

    Current form (steady Kalman, Luenberger): ``ξ = x̄``, ``x̂ = (I − LC)x̄ + L y``,
    ``x̄⁺ = Φ x̂ + Γ u``; predictor form: ``ξ = x̂``; reduced order: ``ξ = z``,
    ``x̂ = T⁻¹[y; z + G y]``; the time-varying Kalman filter at its steady gain. Refuses
    plugins and the delay-augmented filter with one line naming the policy.
    """
    from pendulum_lqg.core.protocol import optional_members
    from pendulum_lqg.policies import estimators as est_mod

    est = optional_members(policy).estimator
    name = getattr(policy, "name", repr(policy))
    if isinstance(est, est_mod.TrueState):
        z = np.zeros((0, 0))
        return LinearEstimator(z, z, z, z, z, full_state=True)    # shapes: augmented_loop
    if isinstance(est, est_mod.CurrentEstimator | est_mod.TimeVaryingKalman):
        tv = isinstance(est, est_mod.TimeVaryingKalman)
        L = policy.info["L"] if tv else est.gain
        steps = _gain_schedule(est, L) if tv else ()
        note = ("time-varying Kalman filter: its steady-state gain when stationary, its own "
                "gains over the episode" if tv else "")
        return replace(_current_form(est.Phi, est.Gamma, est.C, L), note=note,
                       schedule=tuple(_current_form(est.Phi, est.Gamma, est.C, g) for g in steps))
    if isinstance(est, est_mod.PredictorEstimator):
        q = est.F.shape[0]
        return LinearEstimator(est.F, est.G_y, est.G_u, np.eye(q), np.zeros((q, est.C.shape[0])))
    if isinstance(est, est_mod.ReducedOrderEstimator):
        p = est.C.shape[0]
        Ti_y, Ti_w = est.T_inv[:, :p], est.T_inv[:, p:]
        # reset: [ŷ₀; ŵ₀] = T x̂₀ and z₀ = ŵ₀ − G ŷ₀
        S = est.T[p:] - est.gain @ est.T[:p]
        return LinearEstimator(est.F, est.H_y, est.H_u, Ti_w, Ti_y + Ti_w @ est.gain, S=S)
    raise ConfigError(f"theory: policy {name!r} is not a built-in linear policy the theory "
                      "knows (plugins and kalman-delay are not)")


def _current_form(Phi: np.ndarray, Gamma: np.ndarray, C: np.ndarray, L: np.ndarray) -> Any:
    """The current-form estimator of gain L: ``ξ = x̄``, ``x̂ = (I − LC)x̄ + L y``."""
    H = np.eye(Phi.shape[0]) - L @ C
    return LinearEstimator(Phi @ H, Phi @ L, Gamma, H, L)


#: A varying gain is the steady one within this relative distance; at most MAX_SCHEDULE periods.
GAIN_TOLERANCE, MAX_SCHEDULE = 1e-12, 100_000


def _gain_schedule(est: Any, L: np.ndarray) -> list[np.ndarray]:
    """The gains ``L_a`` of a time-varying Kalman filter until they are the steady ``L``."""
    gains: list[np.ndarray] = []
    scale = float(np.max(np.abs(L))) or 1.0
    while len(gains) < MAX_SCHEDULE:
        La = est.covariances(len(gains))[2]
        if float(np.max(np.abs(La - L))) <= GAIN_TOLERANCE * scale:
            break
        gains.append(La)
    return gains


@dataclass(frozen=True)
class AugmentedLoop:
    r"""The closed loop :math:`s^+ = \mathcal{A}s + \mathcal{B}e` with the read-outs
    :math:`u = C_u s + D_u e` and :math:`\hat x - x = C_e s + D_e e` (module docstring)."""

    A: np.ndarray
    B: np.ndarray
    C_u: np.ndarray
    D_u: np.ndarray
    C_e: np.ndarray
    D_e: np.ndarray
    Phi: np.ndarray          # the period's plant (Φ_T, Γ_T) it was formed from
    Gamma: np.ndarray


def augmented_loop(Phi: np.ndarray, Gamma: np.ndarray, C: np.ndarray, K: np.ndarray,
                   est: LinearEstimator) -> AugmentedLoop:
    """Form the augmented loop of plant ``(Φ, Γ, C)`` (state noise entering as ``x⁺ = … + w``),
    estimator ``est`` and ``u = −K x̂``.

    With ``x̂ = H ξ + D_x x + D_v v`` (``D_x = D_y C``, ``D_v = D_y``; ``D_x = I``, ``D_v = 0``
    without an estimator)::

        x⁺ = (Φ − Γ K D_x) x − Γ K H ξ + w − Γ K D_v v
        ξ⁺ = (G_y C − G_u K D_x) x + (F − G_u K H) ξ + (G_y − G_u K D_v) v
    """
    n, p, m = Phi.shape[0], C.shape[0], Gamma.shape[1]
    if est.full_state:
        q = 0
        D_x, D_v = np.eye(n), np.zeros((n, p))
        F, G_y, G_u, H = np.zeros((0, 0)), np.zeros((0, p)), np.zeros((0, m)), np.zeros((n, 0))
    else:
        q = est.F.shape[0]
        D_x, D_v = est.D_y @ C, est.D_y
        F, G_y, G_u, H = est.F, est.G_y, est.G_u, est.H
    A = np.block([[Phi - Gamma @ K @ D_x, -Gamma @ K @ H],
                  [G_y @ C - G_u @ K @ D_x, F - G_u @ K @ H]])
    B = np.block([[np.eye(n), -Gamma @ K @ D_v],
                  [np.zeros((q, n)), G_y - G_u @ K @ D_v]])
    C_u = -K @ np.hstack([D_x, H])
    D_u = np.hstack([np.zeros((K.shape[0], n)), -K @ D_v])
    C_e = np.hstack([D_x - np.eye(n), H])
    D_e = np.hstack([np.zeros((n, n)), D_v])
    return AugmentedLoop(A=A, B=B, C_u=C_u, D_u=D_u, C_e=C_e, D_e=D_e, Phi=Phi, Gamma=Gamma)


def period_samples(kind: str, Phi: np.ndarray, Gamma: np.ndarray, k: int,
                   ) -> tuple[list[np.ndarray], np.ndarray, np.ndarray]:
    """The states at the start of the k physics steps of a period as ``x_j = T_j [x; u]``
    (a list of k (n, n+m) maps), and the period's ``(Φ_T, Γ_T)``, for the linear backends of
    :class:`~pendulum_lqg.core.physics.linear.LinearPhysics`: ``linear-zoh`` steps
    ``x ← Φ_h x + Γ_h u`` k times (``Phi``, ``Gamma`` per physics step); ``linear-euler`` jumps
    ``x ← Φ_T x + Γ_T u`` once, its samples on the straight line (``Phi``, ``Gamma`` per period).
    """
    n, m = Gamma.shape
    if kind == "linear-zoh":
        M, N = np.eye(n), np.zeros((n, m))
        maps = []
        for _ in range(k):
            maps.append(np.hstack([M, N]))
            M, N = Phi @ M, Phi @ N + Gamma
        return maps, M, N
    maps = [np.hstack([(1 - j / k) * np.eye(n) + (j / k) * Phi, (j / k) * Gamma])
            for j in range(k)]
    return maps, Phi, Gamma


@dataclass(frozen=True)
class StationaryProblem:
    """Everything :func:`stationary` needs, as matrices: plant ``(kind, Phi, Gamma)`` as in
    :func:`period_samples` with ``k`` physics steps of ``h`` seconds, output ``C``, gain ``K``,
    the estimator, per-period noise covariances ``Wd`` (n, n) and ``V`` (p, p), the cost weights
    ``Q`` (n, n) and ``R`` (m, m) of ``J = ∫ xᵀQx + 2xᵀNu + uᵀRu dt`` and its cross term ``N``
    (n, m; ``None``: none); ``inputs`` the names of u (``None``: ``u`` for one input, ``u1 …``)."""

    kind: str
    Phi: np.ndarray
    Gamma: np.ndarray
    k: int
    h: float
    C: np.ndarray
    K: np.ndarray
    estimator: LinearEstimator
    Wd: np.ndarray
    V: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    N: np.ndarray | None = None
    inputs: tuple[str, ...] | None = None

    def input_names(self) -> tuple[str, ...]:
        """The names of the m inputs (``inputs``, or ``u`` / ``u1 … um``)."""
        m = self.Gamma.shape[1]
        if self.inputs is not None:
            return tuple(self.inputs)
        return ("u",) if m == 1 else tuple(f"u{j + 1}" for j in range(m))

    def cost_rate(self, r: Readouts) -> float:
        """``E[xᵀQx + 2xᵀNu + uᵀRu]`` averaged over the period's physics steps, from the read-outs
        ``r`` (:func:`readouts`): the rectangle rule of the simulated cost, term by term."""
        rate = float(np.trace(self.Q @ r.x_steps) + np.trace(self.R @ r.u))
        if self.N is not None and np.any(self.N):      # the cross term: E[x_j uᵀ] at each step
            rate += 2.0 * float(np.trace(np.asarray(self.N).T @ r.xu_steps))
        return rate


def noise_covariance(prob: StationaryProblem) -> np.ndarray:
    """``N = blkdiag(Wd, V)``, the covariance of a period's ``e = [w; v]``; finite or refused."""
    n, p = prob.Wd.shape[0], prob.V.shape[0]
    N = np.block([[prob.Wd, np.zeros((n, p))], [np.zeros((p, n)), prob.V]])
    if not np.all(np.isfinite(N)):
        raise ConfigError("noise_scale: the noise covariances overflow (scale² · W or V is not "
                          "a finite number); the theory needs finite noise")
    return N


@dataclass(frozen=True)
class Readouts:
    """From ``E[s sᵀ]`` at the sampling instants: ``z = [x; u]`` there (n+m, n+m), x over the
    period's physics steps (n, n), u (m, m), the estimation error ``x̂ − x`` (n, n) and
    ``E[x uᵀ]`` over the physics steps (n, m; u is held over the period)."""

    z: np.ndarray
    x_steps: np.ndarray
    u: np.ndarray
    error: np.ndarray
    xu_steps: np.ndarray


def readouts(loop: AugmentedLoop, maps: list[np.ndarray], N: np.ndarray, second: np.ndarray,
             ) -> Readouts:
    """The :class:`Readouts` of ``second`` = ``E[s sᵀ]`` (or its mean over periods: every read-out
    is linear in it) for the loop ``loop``, the physics-step maps ``maps``
    (:func:`period_samples`) and the period's noise covariance ``N``."""
    n = maps[0].shape[0]
    # z = [x; u] at the sampling instant: x = [I 0] s, u = C_u s + D_u e (the period's v)
    Zs = np.vstack([np.hstack([np.eye(n), np.zeros((n, loop.A.shape[0] - n))]), loop.C_u])
    Ze = np.vstack([np.zeros((n, N.shape[0])), loop.D_u])
    cov_z = Zs @ second @ Zs.T + Ze @ N @ Ze.T
    cov_steps = [T @ cov_z @ T.T for T in maps]            # x at the start of each physics step
    cov_avg = sum(cov_steps) / len(cov_steps)
    cov_e = loop.C_e @ second @ loop.C_e.T + loop.D_e @ N @ loop.D_e.T
    xu = sum(T @ cov_z[:, n:] for T in maps) / len(maps)
    return Readouts(z=cov_z, x_steps=cov_avg, u=cov_z[n:, n:], error=cov_e, xu_steps=xu)


def per_state(cov: np.ndarray, names: Sequence[str], finite: bool) -> dict[str, float]:
    """The square roots of ``cov``'s diagonal by state (or input) name (inf when not
    ``finite``)."""
    d = np.sqrt(np.clip(np.diag(cov), 0.0, None)) if finite else np.full(len(names), np.inf)
    return {s: float(v) for s, v in zip(names, d, strict=True)}
