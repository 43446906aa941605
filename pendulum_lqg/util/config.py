"""The validators of configuration numbers: one for positive scalars (scenario, env, model
overrides, timing and the design functions) and one for small vectors (scenario, noise, design
spec)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from pendulum_lqg.errors import ConfigError, PendulumLQGError


def check_keys(where: str, table: Any, known: Sequence[str]) -> None:
    """``table`` must be a mapping whose keys are all in ``known``: the one check of every
    configuration table (experiment TOML tables, study tables, model overrides, randomisation);
    the error names ``where``, the first unknown key and lists the known ones."""
    if not isinstance(table, Mapping):
        raise ConfigError(f"{where}: expected a table, got {type(table).__name__}")
    unknown = sorted(set(table) - set(known))
    if unknown:
        raise ConfigError(f"{where}: unknown key {unknown[0]!r}; known keys: " + ", ".join(known))


def positive_number(name: str, value: Any, *,
                    error: type[PendulumLQGError] = ConfigError) -> float:
    """``value`` as a float if it is a finite positive real number (a Python or numpy int or
    float; not a bool, a string or a complex); else ``error`` naming ``name``: "dt: expected a
    finite positive number, got 0.0"."""
    if isinstance(value, bool | np.bool_) or not isinstance(value, int | float | np.integer
                                                             | np.floating) \
            or not np.isfinite(value) or value <= 0:
        raise error(f"{name}: expected a finite positive number, got {value!r}")
    return float(value)


def positive_limit(name: str, value: Any) -> float:
    """A limit [its unit] as a float: a positive number, or ``inf`` (the string ``"inf"`` too, as
    TOML and the command line may spell it) for no limit; else a :class:`ConfigError` naming
    ``name``: "theta_max: expected a positive number or inf, got -1"."""
    if isinstance(value, str) and value.strip().lower() in ("inf", "+inf", "infinity"):
        return float("inf")
    if isinstance(value, bool | np.bool_) or not isinstance(value, int | float | np.integer
                                                             | np.floating) \
            or np.isnan(value) or value <= 0:
        raise ConfigError(f"{name}: expected a positive number or inf, got {value!r}")
    return float(value)


def config_vector(name: str, value: Any, n: int, *, nonneg: bool = False,
                  ) -> tuple[float, ...]:
    """``value`` as a tuple of ``n`` finite floats; a single number is repeated ``n`` times.

    Raises :class:`ConfigError` naming ``name``: "x0: expected 4 finite numbers, got …".
    """
    kind = "non-negative " if nonneg else ""
    items = value if isinstance(value, list | tuple) else [value]
    try:
        if any(isinstance(v, bool | np.bool_ | str | bytes) for v in items) \
                or np.iscomplexobj(value):
            raise TypeError(value)
        arr = np.atleast_1d(np.asarray(value, dtype=float))
    except (TypeError, ValueError) as exc:
        raise ConfigError(f"{name}: expected {n} finite {kind}numbers, got {value!r}") from exc
    if arr.ndim != 1:                                   # nested lists: [[1, 2], …]
        raise ConfigError(f"{name}: expected {n} finite {kind}numbers, got {value!r}")
    if arr.size == 1 and n > 1:
        arr = np.full(n, arr[0])
    if arr.shape != (n,) or not np.all(np.isfinite(arr)) or (nonneg and np.any(arr < 0)):
        raise ConfigError(f"{name}: expected {n} finite {kind}numbers, got {value!r}")
    return tuple(float(a) for a in arr)
