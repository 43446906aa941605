"""The command line's contract for the project's scripts (``benchmarks/*.py``).

What ``pendulum-lqg`` promises, for programs that are not its subcommands: bad input is one line
``error: …`` naming the option and what was expected, exit status 2, no traceback (argparse
conversions, the library's own errors, a file that cannot be written); a missing optional
library is one line saying which extra or package brings it; Ctrl-C is one line, exit 130; an
output follows the output rule of :mod:`pendulum_lqg.util.files`. A script builds its parser with
:class:`ScriptParser`, converts its options with :func:`int_in` / :func:`number`, checks its outputs
with :func:`~pendulum_lqg.util.files.output_file` / :func:`~pendulum_lqg.util.files.output_folder`
and runs its ``main`` through :func:`run_script`.
"""

from __future__ import annotations

import argparse
import importlib
import math
import sys
from collections.abc import Callable
from types import ModuleType
from typing import Any, NoReturn

from pendulum_lqg.errors import ConfigError, PendulumLQGError

#: Exit status of bad input (as ``pendulum-lqg``), and of a run stopped by Ctrl-C (128 + SIGINT).
EXIT_USAGE, EXIT_INTERRUPTED = 2, 130


class ScriptParser(argparse.ArgumentParser):
    """argparse whose errors are one line ``error: --flag: expected …, got …`` and exit 2 (no
    usage block: ``--help`` prints it)."""

    def error(self, message: str) -> NoReturn:
        message = message.removeprefix("argument ")
        print(f"error: {message}", file=sys.stderr)
        raise SystemExit(EXIT_USAGE)


def int_in(minimum: int, maximum: int | None = None) -> Callable[[str], int]:
    """argparse type: an integer in ``[minimum, maximum]`` (no upper bound with ``None``); a
    float such as ``1e12`` is refused, not truncated."""
    what = (f"an integer ≥ {minimum:,}" if maximum is None
            else f"an integer from {minimum:,} to {maximum:,}")

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}") from None
        if value < minimum or (maximum is not None and value > maximum):
            raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}")
        return value

    parse.__name__ = "integer"
    return parse


def number(*, minimum: float | None = None, positive: bool = False,
           maximum: float | None = None) -> Callable[[str], float]:
    """argparse type: a finite number, ``> 0`` with ``positive``, within ``[minimum, maximum]``
    where given."""
    what = "a finite positive number" if positive else "a finite number"
    if minimum is not None and maximum is not None:
        what += f" from {minimum:g} to {maximum:g}"
    elif minimum is not None or maximum is not None:
        what += f" ≥ {minimum:g}" if minimum is not None else f" ≤ {maximum:g}"

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}") from None
        if (not math.isfinite(value) or (positive and value <= 0)
                or (minimum is not None and value < minimum)
                or (maximum is not None and value > maximum)):
            raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}")
        return value

    parse.__name__ = "number"
    return parse


def requires(module: str, *, needed_for: str, install: str) -> ModuleType:
    """``import module``, or one :class:`ConfigError` line saying what needs it and how to install
    it (``install``: e.g. ``"the ray extra: uv sync --extra ray"``)."""
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        raise ConfigError(f"{needed_for} needs {module}, which is not installed ({exc.msg}); "
                          f"install {install}") from None


def script_status(main: Callable[[], Any]) -> int:
    """``main()`` under the contract, as an exit status (0, or ``main``'s integer): the library's
    errors and a file that cannot be written are one line, 2; Ctrl-C is one line, 130. Any other
    exception is a bug and keeps its traceback."""
    try:
        status = main()
    except PendulumLQGError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print("interrupted: stopped by Ctrl-C before the script finished", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:                    # e.g. `… | head`
        return 0
    except OSError as exc:
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"error: cannot write or read {where}{exc.strerror or exc}", file=sys.stderr)
        return EXIT_USAGE
    return status if isinstance(status, int) else 0


def run_script(main: Callable[[], Any]) -> NoReturn:
    """Run a script's ``main()`` under the contract (:func:`script_status`) and exit with its
    status."""
    raise SystemExit(script_status(main))
