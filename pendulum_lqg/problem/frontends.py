"""The command line's view of the declarations: a flag's value read from its text by the declared
type (msgspec, lax about strings: ``"0.5"`` is a number, ``"inf"`` a limit), with the one-line
error of :func:`~pendulum_lqg.problem.declare.expected`.

The flags themselves (name, metavar, default, help, commands, choices) are generated into
``pendulum_lqg/cli/flags.py`` (:mod:`~pendulum_lqg.problem.generate`) so the CLI builds its parser
without importing msgspec; this module is imported only when a declared flag is given.
"""

from __future__ import annotations

from functools import cache
from typing import Annotated, Any

import msgspec

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.problem.declare import Declared, declared, expected
from pendulum_lqg.problem.env import EnvSettings
from pendulum_lqg.problem.scenario import ScenarioSettings


@cache
def settings() -> dict[str, Declared]:
    """Every declared setting by name."""
    return {d.name: d for d in declared(ScenarioSettings) + declared(EnvSettings)}


def flag_value(name: str, text: str) -> Any:
    """The value of the declared setting ``name`` given as ``text`` on the command line."""
    d = settings()[name]
    try:
        return msgspec.convert(text.strip(), d.type, strict=False)
    except msgspec.ValidationError:
        raise ConfigError(f"{d.flag}: expected {expected(d.type)}, got {text!r}") from None


def text_value(kind: str, text: str, *, each: bool = False) -> Any:
    """``text`` read as the constrained type named ``kind`` of :mod:`~pendulum_lqg.problem.declare`
    (``each``: a comma-separated list of them); ``"Complex"`` is a pole such as ``-1+2j``."""
    from pendulum_lqg.problem import declare

    items = [t for t in text.replace(" ", "").split(",") if t] if each else text.strip()
    if kind == "Complex":
        try:
            return [complex(t.replace("i", "j")) for t in items]
        except ValueError:
            raise ConfigError(f"value: expected comma-separated poles like -0.4,-0.5 or "
                              f"-1+2j,-1-2j, got {text!r}") from None
    base: Any = getattr(declare, kind)
    target: Any = Annotated[list[base], msgspec.Meta(min_length=1)] if each else base
    try:
        return msgspec.convert(items, target, strict=False)
    except msgspec.ValidationError:
        what = f"comma-separated {declare.expected(declare.vector(2, base))[2:]}" if each \
            else expected(base)
        raise ConfigError(f"value: expected {what}, got {text!r}") from None
