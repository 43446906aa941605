"""The scenario's settings, each declared once: type and bounds, default, unit, help text and the
front ends that offer it (:mod:`~pendulum_lqg.problem.declare`).

:class:`ScenarioSettings` is the declaration; :class:`~pendulum_lqg.core.scenario.Scenario` takes
its defaults from it, the experiment file's ``[scenario]`` table and grid routing
(:mod:`~pendulum_lqg.problem.experiment`), the environments' keywords
(:mod:`~pendulum_lqg.problem.env`), the ``run`` / ``theory`` flags
(:mod:`~pendulum_lqg.problem.frontends`) and the docs' tables (:mod:`~pendulum_lqg.problem.generate`)
are derived from it. The cross-field rules (a delay of whole control periods, a burn-in shorter
than the episode, what a linear plant supports) are the Scenario's.
"""

from __future__ import annotations

from typing import Annotated, Literal

import msgspec

from pendulum_lqg.problem import defaults
from pendulum_lqg.problem.declare import (
    Limit,
    NonNegative,
    NonNegative4,
    Positive,
    Probability,
    Vector4,
    setting,
)

Plant = Literal["mujoco", "linear-zoh", "linear-euler"]
Estimate0 = Literal["zero", "true"]

_STATE = "m, rad, m/s, rad/s"


class ScenarioSettings(msgspec.Struct, frozen=True, kw_only=True, forbid_unknown_fields=True):
    """The scenario's settings (the noise, the model overrides and the randomisation are their own
    tables). ``grid``: a grid key of the experiment file that routes to the scenario."""

    control_period: Annotated[Positive, setting(
        "the control period T, an integer multiple of the model's physics step", unit="s",
        metavar="T", fronts=("env", "file"), grid=True)] = defaults.CONTROL_PERIOD
    duration: Annotated[Positive, setting(
        "episode length (rounded to whole control periods)", unit="s", metavar="S",
        fronts=("env", "file", "run", "theory"), grid=True)] = defaults.DURATION
    x0: Annotated[Vector4, setting(
        "mean initial state [p, θ, ṗ, θ̇]", unit=_STATE, fronts=("env", "file"))] = defaults.X0
    x0_std: Annotated[NonNegative4, setting(
        "standard deviation of the initial state around x0 (drawn per episode)", unit=_STATE,
        fronts=("env", "file"))] = defaults.X0_STD
    estimate0: Annotated[Estimate0, setting(
        "initial estimate: 'zero' (x̂₀ = 0) or 'true' (x̂₀ = x₀)",
        fronts=("file", "run", "theory"), grid=True)] = "zero"
    theta_max: Annotated[Limit, setting(
        "failure when |θ| exceeds this; inf switches the rule off", unit="rad", metavar="RAD",
        fronts=("env", "file", "run", "theory"))] = defaults.THETA_MAX
    track_limit: Annotated[Limit | None, setting(
        "failure when |p| reaches this (default: the MJCF slider range, ±2.4 m; beyond it only "
        "on a linear plant); inf switches the rule off", unit="m", metavar="M",
        fronts=("env", "file", "run", "theory"))] = None
    force_limit: Annotated[Limit | None, setting(
        "saturation |u| ≤ this (default: the MJCF ctrlrange, ±10 N; beyond it only on a linear "
        "plant); inf switches saturation off", unit="N", metavar="N",
        fronts=("env", "file", "run", "theory"))] = None
    settle_band: Annotated[Positive, setting(
        "settling time is the last time |θ| was above this band", unit="rad",
        fronts=("file",))] = defaults.SETTLE_BAND
    cost_Q: Annotated[NonNegative4, setting(
        "state weights of J = ∫ xᵀ diag(Q) x + R u² dt", fronts=("env", "file"))] = defaults.COST_Q
    cost_R: Annotated[Positive, setting(
        "input weight R of J", unit="N⁻²", fronts=("env", "file"))] = defaults.COST_R
    measurement_delay: Annotated[NonNegative, setting(
        "age of the measurement the policy receives (a whole number of control periods)",
        unit="s", metavar="S", fronts=("env", "file", "run"), grid=True)] = 0.0
    actuator_delay: Annotated[NonNegative, setting(
        "delay of the force (a whole number of control periods)", unit="s", metavar="S",
        fronts=("env", "file", "run"), grid=True)] = 0.0
    dropout: Annotated[Probability, setting(
        "probability that a measurement sample is lost (the policy gets nan)", metavar="P",
        fronts=("env", "file", "run"), grid=True)] = 0.0
    actuator_tau: Annotated[NonNegative, setting(
        "time constant of a first-order lag of the force (0: none)", unit="s", metavar="S",
        fronts=("env", "file", "run"), grid=True)] = 0.0
    plant: Annotated[Plant, setting(
        "how the plant is simulated: MuJoCo, or the linearisation discretised exactly (ZOH) or "
        "by forward Euler", fronts=("file",), grid=True)] = "mujoco"
    burn_in: Annotated[NonNegative, setting(
        "seconds at the start of an episode left out of the RMS metrics", unit="s",
        metavar="SECONDS", fronts=("file", "run", "theory"))] = 0.0
