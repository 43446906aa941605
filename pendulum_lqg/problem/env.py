"""The Gymnasium environments' keyword layer, declared: the scenario settings the env offers
(:class:`~pendulum_lqg.problem.scenario.ScenarioSettings`, ``"env"`` among their front ends) and the
env's own (:class:`EnvSettings`: the noise flattened into keywords, the observation, the reward, the
model).

:func:`env_keywords` is the one list of the environments' keywords;
``pendulum_lqg/envs/keywords.py`` (its ``EnvKeywords`` TypedDict, which type checkers see in
``CartPoleLQGEnv(**keywords)``) and the docs' keyword table are generated from it
(:mod:`~pendulum_lqg.problem.generate`).
"""

from __future__ import annotations

from typing import Annotated, Literal

import msgspec

from pendulum_lqg.problem import defaults
from pendulum_lqg.problem.declare import Declared, NonNegative, Positive, declared, setting

_ENV = ("env",)
_DENSITY = "units²·s"


class EnvSettings(msgspec.Struct, frozen=True, kw_only=True, forbid_unknown_fields=True):
    """The environment's own keywords."""

    observation_mode: Annotated[Literal["measurement", "state"], setting(
        "the observation: the measurement y = [p, θ] or the state", fronts=_ENV)] = "measurement"
    noise_scale: Annotated[NonNegative, setting(
        "multiplies both noises' standard deviations (0: noise-free)", metavar="S",
        fronts=("env", "run", "theory"))] = defaults.NOISE_SCALE
    process_noise: Annotated[Literal["state", "force"], setting(
        "'state' (F = I₄, the lecture) or 'force' (generalised forces on slider and hinge, "
        "redrawn every physics step)", fronts=_ENV)] = "state"
    process_density: Annotated[NonNegative | tuple[NonNegative, ...] | None, setting(
        "spectral density W: 4 entries for 'state' (default 4e-4 each); required, with 2 "
        "entries (N²·s, N²m²·s), for 'force'", unit=_DENSITY, fronts=_ENV)] = None
    measurement_variance: Annotated[NonNegative | tuple[NonNegative, ...], setting(
        "per-sample covariance V of [p, θ] (one number: both)", unit="m², rad²",
        fronts=_ENV)] = defaults.MEASUREMENT_VARIANCE
    reward_scale: Annotated[Positive, setting(
        "s of the reward r = exp(−c / (s·T))", unit="J/s", fronts=_ENV)] = defaults.REWARD_SCALE
    model_overrides: Annotated[dict[str, float] | None, setting(
        "changes of the simulated plant (model mismatch): pole_mass, cart_mass [kg], "
        "pole_length [m], their *_scale, force_limit [N], timestep [s]", fronts=_ENV)] = None
    plant: Annotated[str | None, setting(
        "the plant: a shipped NAME (cartpole, double-cartpole) or a plant FILE, whose file holds "
        "its period, x0, noise, cost and limits (default: the cart-pole); kept one release: "
        "'mujoco', 'linear-zoh' or 'linear-euler' name the simulator", fronts=_ENV)] = None
    simulator: Annotated[Literal["mujoco", "linear-zoh", "linear-euler"] | None, setting(
        "how the plant is simulated: MuJoCo, or its linearisation discretised exactly (ZOH) or by "
        "forward Euler (default: MuJoCo for a MuJoCo model, ZOH for matrices)",
        fronts=_ENV)] = None
    model_path: Annotated[str | None, setting(
        "another cart-pole MJCF (default: the shipped model)", fronts=_ENV)] = None
    randomize: Annotated[dict[str, tuple[float, float]] | None, setting(
        "per-episode uniform scales, e.g. {'pole_mass_scale': (0.8, 1.2)}; keys "
        "pole_mass_scale, pole_length_scale, cart_mass_scale", fronts=_ENV)] = None


def env_keywords() -> list[Declared]:
    """Every keyword of the environments, declared: the scenario's then the env's own."""
    from pendulum_lqg.problem.scenario import ScenarioSettings

    return [d for d in declared(ScenarioSettings) if "env" in d.fronts] + declared(EnvSettings)
