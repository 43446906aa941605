r"""Theory beside simulation: a linear policy's stationary closed loop in closed form.

The loop :math:`s_{n+1} = \mathcal{A} s_n + \mathcal{B} e_n` of plant, estimator and ``u = −K x̂``
(:mod:`pendulum_lqg.policies.closed_loop`, docs/theory.md §4.3) is stable when the spectral radius
of :math:`\mathcal{A}` is below 1; its stationary covariance then solves one discrete Lyapunov
equation :math:`\Sigma = \mathcal{A}\Sigma\mathcal{A}^T + \mathcal{B}N\mathcal{B}^T`
(``scipy.linalg.solve_discrete_lyapunov``); the spread of x, of each input and of the estimation
error ``x̂ − x`` and the mean cost per second follow from Σ. Nothing here runs a simulation:
:func:`policy_theory` is the closed-form companion of a Monte Carlo run with the limits switched
off (``theta_max``, ``track_limit`` and ``force_limit`` at ``inf``,
:func:`pendulum_lqg.core.rules.limits`); with the limits on, the loop is not linear and the
numbers say how far the limits are from the stationary spread.

Definitions match the simulation's metrics (:mod:`pendulum_lqg.core.metrics`): ``std`` and the
estimation error are taken at the sampling instants (the state the controller sees, after the
period's noise jump), ``rms`` and the cost rate average over the physics steps of a period as the
metrics' integrals do (``J = ∫ xᵀQx + 2xᵀNu + uᵀRu dt``, the rectangle rule at the physics step,
:func:`pendulum_lqg.core.rules.period_integrals`). The expected RMS over one episode from x₀ and
x̂₀ is :mod:`pendulum_lqg.policies.episode_theory`'s.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.names import LECTURE_POLICIES
from pendulum_lqg.policies.closed_loop import (
    StationaryProblem,
    augmented_loop,
    linear_estimator,
    noise_covariance,
    per_state,
    period_samples,
    readouts,
)
from pendulum_lqg.policies.episode_theory import (
    EpisodeStart,
    EpisodeTheory,
    by_input,
    episode_start,
    episode_theory,
)

if TYPE_CHECKING:
    from pendulum_lqg.core.scenario import Scenario
    from pendulum_lqg.model.interface import SimulatedPlant
    from pendulum_lqg.policies.lqg import DesignSpec


@dataclass(frozen=True)
class ClosedLoopTheory:
    """The stationary closed loop of one policy (see the module docstring for definitions).

    Attributes
    ----------
    name : the policy; plant : ``linear-zoh`` or ``linear-euler``
    eigenvalues : (n+q,) of the augmented loop; spectral_radius ; stable : radius < 1
    std, rms : per state name, the stationary std at the sampling instants and the RMS over the
        physics steps (inf when unstable)
    u_std : std of the force [N] (the first input); u_std_by_input : per input name with several
        inputs (empty for one); estimate_error_std : per state name, of ``x̂ − x``
    cost_rate : stationary ``E[xᵀQx + 2xᵀNu + uᵀRu]`` averaged over the period [1/s of J];
        cost_J : ``cost_rate · duration``, the J a stationary episode of the scenario's length
        implies (the simulation's J adds the start-up transient from x₀)
    covariance : Σ (n+q, n+q) of ``[x; ξ]`` at the sampling instants (nan when unstable)
    episode : the expected RMS over an episode from the scenario's x₀ and x̂₀
        (:class:`EpisodeTheory`), or ``None`` when not asked for
    limits : ``{"theta_max", "track_limit", "force_limit"}`` of the scenario on the plant, or
        for a plant file ``{"force_limit", "limit_<state>" …}`` of each state it limits
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
    u_std_by_input: dict[str, float] = field(default_factory=dict)

    @property
    def verdict(self) -> str:
        """One plain line: stable or not, and the stationary spread against the limits."""
        if not self.stable:
            return (f"unstable: spectral radius {self.spectral_radius:.4g} ≥ 1, the states grow "
                    "without bound")
        parts, beyond = [], []
        checks = [("track_limit", 0, "the track"), ("theta_max", 1, "θ_max")]
        per_state = [(key, self.state_names.index(key[len("limit_"):]), "its limit")
                     for key in self.limits if key.startswith("limit_")]
        if per_state:                           # a plant file's state_limits: each limited state
            checks = per_state
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
                "u_std": self.u_std,
                **({"u_std_by_input": dict(self.u_std_by_input)} if self.u_std_by_input else {}),
                "estimate_error_std": dict(self.estimate_error_std),
                "cost_rate": self.cost_rate, "cost_J": self.cost_J, "duration": self.duration,
                "limits": plain(self.limits, nonfinite_as_string=True), "verdict": self.verdict,
                "notes": list(self.notes), "eigenvalues": plain(self.eigenvalues),
                **({"episode": self.episode.to_dict()} if self.episode is not None else {})}


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
    cost_rate = prob.cost_rate(r)
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
        std=per_state(r.z[:n, :n], state_names, stable),
        rms=per_state(r.x_steps, state_names, stable),
        u_std=float(np.sqrt(max(r.u[0, 0], 0.0))) if stable else float("inf"),
        estimate_error_std=per_state(r.error, state_names, stable),
        cost_rate=cost_rate if stable else float("inf"),
        cost_J=cost_rate * duration if stable else float("inf"), duration=float(duration),
        covariance=Sigma, limits=dict(limits or {}), notes=notes,
        state_names=tuple(state_names), units=tuple(units), episode=ep,
        u_std_by_input=(by_input(r.u, prob) if stable
                        else dict.fromkeys(by_input(r.u, prob), float("inf"))))


