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
import sys
from collections.abc import Sequence

from pendulum_lqg.cli.commands import cmd_bench, cmd_perf, cmd_report, cmd_run
from pendulum_lqg.cli.design import cmd_design
from pendulum_lqg.cli.parser import EXIT_USAGE, build_parser
from pendulum_lqg.cli.score import cmd_board, cmd_score
from pendulum_lqg.cli.theory import cmd_theory
from pendulum_lqg.cli.train import cmd_train

#: Exit status of a run stopped by Ctrl-C (128 + SIGINT, as a shell reports it).
EXIT_INTERRUPTED = 130

COMMANDS = {"design": cmd_design, "run": cmd_run, "bench": cmd_bench, "perf": cmd_perf,
            "report": cmd_report, "score": cmd_score, "board": cmd_board, "theory": cmd_theory,
            "train": cmd_train}


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
        return COMMANDS[args.command](args)
    except PendulumLQGError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except BrokenPipeError:  # e.g. `pendulum-lqg design --json | head`
        return 0
    except OSError as exc:   # a full disk, a read-only or vanished folder: files written stay
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"error: cannot write or read {where}{exc.strerror or exc}", file=sys.stderr)
        return EXIT_USAGE
