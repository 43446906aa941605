"""``pendulum-lqg train``: one training run of one method (:mod:`pendulum_lqg.learn`).

Numbers are taken as text and checked by :func:`pendulum_lqg.learn.train.prepare` (one line
naming the option, exit 2, before any training); nothing heavy is imported at parse time.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

#: Exit status of a run stopped by Ctrl-C (128 + SIGINT).
EXIT_STOPPED = 130


def add_train_parser(sub: Any) -> None:
    """The ``train`` subcommand."""
    p = sub.add_parser(
        "train", help="train one run of a learning method (RL, random search, identification)",
        description="Train run SEED of METHOD on its suite's env (pendulum-lqg train --list: the "
                    "methods). Writes DIR/METHOD-seedS.json (a linear controller file, or an SB3 "
                    "model's training record beside METHOD-seedS.zip) and the learning curve "
                    "DIR/METHOD-seedS-curve.csv, rewritten whole at every point. Ctrl-C stops at "
                    "the next safe point with a checkpoint (exit 130); --resume continues it.")
    p.add_argument("method", nargs="?", default=None, metavar="METHOD",
                   help="the method (see --list)")
    p.add_argument("--seed", default="0", metavar="S",
                   help="the run's training seed, an integer ≥ 0; its episodes are never a "
                        "suite's (default 0)")
    p.add_argument("--suite", default=None, metavar="NAME|FILE",
                   help="the suite whose env the run trains on (default: the method's, lecture "
                        "or full-state)")
    from pendulum_lqg.cli.score import add_plant_option

    add_plant_option(p, "train on the env of the plant's own suite, the one score --plant "
                        "scores on (ars-history, ars-history-clone; the others are refused, "
                        "naming why; not with --suite)")
    p.add_argument("--steps", default=None, metavar="N",
                   help="env steps of the run (ls-clone: closed-loop samples of the fit; "
                        "sysid-lqg: the identification's budget; default: the method's)")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="the run folder (default: a new runs/METHOD-seedS-<UTC time>/, never the "
                        "committed models)")
    p.add_argument("--force", action="store_true",
                   help="replace the run files already in --out (default: refuse)")
    p.add_argument("--resume", action="store_true",
                   help="continue the run stopped in --out from its last checkpoint (same seed "
                        "stream)")
    p.add_argument("--list", action="store_true", help="list every method and exit")
    g = p.add_argument_group("method options (refused by the methods they do not apply to)")
    g.add_argument("--eval-every", default=None, metavar="N",
                   help="env steps between curve points (default 50 000)")
    g.add_argument("--noise-scale", default=None, metavar="X",
                   help="SB3 methods: train at the suite's env with noise_scale X, the noise "
                        "ladder; writes METHOD-noiseX-seedS (default: the suite's own noise)")
    g.add_argument("--frames", default=None, metavar="K",
                   help="ARS and ls-clone: the history length K (default 64)")
    g.add_argument("--alpha", default=None, metavar="A",
                   help="ARS: step size α (default 0.02; from a clone 2e-4)")
    g.add_argument("--nu", default=None, metavar="V",
                   help="ARS: exploration ν (default 0.03; from a clone 5e-4)")
    g.add_argument("--init", default=None, metavar="FILE",
                   help="ars-history-clone: the ls-clone controller file ARS starts from "
                        "(default: none; that method requires it)")


def cmd_train(args: argparse.Namespace) -> int:
    from pendulum_lqg.learn.methods import list_lines

    if args.list or args.method is None:
        print("\n".join(list_lines()))
        return 0
    from pendulum_lqg.learn.runs import Stopped
    from pendulum_lqg.learn.train import prepare, run

    options = {k: getattr(args, k) for k in ("eval_every", "noise_scale", "frames", "alpha", "nu",
                                             "init")}
    ctx = prepare(args.method, seed=args.seed, suite=args.suite, steps=args.steps, out=args.out,
                  force=args.force, resume=args.resume, options=options, plant=args.plant_ref)
    try:
        wrote = run(ctx)
    except Stopped as stop:
        print(f"stopped at {stop.steps} steps; wrote {', '.join(map(str, stop.wrote))}; continue "
              f"with: {_resume_command(args, ctx.out)}", file=sys.stderr)
        return EXIT_STOPPED
    print(f"wrote {', '.join(map(str, wrote))}", file=sys.stderr)
    return 0


def _resume_command(args: argparse.Namespace, out: Any) -> str:
    """The command that continues this run from its checkpoint."""
    import shlex

    parts = ["pendulum-lqg", "train", args.method, "--seed", str(args.seed)]
    for flag in ("plant_ref", "suite", "steps", "eval_every", "noise_scale", "frames", "alpha",
                 "nu", "init"):
        value = getattr(args, flag)
        if value is not None:
            parts += [f"--{flag.removesuffix('_ref').replace('_', '-')}", str(value)]
    return " ".join(shlex.quote(p) for p in [*parts, "--out", str(out), "--resume"])
