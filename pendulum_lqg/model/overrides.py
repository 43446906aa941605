"""What an experiment may change of the MuJoCo cart-pole's model: fixed overrides
(:class:`ModelOverrides`, a mismatch study) and per-episode randomisation (:class:`Randomization`).

These are the scenario's data (:class:`~pendulum_lqg.core.scenario.Scenario` holds them); the plant
applies them to its MJCF spec as it compiles (:func:`pendulum_lqg.model.plant.load_plant`, and
:meth:`~pendulum_lqg.model.plant.Plant.varied` for one episode's draw).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.problem.declare import Converted, positive_number
from pendulum_lqg.problem.errors import check_keys


@dataclass(frozen=True)
class ModelOverrides:
    """Changes to the MJCF model for mismatch studies, applied by editing the spec.

    Every field is optional; ``None`` keeps the XML value. Scales multiply the XML value.

    Attributes
    ----------
    pole_mass, cart_mass : float, kg
        Mass of the pole rod / the cart body.
    pole_length : float, m
        Full length of the pole rod (hinge to tip); the rod stays uniform.
    pole_mass_scale, pole_length_scale, cart_mass_scale : float
        Multipliers of the XML values (cannot be combined with the absolute value of the same field).
    force_limit : float, N
        Symmetric actuator limit ``ctrlrange = [-force_limit, force_limit]``.
    timestep : float, s
        Physics step.
    """

    pole_mass: float | None = None
    pole_length: float | None = None
    cart_mass: float | None = None
    pole_mass_scale: float | None = None
    pole_length_scale: float | None = None
    cart_mass_scale: float | None = None
    force_limit: float | None = None
    timestep: float | None = None

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if value is None:
                continue
            positive_number(f.name, value)
        for name in ("pole_mass", "pole_length", "cart_mass"):
            if getattr(self, name) is not None and getattr(self, name + "_scale") is not None:
                raise ConfigError(f"{name}: give either {name} or {name}_scale, not both")

    @classmethod
    def from_mapping(cls, data: dict[str, object] | None) -> ModelOverrides:
        """Build from a mapping (e.g. a TOML table); unknown keys are an error listing the known."""
        data = dict(data or {})
        check_keys("model", data, [f.name for f in dataclasses.fields(cls)])
        return cls(**data)  # type: ignore[arg-type]

    def is_empty(self) -> bool:
        return all(getattr(self, f.name) is None for f in dataclasses.fields(self))


#: The parameters :class:`Randomization` can draw, in the order of their uniform draws.
RANDOMIZABLE: tuple[str, ...] = ("pole_mass_scale", "pole_length_scale", "cart_mass_scale")


def _scale_range(name: str, value: Any) -> tuple[float, float] | None:
    """A randomisation range ``[lo, hi]`` as floats with ``0 < lo ≤ hi``, or ``None``."""
    if value is None:
        return None
    try:
        lo, hi = (float(v) for v in value)
    except (TypeError, ValueError):
        raise ConfigError(f"randomize.{name}: expected [lo, hi], two numbers with "
                          f"0 < lo ≤ hi, got {value!r}") from None
    if not (np.isfinite(lo) and np.isfinite(hi) and 0 < lo <= hi):
        raise ConfigError(f"randomize.{name}: expected [lo, hi] with 0 < lo ≤ hi, got "
                          f"{value!r}")
    return lo, hi


@dataclass(frozen=True)
class Randomization:
    """Per-episode parameter randomisation of the simulated plant: ``[lo, hi]`` multipliers.

    Each episode draws, from its own child generator, three uniforms ``r`` in the fixed order of
    :data:`RANDOMIZABLE` (all three are always drawn, so adding a range does not change the others'
    draws) and simulates the plant with ``scale = lo + (hi − lo)·r`` for every range given (×1 for
    the others), on top of the scenario's own model overrides (a scale multiplies an override's
    scale or absolute value).

    Attributes
    ----------
    pole_mass_scale, pole_length_scale, cart_mass_scale : ``(lo, hi)`` with ``0 < lo ≤ hi``, or
        ``None`` (not randomised)
    """

    # each range converted to (lo, hi) floats as the instance is made (Converted: no second pass)
    pole_mass_scale: Converted[tuple[float, float] | None] = Converted(_scale_range, None)
    pole_length_scale: Converted[tuple[float, float] | None] = Converted(_scale_range, None)
    cart_mass_scale: Converted[tuple[float, float] | None] = Converted(_scale_range, None)

    @classmethod
    def from_mapping(cls, data: Any) -> Randomization:
        """From a mapping such as the TOML ``randomize = {pole_mass_scale = [0.8, 1.2]}``."""
        if isinstance(data, Randomization):
            return data
        if data is None:
            return cls()
        check_keys("randomize", data, RANDOMIZABLE)
        return cls(**dict(data))

    def is_empty(self) -> bool:
        return all(getattr(self, name) is None for name in RANDOMIZABLE)

    def scales(self, r: np.ndarray) -> dict[str, float]:
        """The multipliers of one episode from its three uniforms ``r`` in [0, 1)."""
        out = {}
        for name, ri in zip(RANDOMIZABLE, r, strict=True):
            rng = getattr(self, name)
            out[name] = 1.0 if rng is None else rng[0] + (rng[1] - rng[0]) * float(ri)
        return out

    @staticmethod
    def apply(base: ModelOverrides, scales: dict[str, float]) -> ModelOverrides:
        """``base`` with each parameter multiplied by its scale (absolute values stay absolute)."""
        changes: dict[str, float] = {}
        for scale_name, s in scales.items():
            name = scale_name.removesuffix("_scale")
            if getattr(base, name) is not None:
                changes[name] = getattr(base, name) * s
            else:
                prior = getattr(base, scale_name)
                changes[scale_name] = s if prior is None else prior * s
        return dataclasses.replace(base, **changes)
