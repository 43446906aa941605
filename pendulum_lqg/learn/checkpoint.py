"""The checkpoint ``pendulum-lqg train --resume`` continues, read and checked at the boundary
before any work (:mod:`pendulum_lqg.boundary.schemas`): one reader per method kind, against the
run being resumed (its settings, suite, seed and budget)."""

from __future__ import annotations

from typing import Any

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.learn.runs import RunContext


def read_checkpoint(ctx: RunContext) -> dict[str, Any]:
    """The checkpoint ``--resume`` continues, read and checked at the boundary before any work
    (:mod:`pendulum_lqg.boundary.schemas`): the JSON record, the curve beside it, and the files
    the record names regular files (a FIFO or a device there would hang or grow the run). A
    damaged, truncated, foreign or edited checkpoint is one line naming the file and the key."""
    from pendulum_lqg.boundary import regular_file
    from pendulum_lqg.boundary.schemas import (
        ars_checkpoint,
        curve_file,
        openloop_checkpoint,
        sb3_checkpoint,
        sysid_checkpoint,
    )

    kind, where = ctx.options["kind"], "--resume"
    path = ctx.path("-checkpoint.json")
    curve_path = ctx.path("-curve.csv")
    curve = curve_file(curve_path, where_text=where) if (
        curve_path.is_symlink() or curve_path.exists()) else None
    fingerprint = ctx.suite.fingerprint()
    if kind == "ars":
        from dataclasses import asdict

        from pendulum_lqg.learn.ars import history_inputs, settings_of

        saved = ars_checkpoint(path, where_text=where, settings=asdict(settings_of(ctx)),
                               suite=fingerprint, curve=curve, inputs=history_inputs(ctx.suite))
    elif kind == "sysid-openloop":
        from pendulum_lqg.learn.openloop import budgets_for

        saved = openloop_checkpoint(path, where_text=where, budgets=list(budgets_for(ctx.steps)),
                                    suite=fingerprint, curve=curve)
    elif kind == "sb3":
        from pendulum_lqg.learn.deep import METHODS as SB3

        m = SB3[ctx.options["base"]]
        saved = sb3_checkpoint(path, where_text=where, algo=m.algo, suite=fingerprint,
                               steps=ctx.steps or m.steps, curve=curve)
        regular_file(ctx.path("-checkpoint.zip"), where=where)
        regular_file(ctx.path("-checkpoint-vecnormalize.pkl"), where=where)
        replay = ctx.path("-checkpoint-replay.pkl")
        if replay.is_symlink() or replay.exists():
            regular_file(replay, where=where)
    elif kind == "sysid-lqg":
        saved = sysid_checkpoint(path, where_text=where, suite=fingerprint, seed=ctx.seed,
                                 steps=ctx.steps, curve=curve,
                                 data=ctx.path("-checkpoint-data.npz"))
    else:
        raise ConfigError(f"--resume: {ctx.method} is not resumed (identification and fit take "
                          "about a minute); start it again with --force")
    if saved["points"] and curve is None:
        raise ConfigError(f"--resume: {curve_path}: missing (the checkpoint {path.name} counts "
                          f"{saved['points']} points of it)")
    saved["curve"] = (curve or [])[:saved["points"]]
    return saved
