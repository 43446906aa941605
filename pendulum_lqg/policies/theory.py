r"""Theory beside simulation: a linear policy's closed loop in closed form, stationary and per episode.

For a linear plant sampled at the control period T, a linear estimator and ``u = −K x̂`` driven by
the scenario's Gaussian noise, the plant state ``x`` and the estimator's state ``ξ`` form one
linear system (docs/theory.md §4.3)

.. math::
    s_{n+1} = \mathcal{A}\, s_n + \mathcal{B}\, e_n, \qquad s = \begin{bmatrix} x \\ \xi
    \end{bmatrix}, \quad e = \begin{bmatrix} w \\ v \end{bmatrix}, \quad
    \operatorname{E}[e e^T] = N = \begin{bmatrix} W T & 0 \\ 0 & V \end{bmatrix} s^2,

with W the state-noise density, V the per-sample measurement covariance and s the noise scale —
the jump ``δx ~ N(0, W·T)`` the simulator adds at the end of every period and the ``v`` of
``y = C x + v`` (:mod:`pendulum_lqg.core.noise`). When the spectral radius of
:math:`\mathcal{A}` is below 1 the loop is stable and its stationary covariance solves one
discrete Lyapunov equation :math:`\Sigma = \mathcal{A}\Sigma\mathcal{A}^T + \mathcal{B}N
\mathcal{B}^T` (``scipy.linalg.solve_discrete_lyapunov``); the spread of x, of the force u and of
the estimation error ``x̂ − x`` and the mean cost per second follow from Σ. Nothing here runs a
simulation: :func:`policy_theory` is the closed-form companion of a Monte Carlo run with the
limits switched off (``theta_max``, ``track_limit`` and ``force_limit`` at ``inf``,
:func:`pendulum_lqg.core.rules.limits`); with the limits on, the loop is not linear and the
numbers say how far the limits are from the stationary spread.

Definitions match the simulation's metrics (:mod:`pendulum_lqg.core.metrics`): ``std`` and the
estimation error are taken at the sampling instants (the state the controller sees, after the
period's noise jump), ``rms`` and the cost rate average over the physics steps of a period as the
metrics' integrals do (``J = ∫ xᵀ diag(Q) x + R u² dt``, the rectangle rule at the physics step,
:func:`pendulum_lqg.core.rules.period_integrals`). :func:`episode_theory` gives the expected RMS
over one episode from x₀ and x̂₀ (mean and covariance through the loop, in closed form; the
time-varying Kalman filter through its gains, the stationary loop at its steady gain).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.names import LECTURE_POLICIES

if TYPE_CHECKING:
    from pendulum_lqg.core.scenario import Scenario
    from pendulum_lqg.model.plant import Plant
    from pendulum_lqg.policies.lqg import DesignSpec


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
class ClosedLoopTheory:
    """The stationary closed loop of one policy (see the module docstring for definitions).

    Attributes
    ----------
    name : the policy; plant : ``linear-zoh`` or ``linear-euler``
    eigenvalues : (n+q,) of the augmented loop; spectral_radius ; stable : radius < 1
    std, rms : per state name, the stationary std at the sampling instants and the RMS over the
        physics steps (inf when unstable)
    u_std : std of the force [N]; estimate_error_std : per state name, of ``x̂ − x``
    cost_rate : stationary ``E[xᵀQx + R u²]`` averaged over the period [1/s of J];
        cost_J : ``cost_rate · duration``, the J a stationary episode of the scenario's length
        implies (the simulation's J adds the start-up transient from x₀)
    covariance : Σ (n+q, n+q) of ``[x; ξ]`` at the sampling instants (nan when unstable)
    episode : the expected RMS over an episode from the scenario's x₀ and x̂₀
        (:class:`EpisodeTheory`), or ``None`` when not asked for
    limits : ``{"theta_max", "track_limit", "force_limit"}`` of the scenario on the plant
    notes : what the theory assumed (steady-state gains)
    """

    name: str
    plant: str
    eigenvalues: np.ndarray
    spectral_radius: float
    stable: bool
    std: dict[str, float]
    rms: dict[str, float]
    u_std: float
    estimate_error_std: dict[str, float]
    cost_rate: float
    cost_J: float
    duration: float
    covariance: np.ndarray = field(repr=False)
    limits: dict[str, float] = field(default_factory=dict)
    notes: tuple[str, ...] = ()
    state_names: tuple[str, ...] = ("p", "theta", "p_dot", "theta_dot")
    units: tuple[str, ...] = ("m", "rad", "m/s", "rad/s")
    episode: EpisodeTheory | None = None

    @property
    def verdict(self) -> str:
        """One plain line: stable or not, and the stationary spread against the limits."""
        if not self.stable:
            return (f"unstable: spectral radius {self.spectral_radius:.4g} ≥ 1, the states grow "
                    "without bound")
        parts, beyond = [], []
        checks = [("track_limit", 0, "the track"), ("theta_max", 1, "θ_max")]
        for key, i, what in checks[:len(self.state_names)]:
            name, unit = self.state_names[i], self.units[i]
            s, lim = self.std[name], self.limits.get(key, float("inf"))
            label, u = ("θ" if name == "theta" else name), (f" {unit}" if unit else "")
            if not np.isfinite(lim):
                parts.append(f"std {label} = {s:.2g}{u} (no limit)")
            elif s > lim:
                beyond.append(f"stationary std {label} = {s:.2g}{u} exceeds {what} ±{lim:g}{u}")
            else:
                parts.append(f"std {label} = {s:.2g}{u} ({what} ±{lim:g}{u} is "
                             f"{lim / s:.1f} σ away)" if s > 0 else f"std {label} = 0")
        return "stable; " + "; ".join(beyond + parts)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: ``spectral_radius, stable, std.{p, theta, p_dot, theta_dot}, u_std,
        estimate_error_std.{…}, cost_rate`` and more (eigenvalues as ``[re, im]``)."""
        from pendulum_lqg.util.jsonio import plain

        return {"plant": self.plant, "spectral_radius": self.spectral_radius,
                "stable": self.stable, "std": dict(self.std), "rms": dict(self.rms),
                "u_std": self.u_std, "estimate_error_std": dict(self.estimate_error_std),
                "cost_rate": self.cost_rate, "cost_J": self.cost_J, "duration": self.duration,
                "limits": plain(self.limits, nonfinite_as_string=True), "verdict": self.verdict,
                "notes": list(self.notes), "eigenvalues": plain(self.eigenvalues),
                **({"episode": self.episode.to_dict()} if self.episode is not None else {})}


@dataclass(frozen=True)
class StationaryProblem:
    """Everything :func:`stationary` needs, as matrices: plant ``(kind, Phi, Gamma)`` as in
    :func:`period_samples` with ``k`` physics steps of ``h`` seconds, output ``C``, gain ``K``,
    the estimator, per-period noise covariances ``Wd`` (n, n) and ``V`` (p, p), the cost weights
    ``Q`` (n, n) and ``R`` (m, m)."""

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


@dataclass(frozen=True)
class EpisodeStart:
    """How an episode starts: ``x₀ ~ N(x0, diag(x0_std²))`` (n,) each, and the initial estimate
    ``x̂₀ = x_hat0`` (n,), or ``x̂₀ = x₀`` itself when ``x_hat0`` is ``None`` (the scenario's
    ``estimate0 = "true"``)."""

    x0: np.ndarray
    x0_std: np.ndarray
    x_hat0: np.ndarray | None = None


@dataclass(frozen=True)
class EpisodeTheory:
    """The expected RMS over one episode from its start (:func:`episode_theory`), in the
    simulated metrics' own definitions (:mod:`pendulum_lqg.core.metrics`).

    Attributes
    ----------
    rms : per state name, ``sqrt`` of the mean over the episode's physics steps (the state at the
        start of each step, periods ``skip … periods−1``) of ``E[x_i²]``
    u_rms : ``sqrt`` of the mean over those periods of ``E[u²]`` (the first input)
    estimate_error_rms : per state name, ``sqrt`` of the mean over those periods' samples of
        ``E[(x̂ − x)²]``
    cost_J : ``E[J]`` over the whole episode (every period: J has no burn-in)
    periods : control periods of the episode; skip : the first periods left out of the RMS
    burn_in : ``skip`` in seconds
    """

    rms: dict[str, float]
    u_rms: float
    estimate_error_rms: dict[str, float]
    cost_J: float
    periods: int
    skip: int
    burn_in: float

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: ``rms.{state}, u_rms, estimate_error_rms.{state}, cost_J, periods, skip,
        burn_in``."""
        return {"rms": dict(self.rms), "u_rms": self.u_rms,
                "estimate_error_rms": dict(self.estimate_error_rms), "cost_J": self.cost_J,
                "periods": self.periods, "skip": self.skip, "burn_in": self.burn_in}


def start_moments(loop: AugmentedLoop, est: LinearEstimator, start: EpisodeStart,
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Mean (n+q,) and covariance (n+q, n+q) of ``s₀ = [x₀; ξ₀]`` with ``ξ₀ = S x̂₀``
    (:meth:`LinearEstimator.start_map`)."""
    x0 = np.asarray(start.x0, dtype=float)
    n = x0.shape[0]
    S = est.start_map(n)
    D0 = np.diag(np.asarray(start.x0_std, dtype=float) ** 2)
    if start.x_hat0 is None:                    # x̂₀ = x₀: ξ₀ moves with x₀
        J = np.vstack([np.eye(n), S])
        return J @ x0, J @ D0 @ J.T
    m0 = np.concatenate([x0, S @ np.asarray(start.x_hat0, dtype=float)])
    P0 = np.zeros((loop.A.shape[0],) * 2)
    P0[:n, :n] = D0
    return m0, P0


def mean_second_moment(A: np.ndarray, Sigma: np.ndarray, G: np.ndarray, a: int, b: int) -> Any:
    r"""The mean over periods ``a … b−1`` of :math:`E[s_k s_k^T] = \Sigma + A^k G A^{kT}`.

    With :math:`X = A X A^T + G` (one Lyapunov equation, A stable) the finite sum is
    :math:`\sum_{j<L} A^j G A^{jT} = X - A^L X A^{LT}`, so the mean is
    :math:`\Sigma + A^a (X - A^L X A^{LT}) A^{aT} / L` with ``L = b − a`` — exact for any
    horizon (the ceiling of 10⁸ periods included) at the cost of two matrix powers.
    """
    from scipy.linalg import solve_discrete_lyapunov

    L = b - a
    X = solve_discrete_lyapunov(A, G)
    AL, Aa = np.linalg.matrix_power(A, L), np.linalg.matrix_power(A, a)
    out = Sigma + Aa @ (X - AL @ X @ AL.T) @ Aa.T / L
    return 0.5 * (out + out.T)


def episode_theory(loop: AugmentedLoop, maps: list[np.ndarray], N: np.ndarray,
                   Sigma: np.ndarray | None, start: EpisodeStart, *, prob: StationaryProblem,
                   periods: int, skip: int = 0,
                   state_names: Sequence[str] = ("p", "theta", "p_dot", "theta_dot"),
                   ) -> EpisodeTheory:
    r"""The expected RMS over an episode of ``periods`` control periods from ``start``.

    The loop :math:`s_{k+1} = \mathcal{A}s_k + \mathcal{B}e_k` carries the mean
    :math:`m_k = \mathcal{A}^k m_0` and the covariance :math:`P_{k+1} = \mathcal{A}P_k
    \mathcal{A}^T + \mathcal{B}N\mathcal{B}^T`; with the stationary Σ,
    :math:`E[s_k s_k^T] = m_k m_k^T + P_k = \Sigma + \mathcal{A}^k (P_0 - \Sigma + m_0 m_0^T)
    \mathcal{A}^{kT}`. Its mean over the periods ``skip … periods−1``
    (:func:`mean_second_moment`) goes through the read-outs of the stationary theory
    (:func:`readouts`): x at the start of every physics step, u and ``x̂ − x`` at every sample —
    the samples the simulated ``rms_*`` take. ``Sigma`` ``None`` (an unstable loop): every value
    is ``inf``. ``cost_J`` is ``E[J]`` over all the periods.
    """
    skip = min(max(skip, 0), periods - 1)
    period = prob.k * prob.h
    burn = skip * period
    if Sigma is None:
        inf = float("inf")
        return EpisodeTheory(rms=dict.fromkeys(state_names, inf), u_rms=inf,
                             estimate_error_rms=dict.fromkeys(state_names, inf), cost_J=inf,
                             periods=periods, skip=skip, burn_in=burn)
    m, P = start_moments(loop, prob.estimator, start)
    sums: dict[int, list[Any]] = {0: [0.0] * 3, skip: [0.0] * 3}   # x, u, e summed from 0, skip
    sched = prob.estimator.schedule[:periods]       # the periods of a varying gain, one by one
    for a, est in enumerate(sched):
        la = augmented_loop(loop.Phi, loop.Gamma, prob.C, prob.K, est)
        r = readouts(la, maps, N, P + np.outer(m, m))
        for b in {0, skip} if a >= skip else {0}:
            sums[b] = [s + v for s, v in zip(sums[b], (r.x_steps, r.u, r.error), strict=True)]
        m, P = la.A @ m, la.A @ P @ la.A.T + la.B @ N @ la.B.T
    rest, G = periods - len(sched), P - Sigma + np.outer(m, m)
    for b in {0, skip} if rest > 0 else ():          # then the steady loop, in closed form
        a = max(b - len(sched), 0)
        r = readouts(loop, maps, N, mean_second_moment(loop.A, Sigma, G, a, rest))
        sums[b] = [s + v * (rest - a) for s, v in zip(sums[b], (r.x_steps, r.u, r.error),
                                                      strict=True)]
    whole, window = ([v / (periods - b) for v in sums[b]] for b in (0, skip))
    cost = periods * period * float(np.trace(prob.Q @ whole[0]) + np.trace(prob.R @ whole[1]))
    values = window
    if not (all(np.all(np.isfinite(v)) for v in values) and math.isfinite(cost)):
        raise ConfigError("x0: the episode's second moments overflow; the theory needs a "
                          "smaller initial state or noise")
    return EpisodeTheory(rms=_per_state(window[0], state_names, True),
                         u_rms=float(np.sqrt(max(window[1][0, 0], 0.0))),
                         estimate_error_rms=_per_state(window[2], state_names, True),
                         cost_J=cost, periods=periods, skip=skip, burn_in=burn)


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
    period's physics steps (n, n), u (m, m) and the estimation error ``x̂ − x`` (n, n)."""

    z: np.ndarray
    x_steps: np.ndarray
    u: np.ndarray
    error: np.ndarray


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
    return Readouts(z=cov_z, x_steps=cov_avg, u=cov_z[n:, n:], error=cov_e)


def _per_state(cov: np.ndarray, names: Sequence[str], finite: bool) -> dict[str, float]:
    """The square roots of ``cov``'s diagonal by state name (inf when not ``finite``)."""
    d = np.sqrt(np.clip(np.diag(cov), 0.0, None)) if finite else np.full(len(names), np.inf)
    return {s: float(v) for s, v in zip(names, d, strict=True)}


def stationary(prob: StationaryProblem, *, name: str, duration: float,
               limits: dict[str, float] | None = None,
               state_names: Sequence[str] = ("p", "theta", "p_dot", "theta_dot"),
               units: Sequence[str] = ("m", "rad", "m/s", "rad/s"),
               start: EpisodeStart | None = None, burn_in: float = 0.0) -> ClosedLoopTheory:
    """The stationary closed loop of ``prob``: eigenvalues, one discrete Lyapunov equation, the
    spreads and the cost rate (:class:`ClosedLoopTheory`); with ``start``, also the expected RMS
    over an episode of ``duration`` seconds that starts there (:func:`episode_theory`, the
    periods before ``burn_in`` seconds left out of the RMS)."""
    from scipy.linalg import solve_discrete_lyapunov

    maps, Phi_T, Gamma_T = period_samples(prob.kind, prob.Phi, prob.Gamma, prob.k)
    loop = augmented_loop(Phi_T, Gamma_T, prob.C, prob.K, prob.estimator)
    eig = np.linalg.eigvals(loop.A)
    radius = float(np.max(np.abs(eig)))
    n = Gamma_T.shape[0]
    N = noise_covariance(prob)
    stable = radius < 1.0
    if stable:
        Sigma = solve_discrete_lyapunov(loop.A, loop.B @ N @ loop.B.T)
        Sigma = 0.5 * (Sigma + Sigma.T)
    else:
        Sigma = np.full(loop.A.shape, np.nan)
    r = readouts(loop, maps, N, Sigma)
    cost_rate = float(np.trace(prob.Q @ r.x_steps) + np.trace(prob.R @ r.u))
    if stable and not (np.all(np.isfinite(Sigma)) and math.isfinite(cost_rate)):
        raise ConfigError("noise_scale: the stationary covariance overflows; the theory needs "
                          "a smaller noise scale or smaller noise covariances")
    period = prob.k * prob.h
    ep = None
    if start is not None:
        periods = max(1, round(duration / period))
        ep = episode_theory(loop, maps, N, Sigma if stable else None, start, prob=prob,
                            periods=periods, skip=round(burn_in / period),
                            state_names=state_names)
    notes = (prob.estimator.note,) if prob.estimator.note else ()
    return ClosedLoopTheory(
        name=name, plant=prob.kind, eigenvalues=eig, spectral_radius=radius, stable=stable,
        std=_per_state(r.z[:n, :n], state_names, stable),
        rms=_per_state(r.x_steps, state_names, stable),
        u_std=float(np.sqrt(max(r.u[0, 0], 0.0))) if stable else float("inf"),
        estimate_error_std=_per_state(r.error, state_names, stable),
        cost_rate=cost_rate if stable else float("inf"),
        cost_J=cost_rate * duration if stable else float("inf"), duration=float(duration),
        covariance=Sigma, limits=dict(limits or {}), notes=notes,
        state_names=tuple(state_names), units=tuple(units), episode=ep)


def policy_theory(plant: Plant, scenario: Scenario, policy: Any, *,
                  plant_kind: str | None = None) -> ClosedLoopTheory:
    """The stationary closed loop of a built-in ``policy`` on ``plant``'s linearisation under
    ``scenario``'s noise (scaled by its ``noise.scale``), period and cost.

    ``plant_kind``: ``"linear-zoh"`` or ``"linear-euler"`` (default the scenario's plant; for
    ``"mujoco"`` the exact ZOH of the linearisation). The scenario must have state noise and no
    delay, dropout or actuator lag (one line naming the field otherwise); the limits are ignored
    (the loop is taken unsaturated) and reported for the verdict. The result's ``episode`` is the
    expected RMS over one episode of the scenario from its ``x0``, ``x0_std`` and ``estimate0``,
    the RMS after its ``burn_in`` (:func:`episode_theory`).
    """
    from pendulum_lqg.core.physics.linear import LinearPhysics
    from pendulum_lqg.core.rules import limits
    from pendulum_lqg.model.linearize import linearize
    from pendulum_lqg.model.plant import steps_per_period

    kind = plant_kind or (scenario.plant if scenario.plant != "mujoco" else "linear-zoh")
    if kind not in ("linear-zoh", "linear-euler"):
        raise ConfigError(f"plant: expected 'linear-zoh' or 'linear-euler' for the theory, got "
                          f"{kind!r}")
    _check_linear_scenario(scenario)
    k = steps_per_period(plant, scenario.control_period)
    phys = LinearPhysics(plant, kind, k)
    s2 = scenario.noise.scale * scenario.noise.scale      # inf, not OverflowError, past 1e154
    theta_max, track, u_max = limits(plant, scenario.replace(plant=kind))
    prob = StationaryProblem(
        kind=kind, Phi=phys.Phi, Gamma=phys.Gamma[:, None], k=k, h=plant.timestep,
        C=linearize(plant).C,                       # the sensors y = [p, θ] of the MJCF
        K=np.asarray(policy.K, dtype=float), estimator=linear_estimator(policy),
        Wd=scenario.noise.W * (k * plant.timestep) * s2, V=scenario.noise.V * s2,
        Q=np.diag(scenario.cost_Q), R=np.array([[scenario.cost_R]]))
    return stationary(prob, name=str(policy.name), duration=scenario.n_periods * k * plant.timestep,
                      limits={"theta_max": theta_max, "track_limit": track, "force_limit": u_max},
                      start=episode_start(scenario.x0, scenario.x0_std, scenario.estimate0, policy),
                      burn_in=scenario.burn_in)


def episode_start(x0: Any, x0_std: Any, estimate0: str, policy: Any) -> EpisodeStart:
    """The :class:`EpisodeStart` of a scenario's ``x0``, ``x0_std`` and ``estimate0`` for
    ``policy`` (``"zero"``: its own ``x_hat0``, as the runner's ``policy.reset(n)``)."""
    x0 = np.asarray(x0, dtype=float)
    if estimate0 == "true":
        return EpisodeStart(x0=x0, x0_std=np.asarray(x0_std, dtype=float))
    x_hat0 = np.asarray(getattr(policy, "x_hat0", np.zeros_like(x0)), dtype=float)
    return EpisodeStart(x0=x0, x0_std=np.asarray(x0_std, dtype=float), x_hat0=x_hat0)


def _check_linear_scenario(scenario: Scenario) -> None:
    """The theory's model is the plain sampled loop: state noise, no delay, loss or lag."""
    if scenario.noise.process != "state":
        raise ConfigError("noise: the theory takes process noise on the state (process = "
                          "'state'), as the linear plants do")
    for name in ("measurement_delay", "actuator_delay", "dropout", "actuator_tau"):
        if getattr(scenario, name):
            raise ConfigError(f"{name}: the theory covers the plain sampled loop; set {name} = 0")


def lecture_theory(names: Sequence[str] = LECTURE_POLICIES, *, plant: Plant | None = None,
                   scenario: Scenario | None = None, plant_kind: str = "linear-zoh",
                   spec: DesignSpec | None = None) -> dict[str, ClosedLoopTheory]:
    """:func:`policy_theory` of each built-in policy in ``names`` (default the lecture study's,
    :data:`~pendulum_lqg.names.LECTURE_POLICIES`) on the plant (default the shipped model) under
    ``scenario`` (default the lecture's), designed with ``spec``'s weights and poles."""
    from pendulum_lqg.core.scenario import Scenario
    from pendulum_lqg.model.plant import load_plant
    from pendulum_lqg.policies.loading import build_policy, is_plugin_ref

    plant = plant if plant is not None else load_plant()
    scenario = scenario if scenario is not None else Scenario()
    out = {}
    for name in names:
        if is_plugin_ref(name):
            raise ConfigError(f"policy: {name!r} is a plugin; the theory takes built-in linear "
                              "policies 'controller+observer'")
        policy = build_policy(name, plant=plant, scenario=scenario, spec=spec)
        out[name] = policy_theory(plant, scenario, policy, plant_kind=plant_kind)
    return out
