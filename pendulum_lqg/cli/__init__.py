"""The ``pendulum-lqg`` command: ``design``, ``run``, ``bench``, ``perf``, ``report``, ``score``,
``board``, ``theory``, ``train``.

============  ========================================================================
module        concept
============  ========================================================================
``parser``    the grammar and the arguments' conversions
``design``    ``design``: the linearised model and every design
``commands``  ``run``, ``bench``, ``report`` and ``perf``
``score``     ``score`` and ``board``
``theory``    ``theory``: built-in linear policies in closed form
``lti``       ``run --lti FILE``: episodes of a plant given as matrices
``train``     ``train``: one training run of one method
``__main__``  ``python -m pendulum_lqg.cli``
============  ========================================================================

Only argument parsing and presentation live here; every computation is a library call. Heavy
imports (numpy, MuJoCo, python-control, rich) happen inside the commands so ``--help`` is instant.
Bad input prints one line ``error: …`` naming the parameter and exits with status 2.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Callable, Sequence

from pendulum_lqg.cli.parser import EXIT_USAGE, build_parser

#: Exit status of a run stopped by Ctrl-C (128 + SIGINT, as a shell reports it).
EXIT_INTERRUPTED = 130

#: Each command's module and function. A command's module is imported when it runs, not when
#: the CLI starts: every invocation pays for the grammar, only one pays for its command.
COMMANDS: dict[str, tuple[str, str]] = {
    "design": ("design", "cmd_design"), "run": ("commands", "cmd_run"),
    "bench": ("commands", "cmd_bench"), "perf": ("commands", "cmd_perf"),
    "report": ("commands", "cmd_report"), "score": ("score", "cmd_score"),
    "board": ("score", "cmd_board"), "theory": ("theory", "cmd_theory"),
    "train": ("train", "cmd_train")}


def command(name: str) -> Callable[[argparse.Namespace], int]:
    """The function that runs the command ``name`` (its module imported now)."""
    module, function = COMMANDS[name]
    handler: Callable[[argparse.Namespace], int] = getattr(
        importlib.import_module(f"pendulum_lqg.cli.{module}"), function)
    return handler


def main(argv: Sequence[str] | None = None) -> int:
    try:
        parser = build_parser()
        args = parser.parse_args(argv)
        return _dispatch(args)
    except KeyboardInterrupt:   # Ctrl-C: one line; outputs are written only once complete
        print("interrupted: stopped by Ctrl-C before the command finished", file=sys.stderr)
        return EXIT_INTERRUPTED


def _dispatch(args: argparse.Namespace) -> int:
    from pendulum_lqg.errors import PendulumLQGError

    try:
        return command(args.command)(args)
    except PendulumLQGError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except BrokenPipeError:  # e.g. `pendulum-lqg design --json | head`
        return 0
    except OSError as exc:   # a full disk, a read-only or vanished folder: files written stay
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"error: cannot write or read {where}{exc.strerror or exc}", file=sys.stderr)
        return EXIT_USAGE