def policy_theory(plant: SimulatedPlant, scenario: Scenario, policy: Any, *,
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
    _plant_kind(scenario, plant_kind)          # the scenario's errors before the policy's
    prob, lims = linear_problem(plant, scenario, np.asarray(policy.K, dtype=float),
                                linear_estimator(policy), plant_kind=plant_kind)
    return stationary(prob, name=str(policy.name), duration=scenario.n_periods * prob.k * prob.h,
                      limits=lims,
                      start=episode_start(scenario.x0, scenario.x0_std, scenario.estimate0, policy),
                      burn_in=scenario.burn_in)


def linear_problem(plant: SimulatedPlant, scenario: Scenario, K: np.ndarray, estimator: Any, *,
                   plant_kind: str | None = None,
                   ) -> tuple[StationaryProblem, dict[str, float]]:
    """The :class:`StationaryProblem` of gain ``K`` and ``estimator`` (a
    :class:`~pendulum_lqg.policies.closed_loop.LinearEstimator`) on ``plant``'s linearisation
    under ``scenario``'s noise, period and cost (:func:`policy_theory`'s rules), and the limits
    in force ``{"theta_max", "track_limit", "force_limit"}``. Any linear compensator written as
    an estimator and a gain takes this path (:mod:`pendulum_lqg.scoreboard.exact`)."""
    from pendulum_lqg.core.physics.linear import LinearPhysics
    from pendulum_lqg.core.rules import limits
    from pendulum_lqg.model.interface import steps_per_period

    kind = _plant_kind(scenario, plant_kind)
    k = steps_per_period(plant, scenario.control_period)
    phys = LinearPhysics(plant, kind, k)
    s2 = scenario.noise.scale * scenario.noise.scale      # inf, not OverflowError, past 1e154
    theta_max, track, u_max = limits(plant, scenario.replace(plant=kind))
    prob = StationaryProblem(
        kind=kind, Phi=phys.Phi, Gamma=phys.Gamma[:, None], k=k, h=plant.timestep,
        C=plant.linear_model().C,                   # the sensors y = [p, θ] of the MJCF
        K=np.asarray(K, dtype=float), estimator=estimator,
        Wd=scenario.noise.W * (k * plant.timestep) * s2, V=scenario.noise.V * s2,
        Q=np.diag(scenario.cost_Q), R=np.array([[scenario.cost_R]]))
    return prob, {"theta_max": theta_max, "track_limit": track, "force_limit": u_max}


def _plant_kind(scenario: Scenario, plant_kind: str | None) -> str:
    """The linear plant of the theory (``plant_kind``, else the scenario's; ``linear-zoh`` for
    ``mujoco``), the scenario checked to be the plain sampled loop."""
    kind = plant_kind or (scenario.plant if scenario.plant != "mujoco" else "linear-zoh")
    if kind not in ("linear-zoh", "linear-euler"):
        raise ConfigError(f"plant: expected 'linear-zoh' or 'linear-euler' for the theory, got "
                          f"{kind!r}")
    _check_linear_scenario(scenario)
    return kind


def _check_linear_scenario(scenario: Scenario) -> None:
    """The theory's model is the plain sampled loop: state noise, no delay, loss or lag."""
    if scenario.noise.process != "state":
        raise ConfigError("noise: the theory takes process noise on the state (process = "
                          "'state'), as the linear plants do")
    for name in ("measurement_delay", "actuator_delay", "dropout", "actuator_tau"):
        if getattr(scenario, name):
            raise ConfigError(f"{name}: the theory covers the plain sampled loop; set {name} = 0")


def lecture_theory(names: Sequence[str] = LECTURE_POLICIES, *, plant: SimulatedPlant,
                   scenario: Scenario | None = None, plant_kind: str = "linear-zoh",
                   spec: DesignSpec | None = None) -> dict[str, ClosedLoopTheory]:
    """:func:`policy_theory` of each built-in policy in ``names`` (default the lecture study's,
    :data:`~pendulum_lqg.names.LECTURE_POLICIES`) on ``plant`` (the shipped cart-pole:
    :func:`~pendulum_lqg.model.plant.load_plant`) under
    ``scenario`` (default the lecture's), designed with ``spec``'s weights and poles."""
    from pendulum_lqg.core.scenario import Scenario
    from pendulum_lqg.policies.loading import build_policy, is_plugin_ref

    scenario = scenario if scenario is not None else Scenario()
    out = {}
    for name in names:
        if is_plugin_ref(name):
            raise ConfigError(f"policy: {name!r} is a plugin; the theory takes built-in linear "
                              "policies 'controller+observer'")
        policy = build_policy(name, plant=plant, scenario=scenario, spec=spec)
        out[name] = policy_theory(plant, scenario, policy, plant_kind=plant_kind)
    return out
