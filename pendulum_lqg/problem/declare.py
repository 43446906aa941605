"""Declaring a setting once — its type, bounds, default, unit and help text — on msgspec.

A setting is a field of a frozen :class:`msgspec.Struct`; its type is one of the constrained types
below (``Positive``, ``Limit``, :func:`vector` …) annotated with :func:`setting`, which carries the
help text, the unit and the front ends that offer it::

    duration: Annotated[Positive, setting("episode length", unit="s")] = defaults.DURATION

Every front end reads the declaration (:mod:`~pendulum_lqg.problem.frontends`,
:mod:`~pendulum_lqg.problem.generate`), and every value is checked by msgspec through one path,
:func:`check` (a single value) or :func:`~pendulum_lqg.problem.errors.convert` (a table): the
bounds are msgspec's ``Meta`` constraints, and the words of the one-line error
(``expected a finite positive number``) are derived from them by :func:`expected`.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable
from functools import cache
from typing import Annotated, Any, Generic, Literal, TypeVar, get_args, get_origin

import msgspec

from pendulum_lqg.errors import ConfigError, PendulumLQGError

#: The largest float: a bound ``le=BIG`` / ``ge=-BIG`` refuses ±inf (and nan fails every bound).
BIG = sys.float_info.max

Finite = Annotated[float, msgspec.Meta(ge=-BIG, le=BIG)]
NonNegative = Annotated[float, msgspec.Meta(ge=0.0, le=BIG)]
Positive = Annotated[float, msgspec.Meta(gt=0.0, le=BIG)]
#: A limit: a positive number, or ``inf`` for none.
Limit = Annotated[float, msgspec.Meta(gt=0.0)]
Probability = Annotated[float, msgspec.Meta(ge=0.0, lt=1.0)]
PositiveInt = Annotated[int, msgspec.Meta(ge=1)]
NonNegativeInt = Annotated[int, msgspec.Meta(ge=0)]

#: The front ends a setting is offered by: the Gymnasium env's keywords, the experiment file's
#: table, the ``run`` command's flags and the ``theory`` command's flags.
FRONTS = ("env", "file", "run", "theory")


#: Four numbers (a state vector [p, θ, ṗ, θ̇], its weights), and four numbers ≥ 0.
Vector4 = Annotated[tuple[Finite, ...], msgspec.Meta(min_length=4, max_length=4)]
NonNegative4 = Annotated[tuple[NonNegative, ...], msgspec.Meta(min_length=4, max_length=4)]


def vector(n: int, item: Any = Finite) -> Any:
    """The type of ``n`` numbers of type ``item`` (a tuple)."""
    return Annotated[tuple[item, ...], msgspec.Meta(min_length=n, max_length=n)]


def setting(help: str, *, unit: str = "", metavar: str | None = None,
            fronts: tuple[str, ...] = FRONTS, **extra: Any) -> msgspec.Meta:
    """The declaration of one setting: its ``help`` text (one phrase, no default — that is the
    field's), its ``unit`` and the ``fronts`` that offer it (a subset of :data:`FRONTS`)."""
    return msgspec.Meta(description=help, extra={"unit": unit, "metavar": metavar,
                                                 "fronts": fronts, **extra})


class Declared(msgspec.Struct, frozen=True):
    """One declared setting as the front ends read it."""

    name: str
    type: Any            # the constrained type (without the setting's Meta)
    default: Any
    help: str
    unit: str
    metavar: str | None
    fronts: tuple[str, ...]
    grid: bool = False       # also a key of the experiment file's [grid] (routed to its table)

    @property
    def flag(self) -> str:
        return "--" + self.name.replace("_", "-")


def declared(struct: type[msgspec.Struct]) -> list[Declared]:
    """The settings declared by ``struct``, in order."""
    hints = _hints(struct)
    out = []
    for field in msgspec.structs.fields(struct):
        name, default = field.name, field.default
        kind, info = _split(hints[name])
        out.append(Declared(name, kind, default, info.description or "",
                            (info.extra or {}).get("unit", ""), (info.extra or {}).get("metavar"),
                            (info.extra or {}).get("fronts", FRONTS),
                            (info.extra or {}).get("grid", False)))
    return out


def _hints(struct: type) -> dict[str, Any]:
    from typing import get_type_hints

    return get_type_hints(struct, include_extras=True)


def _split(kind: Any) -> tuple[Any, msgspec.Meta]:
    """A field's type without its outermost :func:`setting` Meta, and that Meta."""
    args = get_args(kind)
    if get_origin(kind) is Annotated and isinstance(args[-1], msgspec.Meta) \
            and args[-1].description is not None:
        rest = args[1:-1]
        return (Annotated[(args[0], *rest)] if rest else args[0]), args[-1]
    return kind, msgspec.Meta()


def strip(kind: Any) -> Any:
    """``kind`` without its ``Annotated`` constraints (``Positive`` → ``float``), at every level."""
    while get_origin(kind) is Annotated:
        kind = get_args(kind)[0]
    args = get_args(kind)
    if args and get_origin(kind) is not Literal:
        inner = tuple(strip(a) for a in args)
        origin = get_origin(kind)
        if origin in (tuple, dict, list):
            return origin[inner]
        from functools import reduce
        from operator import or_

        return reduce(or_, inner)
    return kind


def _constraints(kind: Any) -> tuple[Any, dict[str, Any]]:
    """The base type of ``kind`` and its merged Meta constraints."""
    bounds: dict[str, Any] = {}
    while get_origin(kind) is Annotated:
        base, *metas = get_args(kind)
        for m in metas:
            if isinstance(m, msgspec.Meta):
                bounds.update({k: getattr(m, k) for k in ("gt", "ge", "lt", "le", "min_length",
                                                          "max_length") if getattr(m, k) is not None})
        kind = base
    return kind, bounds


def expected(kind: Any) -> str:
    """What a value of ``kind`` must be, in the words of the project's errors."""
    base, b = _constraints(kind)
    args = get_args(base)
    if get_origin(base) is Literal:
        return " or ".join(repr(a) for a in args) if len(args) == 2 else \
            "one of " + ", ".join(str(a) for a in args)
    if type(None) in args:
        inner = [a for a in args if a is not type(None)]
        return expected(inner[0]) + " or null" if len(inner) == 1 else "a value or null"
    if get_origin(base) is tuple:
        fixed = Ellipsis not in args
        n = len(args) if fixed else b.get("min_length")
        item = expected(args[0])
        return f"{n} {_plural(item)}" if n is not None and (fixed or n == b.get("max_length")) \
            else f"a list of {_plural(item)}"
    if base is int:
        names = {0: "a non-negative integer", 1: "a positive integer"}
        return names.get(b["ge"], f"an integer ≥ {b['ge']}") if "ge" in b else "an integer"
    if base is float:
        return _number_words(b)
    return {str: "a string", bool: "true or false", dict: "a table"}.get(base, str(base))


def _number_words(b: dict[str, Any]) -> str:
    """The words of a float's bounds ``b`` (``gt``, ``ge``, ``lt``, ``le``)."""
    finite = b.get("le") == BIG
    low = ("gt", b["gt"]) if "gt" in b else ("ge", b.get("ge"))
    if low == ("gt", 0) and (finite or ("le" not in b and "lt" not in b)):
        return "a finite positive number" if finite else "a positive number or inf"
    if low == ("ge", 0) and (finite or ("le" not in b and "lt" not in b)):
        return "a finite number ≥ 0" if finite else "a number ≥ 0"
    if low == ("ge", 0) and b.get("lt") == 1:
        return "a probability in [0, 1)"
    if low == ("ge", -BIG) or low[1] is None:
        return "a finite number" if finite else "a number"
    high = ("]", b["le"]) if "le" in b else (")", b.get("lt", math.inf))
    return f"a number in {'(' if low[0] == 'gt' else '['}{low[1]:g}, {high[1]:g}{high[0]}"


def _plural(item: str) -> str:
    """``"a finite number ≥ 0"`` → ``"finite non-negative numbers"``."""
    words = item.removeprefix("a ").removeprefix("an ")
    return {"finite number": "finite numbers", "finite number ≥ 0": "finite non-negative numbers",
            "finite positive number": "finite positive numbers"}.get(words, words + "s")


def check(name: str, value: Any, kind: Any, *,
          error: type[PendulumLQGError] = ConfigError, shown: Any = None) -> Any:
    """``value`` as a ``kind`` (msgspec's conversion: an int is a float, a list a tuple; a bool is
    never a number), or ``error`` naming ``name``: "dt: expected a finite positive number, got 0"
    (``shown``: the value the error shows, if not ``value``). numpy scalars and arrays are read as
    their Python values."""
    plain = value.tolist() if hasattr(value, "tolist") else value
    try:
        return msgspec.convert(plain, kind)
    except msgspec.ValidationError:
        text = " ".join(repr(value if shown is None else shown).split())
        text = text if len(text) <= 120 else text[:117] + "..."
        raise error(f"{name}: expected {expected(kind)}, got {text}") from None


def positive_number(name: str, value: Any, *,
                    error: type[PendulumLQGError] = ConfigError) -> float:
    """A finite positive number (:func:`check` of :data:`Positive`)."""
    return float(check(name, value, Positive, error=error))


def positive_limit(name: str, value: Any) -> float:
    """A limit: a positive number, or ``inf`` (the string ``"inf"`` too, as TOML and the command
    line may spell it) for none."""
    if isinstance(value, str) and value.strip().lower() in ("inf", "+inf", "infinity"):
        return float("inf")
    return float(check(name, value, Limit))


def config_vector(name: str, value: Any, n: int, *, nonneg: bool = False) -> tuple[float, ...]:
    """``n`` finite numbers (≥ 0 with ``nonneg``) as a tuple; a single number is repeated."""
    kind = vector(n, NonNegative if nonneg else Finite)
    return tuple(coerce(Declared(name, kind, None, "", "", None, ()), value))


def coerce(setting: Declared, value: Any) -> Any:
    """``value`` of the declared ``setting`` in its declared type, the spellings a file or a
    caller may use accepted first: ``"inf"`` for a limit, one number for a vector (repeated)."""
    base, bounds = _constraints(setting.type)
    if isinstance(value, str) and value.strip().lower() in ("inf", "+inf", "infinity") \
            and expected(setting.type).startswith("a positive number or inf"):
        return float("inf")
    n = bounds.get("min_length")
    if get_origin(base) is tuple and n is not None:
        plain = value.tolist() if hasattr(value, "tolist") else value
        items = list(plain) if isinstance(plain, list | tuple) else [plain]
        if len(items) == 1 and n > 1:
            items *= n
        return check(setting.name, items, setting.type, shown=value)
    return check(setting.name, value, setting.type)


T = TypeVar("T")


class Converted(Generic[T]):
    """A field of a frozen dataclass whose value is converted as the instance is made.

    A data descriptor as the field's default: the dataclass's ``__init__`` (and so
    :func:`dataclasses.replace`) sets each field through it, and :meth:`__set__` stores
    ``convert(name, value)`` (``name`` the field's, for the error line) — there is no second pass
    over a built instance. Read on the class it is the
    field's ``default`` (the dataclass takes that as the default of its ``__init__``); assignment
    after ``__init__`` stays the frozen dataclass's error.
    """

    def __init__(self, convert: Callable[[str, Any], T], default: T) -> None:
        self.convert = convert
        self.default = default
        self.name = ""

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name

    def __get__(self, obj: object | None, owner: type | None = None) -> T:
        if obj is None:
            return self.default
        try:
            return obj.__dict__[self.name]
        except KeyError:
            raise AttributeError(self.name) from None

    def __set__(self, obj: object, value: T) -> None:
        obj.__dict__[self.name] = self.convert(self.name, value)


class Coerced(Converted[T]):
    """A setting declared on ``struct`` as a dataclass field (:class:`Converted`): its default the
    declared one, its value :func:`coerce`-ed to the declared type (one error line naming it)."""

    def __init__(self, struct: type[msgspec.Struct]) -> None:
        super().__init__(self._coerce, None)  # type: ignore[arg-type]
        self.struct = struct

    def __set_name__(self, owner: type, name: str) -> None:
        super().__set_name__(owner, name)
        # the default straight from the Struct: reading the type hints waits for the first value
        (self.default,) = (f.default for f in msgspec.structs.fields(self.struct) if f.name == name)

    def _coerce(self, name: str, value: Any) -> T:
        return coerce(_by_name(self.struct)[name], value)


@cache
def _by_name(struct: type[msgspec.Struct]) -> dict[str, Declared]:
    """The settings declared by ``struct``, by name (read once, at the first value set)."""
    return {d.name: d for d in declared(struct)}
