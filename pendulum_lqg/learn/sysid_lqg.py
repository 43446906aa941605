"""``sysid-lqg``: closed-loop identification with a certainty-equivalent LQG, as a run of
``pendulum-lqg train`` (the identification itself is :mod:`pendulum_lqg.learn.closed_loop`).

Each round of the identification gives a state-space LQG controller (``action_scale`` 1 N) and the
model it was designed on; the run writes one curve point per round (at the round's logged env
steps) and keeps the last round's controller, its training record holding the identified model,
its validation figure (the one-step innovation RMS on held-out closed-loop data beside the
sensor's floor), the logged and stepped env steps, the wall time and the versions.

Ctrl-C stops at the next stage (the open-loop round, a closed-loop round, a curve point) with a
checkpoint, written after the open-loop round and after every closed-loop round and curve point:
``METHOD-seedS-checkpoint.json`` (what the identification needs to continue: the plan, the seeds
used, the last design, the generator's state; after the last round, the rounds themselves) and
``METHOD-seedS-checkpoint-data.npz`` (the closed-loop episodes so far). ``--resume`` continues from
it, with the same seeds, to the rounds, curve and controller of an uninterrupted run.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from pendulum_lqg.learn.runs import RunContext, Stopped, run_root, versions, write_json

CHECKPOINT = "-checkpoint.json"
DATA = "-checkpoint-data.npz"           # the closed-loop episodes beside it


def identified_rounds(ctx: RunContext, *, steps: int | None,
                      on_stage: Any = None, resume: Any = None) -> list[Any]:
    """The rounds of the closed-loop identification of run ``ctx.seed`` on ``ctx.suite`` with a
    budget of ``steps`` logged env steps (``None``: the default recipe); ``on_stage`` and
    ``resume``: :func:`~pendulum_lqg.learn.closed_loop.identify_closed_loop`'s checkpoints."""
    from pendulum_lqg.learn.closed_loop import identify_closed_loop

    extra = {k: v for k, v in (("on_stage", on_stage), ("resume", resume)) if v is not None}
    return list(identify_closed_loop(ctx.suite, root=run_root(ctx.seed), steps=steps,
                                     log=ctx.log, **extra))


def round_document(ctx: RunContext, rr: Any, wall_seconds: float, rounds: int,
                   ) -> dict[str, Any]:
    """The controller file of round ``rr`` (a ``RoundResult``) with its training record."""
    from pendulum_lqg.learn.runs import EVAL_EPISODES, EVAL_SEED
    from pendulum_lqg.scoreboard.linear import controller_file

    training = {"algo": "closed-loop identification + certainty-equivalent LQG",
                "suite": ctx.suite.name, "rounds": rounds, "model": rr.model,
                "validation": rr.validation,
                "budget": {"steps": int(rr.logged_steps), "logged_steps": int(rr.logged_steps),
                           "stepped_steps": int(rr.stepped_steps), "root_seed": run_root(ctx.seed)},
                "curve": {"eval_seed": EVAL_SEED, "episodes": EVAL_EPISODES},
                "wall_seconds": wall_seconds, "versions": versions()}
    return controller_file("state_space", rr.state_space, action_scale=1.0, env=ctx.suite.env,
                           method=ctx.method, seed=ctx.seed, training=training)


def train_sysid_lqg(ctx: RunContext) -> list[Path]:
    """Identify, then write the last round's controller and one curve point per round, with a
    checkpoint after every stage (module docstring)."""
    from types import SimpleNamespace

    from pendulum_lqg.errors import ConfigError
    from pendulum_lqg.learn.curve import Curve

    saved = ctx.resumed() if ctx.resume else None          # checked before any work
    curve = Curve(ctx.suite, ctx.path("-curve.csv"), name=ctx.name, log=ctx.log,
                  points=saved["curve"] if saved else None)
    record = {"method": ctx.method, "seed": ctx.seed, "steps": ctx.steps,
              "suite": ctx.suite.fingerprint()}
    wrote = [ctx.path("-curve.csv"), ctx.path(CHECKPOINT)]

    def checkpoint(identification: dict[str, Any] | None, rounds: list[dict[str, Any]] | None,
                   steps: int) -> None:
        write_json(ctx.path(CHECKPOINT), {**record, "identification": identification,
                                          "rounds": rounds, "points": len(curve.points),
                                          "wall_seconds": curve.wall_seconds()})
        if ctx.stop.requested:
            raise Stopped(steps, [p for p in (*wrote, ctx.path(DATA)) if p.exists()])

    def on_stage(state: dict[str, Any], data: dict[str, Any]) -> None:
        _write_npz(ctx.path(DATA), data)                   # the data first, the record last
        checkpoint(state, None, int(state["results"][-1][0]))

    with ctx.stop.installed():
        if saved is not None and saved["rounds"] is not None:
            rounds = [SimpleNamespace(**r) for r in saved["rounds"]]
        else:
            resume = None if saved is None else (saved["identification"], saved["data"])
            try:
                rounds = identified_rounds(ctx, steps=ctx.steps, on_stage=on_stage,
                                           resume=resume)
            except ConfigError as exc:
                if saved is None:
                    raise
                raise ConfigError(f"--resume: {ctx.path(CHECKPOINT)}: identification: {exc}"
                                  ) from None
            if not rounds:
                raise ConfigError(f"{ctx.name}: the identification gave no controller")
            checkpoint(None, [_round_json(rr) for rr in rounds], int(rounds[-1].logged_steps))
        doc: dict[str, Any] = {}
        for k, rr in enumerate(rounds, start=1):
            doc = round_document(ctx, rr, curve.wall_seconds(), k)
            if k > len(curve.points):
                curve.add_linear(int(rr.logged_steps), doc)
                if k < len(rounds):
                    checkpoint(None, [_round_json(r) for r in rounds], int(rr.logged_steps))
    doc["training"]["wall_seconds"] = curve.wall_seconds()
    write_json(ctx.path(".json"), doc)
    for suffix in (CHECKPOINT, DATA):
        ctx.path(suffix).unlink(missing_ok=True)
    return [ctx.path(".json"), ctx.path("-curve.csv")]


def _round_json(rr: Any) -> dict[str, Any]:
    return {"logged_steps": int(rr.logged_steps), "stepped_steps": int(rr.stepped_steps),
            "state_space": rr.state_space, "model": rr.model, "validation": rr.validation}


def _write_npz(path: Path, data: dict[str, Any]) -> None:
    """The closed-loop episodes ``Y``, ``U``, ``valid``, whole or not at all
    (:func:`pendulum_lqg.util.files.replacing`)."""
    import numpy as np

    from pendulum_lqg.util.files import replacing

    with replacing(path, where="--out", what="checkpoint") as tmp, open(tmp, "wb") as fh:
        np.savez(fh, Y=np.asarray(data["Y"], dtype=float), U=np.asarray(data["U"], dtype=float),
                 valid=np.asarray(data["valid"], dtype=bool))
