"""The declared flags of ``run`` and ``theory``, added from the generated table
(:mod:`pendulum_lqg.cli.flags`, derived from :mod:`pendulum_lqg.problem`): a setting declared with
the front end ``"run"`` is a ``run`` flag without a line here. A given value is checked by the
declaration's one path (:func:`pendulum_lqg.problem.frontends.flag_value`)."""

from __future__ import annotations

import argparse
from typing import Any

from pendulum_lqg.cli.flags import FLAGS
from pendulum_lqg.errors import ConfigError


class DeclaredType:
    """argparse ``type=`` of the declared setting ``name`` (imports the declarations when used)."""

    def __init__(self, name: str) -> None:
        self.name = self.__name__ = name

    def __call__(self, text: str) -> Any:
        from pendulum_lqg.problem.frontends import flag_value

        try:
            return flag_value(self.name, text)
        except ConfigError as exc:
            raise argparse.ArgumentTypeError(str(exc).split(": ", 1)[1]) from None


def add_flags(p: argparse.ArgumentParser | Any, command: str, names: tuple[str, ...] = (),
              **defaults: Any) -> None:
    """Add the declared flags of ``command`` (those named, else all of them) to ``p`` (a parser or
    an argument group); ``defaults``: a command's own default of a setting."""
    for name, (flag, metavar, default, text, commands, choices) in FLAGS.items():
        if command not in commands or (names and name not in names):
            continue
        default = defaults.get(name, default)
        if default is not None:
            text += f" (default {default:g})" if isinstance(default, float) else \
                f" (default {default})"
        if choices is None:
            p.add_argument(flag, type=DeclaredType(name), default=default, metavar=metavar,
                           help=text)
        else:
            p.add_argument(flag, choices=choices, default=default, help=text)


class Kind:
    """argparse ``type=`` of a constrained type of :mod:`pendulum_lqg.problem.declare` named
    ``kind`` (``"PositiveInt"``, ``"Finite"``, …; ``"Complex"``: a pole), or with ``each`` a
    comma-separated list of them — checked by the declarations' one path when given."""

    def __init__(self, kind: str, *, each: bool = False) -> None:
        self.kind, self.each = kind, each
        self.__name__ = kind

    def __call__(self, text: str) -> Any:
        from pendulum_lqg.problem.frontends import text_value

        try:
            return text_value(self.kind, text, each=self.each)
        except ConfigError as exc:
            raise argparse.ArgumentTypeError(str(exc).split(": ", 1)[1]) from None
