r"""Theory beside simulation: the stationary closed loop of a linear policy, in closed form.

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
:func:`pendulum_lqg.core.rules.period_integrals`). The time-varying Kalman filter is taken at its
steady state (its gain converges within a fraction of a second; the stationary loop is that of the
steady gain).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
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
    G_u (q, m), H (n, q), D_y (n, p).
    """

    F: np.ndarray
    G_y: np.ndarray
    G_u: np.ndarray
    H: np.ndarray
    D_y: np.ndarray
    full_state: bool = False
    note: str = ""


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
        L = policy.info["L"] if isinstance(est, est_mod.TimeVaryingKalman) else est.gain
        note = ("time-varying Kalman filter taken at its steady-state gain"
                if isinstance(est, est_mod.TimeVaryingKalman) else "")
        H = np.eye(est.Phi.shape[0]) - L @ est.C
        return LinearEstimator(est.Phi @ H, est.Phi @ L, est.Gamma, H, L, note=note)
    if isinstance(est, est_mod.PredictorEstimator):
        q = est.F.shape[0]
        return LinearEstimator(est.F, est.G_y, est.G_u, np.eye(q), np.zeros((q, est.C.shape[0])))
    if isinstance(est, est_mod.ReducedOrderEstimator):
        p = est.C.shape[0]
        Ti_y, Ti_w = est.T_inv[:, :p], est.T_inv[:, p:]
        return LinearEstimator(est.F, est.H_y, est.H_u, Ti_w, Ti_y + Ti_w @ est.gain)
    raise ConfigError(f"theory: policy {name!r} is not a built-in linear policy the theory "
                      "knows (plugins and kalman-delay are not)")


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
    return AugmentedLoop(A=A, B=B, C_u=C_u, D_u=D_u, C_e=C_e, D_e=D_e)


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
                "notes": list(self.notes), "eigenvalues": plain(self.eigenvalues)}


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


def stationary(prob: StationaryProblem, *, name: str, duration: float,
               limits: dict[str, float] | None = None,
               state_names: Sequence[str] = ("p", "theta", "p_dot", "theta_dot"),
               units: Sequence[str] = ("m", "rad", "m/s", "rad/s")) -> ClosedLoopTheory:
    """The stationary closed loop of ``prob``: eigenvalues, one discrete Lyapunov equation, the
    spreads and the cost rate (:class:`ClosedLoopTheory`)."""
    from scipy.linalg import solve_discrete_lyapunov

    maps, Phi_T, Gamma_T = period_samples(prob.kind, prob.Phi, prob.Gamma, prob.k)
    loop = augmented_loop(Phi_T, Gamma_T, prob.C, prob.K, prob.estimator)
    eig = np.linalg.eigvals(loop.A)
    radius = float(np.max(np.abs(eig)))
    n = Gamma_T.shape[0]
    N = np.block([[prob.Wd, np.zeros((n, prob.V.shape[0]))],
                  [np.zeros((prob.V.shape[0], n)), prob.V]])
    stable = radius < 1.0
    if stable:
        Sigma = solve_discrete_lyapunov(loop.A, loop.B @ N @ loop.B.T)
        Sigma = 0.5 * (Sigma + Sigma.T)
    else:
        Sigma = np.full(loop.A.shape, np.nan)
    # z = [x; u] at the sampling instant: x = [I 0] s, u = C_u s + D_u e (the period's v)
    Zs = np.vstack([np.hstack([np.eye(n), np.zeros((n, loop.A.shape[0] - n))]), loop.C_u])
    Ze = np.vstack([np.zeros((n, N.shape[0])), loop.D_u])
    cov_z = Zs @ Sigma @ Zs.T + Ze @ N @ Ze.T
    cov_steps = [T @ cov_z @ T.T for T in maps]            # x at the start of each physics step
    cov_avg = sum(cov_steps) / len(cov_steps)
    cov_u = cov_z[n:, n:]
    cov_e = loop.C_e @ Sigma @ loop.C_e.T + loop.D_e @ N @ loop.D_e.T
    cost_rate = float(np.trace(prob.Q @ cov_avg) + np.trace(prob.R @ cov_u))

    def per_state(cov: np.ndarray) -> dict[str, float]:
        d = np.sqrt(np.clip(np.diag(cov), 0.0, None)) if stable else np.full(n, np.inf)
        return {s: float(v) for s, v in zip(state_names, d, strict=True)}

    notes = (prob.estimator.note,) if prob.estimator.note else ()
    return ClosedLoopTheory(
        name=name, plant=prob.kind, eigenvalues=eig, spectral_radius=radius, stable=stable,
        std=per_state(cov_z[:n, :n]), rms=per_state(cov_avg),
        u_std=float(np.sqrt(max(cov_u[0, 0], 0.0))) if stable else float("inf"),
        estimate_error_std=per_state(cov_e), cost_rate=cost_rate if stable else float("inf"),
        cost_J=cost_rate * duration if stable else float("inf"), duration=float(duration),
        covariance=Sigma, limits=dict(limits or {}), notes=notes,
        state_names=tuple(state_names), units=tuple(units))


def policy_theory(plant: Plant, scenario: Scenario, policy: Any, *,
                  plant_kind: str | None = None) -> ClosedLoopTheory:
    """The stationary closed loop of a built-in ``policy`` on ``plant``'s linearisation under
    ``scenario``'s noise (scaled by its ``noise.scale``), period and cost.

    ``plant_kind``: ``"linear-zoh"`` or ``"linear-euler"`` (default the scenario's plant; for
    ``"mujoco"`` the exact ZOH of the linearisation). The scenario must have state noise and no
    delay, dropout or actuator lag (one line naming the field otherwise); the limits are ignored
    (the loop is taken unsaturated) and reported for the verdict.
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
    s2 = scenario.noise.scale ** 2
    theta_max, track, u_max = limits(plant, scenario.replace(plant=kind))
    prob = StationaryProblem(
        kind=kind, Phi=phys.Phi, Gamma=phys.Gamma[:, None], k=k, h=plant.timestep,
        C=linearize(plant).C,                       # the sensors y = [p, θ] of the MJCF
        K=np.asarray(policy.K, dtype=float), estimator=linear_estimator(policy),
        Wd=scenario.noise.W * (k * plant.timestep) * s2, V=scenario.noise.V * s2,
        Q=np.diag(scenario.cost_Q), R=np.array([[scenario.cost_R]]))
    return stationary(prob, name=str(policy.name), duration=scenario.n_periods * k * plant.timestep,
                      limits={"theta_max": theta_max, "track_limit": track, "force_limit": u_max})


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
