"""The validators of one value read from a file, and :class:`Where`, the file and key an error names.

A validator is a function ``value -> value`` that raises :class:`Invalid` with what it expected;
:meth:`Where.get` turns that into the project's one line, ``FILE: KEY: expected …, got …``, so
every schema (:mod:`pendulum_lqg.boundary.schemas`, the suite files) reports errors the same way.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from pendulum_lqg.errors import ConfigError

Validator = Callable[[Any], Any]
_MISSING: Any = object()


class Invalid(Exception):
    """A value is not what a validator expects (``expected``: e.g. ``"a positive integer"``)."""

    def __init__(self, expected: str) -> None:
        super().__init__(expected)
        self.expected = expected


def short(value: object) -> str:
    """``repr(value)`` on one line, at most 60 characters (a damaged file may hold anything)."""
    if isinstance(value, dict | list) and len(value) > 3:
        return f"{type(value).__name__} of {len(value)} items"
    text = " ".join(repr(value).split())
    return text if len(text) <= 60 else text[:57] + "..."


@dataclass(frozen=True)
class Where:
    """A place in a file: ``file`` (as the error shows it) and the keys leading there."""

    file: str
    keys: tuple[str, ...] = ()

    def at(self, key: str) -> Where:
        return Where(self.file, (*self.keys, key))

    def label(self, key: str | None = None) -> str:
        keys = self.keys if key is None else (*self.keys, key)
        return f"{self.file}: {'.'.join(keys)}" if keys else self.file

    def error(self, message: str, key: str | None = None) -> ConfigError:
        return ConfigError(f"{self.label(key)}: {message}")

    def get(self, data: Mapping[str, Any], key: str, check: Validator, *,
            default: Any = _MISSING) -> Any:
        """``data[key]`` passed through ``check``; missing (without ``default``) or invalid is one
        :class:`ConfigError` line naming the file and the key."""
        if key not in data:
            if default is _MISSING:
                raise self.error("missing", key)
            return default
        return self.check(data[key], check, key)

    def check(self, value: Any, check: Validator, key: str | None = None) -> Any:
        try:
            return check(value)
        except Invalid as exc:
            raise self.error(f"expected {exc.expected}, got {short(value)}", key) from None


def text(value: Any) -> str:
    if not isinstance(value, str) or not value:
        raise Invalid("a non-empty string")
    return value


def any_text(value: Any) -> str:
    if not isinstance(value, str):
        raise Invalid("a string")
    return value


def boolean(value: Any) -> bool:
    if not isinstance(value, bool):
        raise Invalid("true or false")
    return value


def integer(minimum: int) -> Validator:
    """An integer ≥ ``minimum`` (not a bool)."""
    what = {0: "a non-negative integer", 1: "a positive integer"}.get(minimum,
                                                                       f"an integer ≥ {minimum}")

    def check(value: Any) -> int:
        if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
            raise Invalid(what)
        return value
    return check


def exactly(expected: object) -> Validator:
    def check(value: Any) -> Any:
        if type(value) is not type(expected) or value != expected:
            raise Invalid(repr(expected))
        return value
    return check


def number(*, low: float = -math.inf, high: float = math.inf, nullable: bool = False) -> Validator:
    """A finite real number in [``low``, ``high``] (not a bool), or ``None`` if ``nullable``."""
    what = "a finite number" + ("" if (low, high) == (-math.inf, math.inf) else f" in [{low:g}, "
                                                                                f"{high:g}]")
    what += " or null" if nullable else ""

    def check(value: Any) -> Any:
        if value is None and nullable:
            return None
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise Invalid(what)
        try:
            real = float(value)
        except OverflowError:            # an integer beyond any float (JSON allows 10**400)
            raise Invalid(what) from None
        if not math.isfinite(real) or not low <= real <= high:
            raise Invalid(what)
        return value
    return check


def table(value: Any) -> dict[str, Any]:
    if not isinstance(value, dict):
        raise Invalid("a table (JSON object)")
    return value


def list_of(item: Validator, length: int | None = None) -> Validator:
    """A list (of ``length`` items, if given) whose every item passes ``item``."""
    def check(value: Any) -> list[Any]:
        what = f"a list of {length}" if length is not None else "a list"
        if not isinstance(value, list) or (length is not None and len(value) != length):
            raise Invalid(what)
        try:
            return [item(v) for v in value]
        except Invalid as exc:
            raise Invalid(f"{what} whose items are each {exc.expected}") from None
    return check


def one_of(choices: Sequence[str]) -> Validator:
    def check(value: Any) -> str:
        if not isinstance(value, str) or value not in choices:
            raise Invalid("one of " + ", ".join(choices))
        return value
    return check


__all__ = ["Invalid", "Validator", "Where", "any_text", "boolean", "exactly", "integer",
           "list_of", "number", "one_of", "short", "table", "text"]
