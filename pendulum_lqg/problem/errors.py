"""The one adapter from msgspec's validation errors to the project's one-line error,
``FILE: key.path: expected …, got …``, and :class:`Where`, the file and key such a line names.

msgspec reports a failed conversion as ``Expected `float` > 0.0 - at `$.scenario.duration```; the
adapter keeps the path (as dotted keys), words the expectation from the declared type
(:func:`~pendulum_lqg.problem.declare.expected`) and shows the value found there.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping, Sequence
from typing import Any, TypeVar, get_type_hints

import msgspec

from pendulum_lqg.errors import ConfigError

T = TypeVar("T")

_AT = re.compile(r" - at `\$(?P<path>[^`]*)`$")
_UNKNOWN = re.compile(r"Object contains unknown field `(?P<key>[^`]*)`")
_MISSING = re.compile(r"Object missing required field `(?P<key>[^`]*)`")


Validator = Callable[[Any], Any]
_ABSENT: Any = object()


class Invalid(Exception):
    """A value is not what a validator expects (``expected``: e.g. ``"a positive integer"``)."""

    def __init__(self, expected: str) -> None:
        super().__init__(expected)
        self.expected = expected


class Where(msgspec.Struct, frozen=True):
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
            default: Any = _ABSENT) -> Any:
        """``data[key]`` passed through ``check``; missing (without ``default``) or invalid is one
        :class:`ConfigError` line naming the file and the key."""
        if key not in data:
            if default is _ABSENT:
                raise self.error("missing", key)
            return default
        return self.check(data[key], check, key)

    def check(self, value: Any, check: Validator, key: str | None = None) -> Any:
        try:
            return check(value)
        except Invalid as exc:
            raise self.error(f"expected {exc.expected}, got {short(value)}", key) from None


def check_keys(where: str, table: Any, known: Sequence[str]) -> None:
    """``table`` must be a mapping whose keys are all in ``known``: the one check of every
    configuration table (experiment TOML tables, study tables, model overrides, randomisation);
    the error names ``where``, the first unknown key and lists the known ones (msgspec's own
    ``forbid_unknown_fields`` names the key but not the known ones)."""
    if not isinstance(table, Mapping):
        raise ConfigError(f"{where}: expected a table, got {type(table).__name__}")
    unknown = sorted(set(table) - set(known))
    if unknown:
        raise ConfigError(f"{where}: unknown key {unknown[0]!r}; known keys: " + ", ".join(known))


def short(value: object) -> str:
    """``repr(value)`` on one line, at most 60 characters (a damaged file may hold anything)."""
    if isinstance(value, dict | list) and len(value) > 3:
        return f"{type(value).__name__} of {len(value)} items"
    text = " ".join(repr(value).split())
    return text if len(text) <= 60 else text[:57] + "..."


def convert(data: Any, struct: type[T], *, where: str = "", key: str = "") -> T:
    """``data`` (a mapping) as the declaration ``struct``; a value that does not fit is one
    :class:`ConfigError` line naming ``where`` (a file) and the key path (under ``key``, the
    table's own: ``margins.n_omega``)."""
    try:
        return msgspec.convert(data, struct)
    except msgspec.ValidationError as exc:
        raise config_error(exc, data, struct, where, key) from None


def config_error(exc: msgspec.ValidationError, data: Any, struct: type,
                 where: str = "", key: str = "") -> ConfigError:
    """The project's one line for msgspec's ``exc`` raised converting ``data`` to ``struct``."""
    from pendulum_lqg.problem.declare import expected

    message = str(exc)
    prefix = f"{where}: " if where else ""
    if m := _UNKNOWN.match(message):
        known = ", ".join(getattr(struct, "__struct_fields__", ()))
        return ConfigError(f"{prefix}{key + '.' if key else ''}{m['key']}: unknown key; known "
                           f"keys: {known}")
    if m := _MISSING.match(message):
        return ConfigError(f"{prefix}{key + '.' if key else ''}{m['key']}: missing")
    at = _AT.search(message)
    keys = re.findall(r"\.(\w+)|\[(\d+)\]", at["path"]) if at else []
    path = [k or int(i) for k, i in keys]
    value, kind = data, struct
    for step in path:                     # the value at the key, and its declared type
        if not isinstance(step, str):
            break
        try:
            value = value[step]
        except (KeyError, IndexError, TypeError):
            break
        if isinstance(step, str) and hasattr(kind, "__struct_fields__"):
            kind = get_type_hints(kind, include_extras=True).get(step, Any)
    label = ".".join([*([key] if key else []), *(k for k in path if isinstance(k, str))]) \
        or "value"
    return ConfigError(f"{prefix}{label}: expected {expected(kind)}, got {short(value)}")
