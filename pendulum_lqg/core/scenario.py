"""The control problem every policy faces: timing, noise, initial state, failure limits, cost.

A :class:`Scenario` is validated once, when it is made; the loop, the runner and the envs take it
as it is. It holds no physical parameter of the plant — those live in the MJCF model
(:mod:`pendulum_lqg.model.plant`) — only what the experiment chooses.

Each setting is declared once, in :class:`~pendulum_lqg.problem.scenario.ScenarioSettings`; the
Scenario's fields for them are its base :class:`~pendulum_lqg.core.scenario_fields.ScenarioFields`,
written from the declarations by ``python -m pendulum_lqg.problem.generate`` (a generated module,
so type checkers see every field and its type; ``--check`` keeps it in step). A declared field is a
:class:`~pendulum_lqg.problem.declare.Coerced` descriptor: the dataclass's own ``__init__`` — and
so ``Scenario(duration=5, x0=[...])`` and :func:`dataclasses.replace` alike — sets it through the
descriptor, which stores the value converted to its declared type (an int a float, a list a
tuple, ``"inf"`` ∞) or raises the one-line error naming it. The conversion thus happens as the
frozen instance is made, with no second pass writing over it, and the Scenario stays a plain
frozen dataclass (fields, ``asdict``, ``replace``, equality, hashing, pickling unchanged). Only its
own tables (``noise``, ``overrides``, ``randomize``) and the rules across fields are written here.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

from pendulum_lqg.core.noise import NoiseModel
from pendulum_lqg.core.scenario_fields import ScenarioFields
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.model.overrides import ModelOverrides, Randomization
from pendulum_lqg.problem.declare import Converted, NonNegative, check
from pendulum_lqg.util.limits import MAX_DELAY_PERIODS, check_control_period, check_duration


@dataclass(frozen=True)
class Scenario(ScenarioFields):
    """The control problem every policy faces: timing, noise, initial state, failure rule, cost.

    The declared settings' help, unit and default are their declarations' (in
    :mod:`pendulum_lqg.problem.scenario`); the notes below add detail.

    Attributes
    ----------
    control_period : T [s], an integer multiple of the model's physics step
    duration : episode length [s] (rounded to whole control periods)
    noise : process / measurement noise model (``noise.scale`` scales both std devs)
    x0 : mean initial state ``[p, θ, ṗ, θ̇]``
    x0_std : standard deviation of the initial state around ``x0`` (drawn per episode)
    estimate0 : initial estimate, ``"zero"`` (x̂₀ = 0) or ``"true"`` (x̂₀ = x₀)
    theta_max : failure when ``|θ|`` exceeds this [rad]; ``inf`` switches the rule off
    track_limit : failure when ``|p|`` reaches this [m]; ``None`` (default) is the MJCF slider's
        ``range``, ``inf`` switches the rule off (a linear plant only: MuJoCo's rail stops the cart
        at its ``range``)
    force_limit : the actuator's saturation ``|u| ≤ force_limit`` [N]; ``None`` (default) is the
        MJCF ``ctrlrange``, ``inf`` switches saturation off (on MuJoCo only up to the model's
        ``ctrlrange``: raise that with the model override ``force_limit``). The limits in force
        are :func:`pendulum_lqg.core.rules.limits`
    settle_band : settling time is the last time ``|θ|`` was above this band [rad]
    cost_Q, cost_R : weights of ``J = ∫ xᵀ diag(Q) x + R u² dt``
    overrides : model changes of the *simulated* plant (mismatch studies); designs use the
        nominal model unless told otherwise
    plant : how the plant is simulated — ``"mujoco"`` (default), or the MJCF model's
        linearisation about the upright: ``"linear-zoh"`` (exact discretisation) or
        ``"linear-euler"`` (the lecture's own ``x ← x + T·(A x + B u) + δx`` per control period);
        same noise streams, failure rule, metrics and policies
    measurement_delay : age of the measurement the policy receives [s], a whole number of control
        periods ``d``: at sample n it gets the sample taken at n − d (NaN for n < d, when no
        sample has arrived yet)
    actuator_delay : delay of the force [s], a whole number of control periods ``d``: the force
        requested at sample n acts over period n + d (0 N over the first d periods)
    dropout : probability that a measurement sample is lost; the policy then receives
        ``[nan, nan]`` for it (the built-in estimators run their prediction only)
    actuator_tau : time constant of a first-order lag of the force [s] (0: none), at the physics
        rate: over physics step j the actuator applies the lag's exact response at the end of
        that step, ``f_j = u + (f_{j−1} − u)·e^{−h/τ}``
    randomize : per-episode parameter randomisation of the simulated plant
        (:class:`~pendulum_lqg.model.overrides.Randomization`; a mapping such as
        ``{"pole_mass_scale": (0.8, 1.2)}`` is accepted)
    burn_in : seconds at the start of an episode left out of the RMS metrics (``rms_*``,
        ``rms_u``, ``rms_est_err_*``), rounded to whole control periods and shorter than the
        episode; 0 (default) keeps every period. J, the maxima, the saturated fraction and the
        settling time always take the whole episode
    """

    noise: NoiseModel = field(default_factory=NoiseModel.lecture)
    overrides: ModelOverrides = field(default_factory=ModelOverrides)
    randomize: Converted[Randomization] = Converted(
        lambda _, value: Randomization.from_mapping(value), Randomization())

    def __post_init__(self) -> None:
        check_control_period(self.control_period)
        check_duration(self.duration, self.control_period)     # at most MAX_PERIODS periods
        check_burn_in(self.burn_in, self.control_period, self.duration)
        if not isinstance(self.noise, NoiseModel):
            raise ConfigError("noise: expected a NoiseModel")
        if not isinstance(self.overrides, ModelOverrides):
            raise ConfigError("overrides: expected a ModelOverrides")
        self._check_delays()
        if self.plant != "mujoco" and self.noise.process == "force":
            raise ConfigError(f"plant: {self.plant!r} takes process noise on the state (the "
                              "lecture model); force noise needs plant = 'mujoco'")
        if self.plant != "mujoco" and self.actuator_tau > 0:
            raise ConfigError(f"actuator_tau: the lag acts at the physics rate, which the plant "
                              f"{self.plant!r} does not have; use plant = 'mujoco'")
        if self.plant != "mujoco" and not self.randomize.is_empty():
            raise ConfigError(f"randomize: per-episode models need plant = 'mujoco', got plant = "
                              f"{self.plant!r}")

    def _check_delays(self) -> None:
        """The delays: whole control periods, at most :data:`MAX_DELAY_PERIODS`."""
        for name in ("measurement_delay", "actuator_delay"):
            periods = getattr(self, name) / self.control_period
            if not periods <= MAX_DELAY_PERIODS:
                raise ConfigError(f"{name}: expected at most {MAX_DELAY_PERIODS:,} control "
                                  f"periods (the ceiling; each is a ring-buffer slot per "
                                  f"episode), got {getattr(self, name)!r} s")
            if abs(periods - round(periods)) > 1e-9 * max(1.0, periods):
                raise ConfigError(f"{name}: expected a whole number of control periods "
                                  f"(T = {self.control_period:g} s), got {getattr(self, name)!r} s")

    @property
    def burn_in_periods(self) -> int:
        """The control periods the burn-in leaves out of the RMS metrics."""
        return round(self.burn_in / self.control_period)

    @property
    def measurement_delay_periods(self) -> int:
        """The measurement delay in control periods."""
        return round(self.measurement_delay / self.control_period)

    @property
    def actuator_delay_periods(self) -> int:
        """The actuator delay in control periods."""
        return round(self.actuator_delay / self.control_period)

    @property
    def n_periods(self) -> int:
        return max(1, round(self.duration / self.control_period))

    def replace(self, **changes: object) -> Scenario:
        return dataclasses.replace(self, **changes)  # type: ignore[arg-type]

    def to_dict(self) -> dict[str, object]:
        """The scenario as plain data, the keys in :data:`_WRITTEN_ORDER` first (the order the
        configurations have always been written in), then any later setting in declared order."""
        fields = dataclasses.asdict(self)
        d = {name: fields.pop(name) for name in _WRITTEN_ORDER} | fields
        d["overrides"] = {k: v for k, v in d["overrides"].items() if v is not None}
        d["randomize"] = {k: list(v) for k, v in d["randomize"].items() if v is not None}
        for name in ("theta_max", "track_limit", "force_limit"):   # a switched-off limit: "inf"
            if d[name] == float("inf"):                              # (JSON has no ∞; null is
                d[name] = "inf"                                      # "the model's" limit)
        if not d["burn_in"]:            # the option's default: the configurations written
            del d["burn_in"]            # before it existed keep their bytes
        return d


def check_burn_in(burn_in: object, control_period: float, duration: float) -> float:
    """``burn_in`` [s] as a float: a finite number ≥ 0 leaving at least one of the episode's
    ``max(1, round(duration / T))`` control periods (it is rounded to ``round(burn_in / T)``
    periods); otherwise a one-line :class:`ConfigError` naming ``burn_in``."""
    burn_in = float(check("burn_in", burn_in, NonNegative))
    if round(burn_in / control_period) >= max(1, round(duration / control_period)):
        raise ConfigError(f"burn_in: expected less than the episode's duration ({duration:g} s), "
                          f"got {burn_in!r} s")
    return burn_in


#: The keys of :meth:`Scenario.to_dict` in the order of the configurations written so far (the
#: dataclass puts the declared fields, :class:`ScenarioFields`, before the tables).
_WRITTEN_ORDER = ("control_period", "duration", "noise", "x0", "x0_std", "estimate0", "theta_max",
                  "track_limit", "force_limit", "settle_band", "cost_Q", "cost_R", "overrides",
                  "plant", "measurement_delay", "actuator_delay", "dropout", "actuator_tau",
                  "randomize", "burn_in")
