"""The one check of a configuration table's keys. Values are checked by the problem's declarations
(:mod:`pendulum_lqg.problem.declare`, on msgspec)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from pendulum_lqg.errors import ConfigError


def check_keys(where: str, table: Any, known: Sequence[str]) -> None:
    """``table`` must be a mapping whose keys are all in ``known``: the one check of every
    configuration table (experiment TOML tables, study tables, model overrides, randomisation);
    the error names ``where``, the first unknown key and lists the known ones."""
    if not isinstance(table, Mapping):
        raise ConfigError(f"{where}: expected a table, got {type(table).__name__}")
    unknown = sorted(set(table) - set(known))
    if unknown:
        raise ConfigError(f"{where}: unknown key {unknown[0]!r}; known keys: " + ", ".join(known))
