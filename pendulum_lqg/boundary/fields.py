"""The kinds of one value read from a file, and :class:`Where`, the file and key an error names.

A validator is a function ``value -> value`` that raises :class:`Invalid` with what it expected;
each here is a msgspec type (:class:`Kind`: msgspec checks the value, bools are never numbers) and
the words of what it expects. :meth:`Where.get` turns :class:`Invalid` into the project's one
line, ``FILE: KEY: expected …, got …``, so every schema (:mod:`pendulum_lqg.boundary.schemas`, the
suite files) reports errors the same way.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Annotated, Any, Literal

import msgspec

from pendulum_lqg.problem.declare import BIG
from pendulum_lqg.problem.errors import Invalid, Validator, Where, short


class Kind:
    """The validator of a msgspec type ``kind``; ``what`` it expects, in the error's words. The
    value is returned as given (an int stays an int) once msgspec has accepted it."""

    def __init__(self, kind: Any, what: str) -> None:
        self.kind, self.what = kind, what

    def __call__(self, value: Any) -> Any:
        try:
            msgspec.convert(value, self.kind)
        except msgspec.ValidationError:
            raise Invalid(self.what) from None
        return value


text = Kind(Annotated[str, msgspec.Meta(min_length=1)], "a non-empty string")
any_text = Kind(str, "a string")
boolean = Kind(bool, "true or false")
table = Kind(dict, "a table (JSON object)")
_INT64 = 2**63 - 1


def integer(minimum: int) -> Kind:
    """An integer ≥ ``minimum`` (not a bool)."""
    return Kind(Annotated[int, msgspec.Meta(ge=minimum)], {0: "a non-negative integer",
                1: "a positive integer"}.get(minimum, f"an integer ≥ {minimum}"))


def exactly(expected: object) -> Kind:
    return Kind(Literal[expected], repr(expected))


def number(*, low: float = -math.inf, high: float = math.inf, nullable: bool = False) -> Kind:
    """A finite real number in [``low``, ``high``] (not a bool), or ``None`` if ``nullable``."""
    what = "a finite number" + ("" if (low, high) == (-math.inf, math.inf) else f" in [{low:g}, "
                                                                                f"{high:g}]")
    lo, hi = max(low, -BIG), min(high, BIG)
    kind: Any = Annotated[float, msgspec.Meta(ge=lo, le=hi)] | Annotated[int, msgspec.Meta(
        ge=max(math.ceil(lo), -_INT64), le=min(math.floor(hi), _INT64))]
    return Kind(kind | None if nullable else kind, what + (" or null" if nullable else ""))


class list_of(Kind):
    """A list (of ``length`` items, if given) whose every item is an ``item``."""

    def __init__(self, item: Kind, length: int | None = None) -> None:
        what = f"a list of {length}" if length is not None else "a list"
        size = msgspec.Meta(min_length=length, max_length=length) if length is not None \
            else msgspec.Meta()
        self.size = Kind(Annotated[list, size], what)
        items: Any = list[item.kind]  # type: ignore[name-defined]  # a type made at run time
        super().__init__(Annotated[items, size], f"{what} whose items are each "
                                                          f"{item.what}")

    def __call__(self, value: Any) -> Any:
        return super().__call__(self.size(value))


def one_of(choices: Sequence[str]) -> Kind:
    return Kind(Literal[tuple(choices)], "one of " + ", ".join(choices))


__all__ = ["Invalid", "Kind", "Validator", "Where", "any_text", "boolean", "exactly", "integer",
           "list_of", "number", "one_of", "short", "table", "text"]
