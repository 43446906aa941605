"""``sysid-lqg``: closed-loop identification with a certainty-equivalent LQG, as a run of
``pendulum-lqg train`` (the identification itself is :mod:`pendulum_lqg.learn.closed_loop`).

Each round of the identification gives a state-space LQG controller (``action_scale`` 1 N) and the
model it was designed on; the run writes one curve point per round (at the round's logged env
steps) and keeps the last round's controller, its training record holding the identified model,
its validation figure (the one-step innovation RMS on held-out closed-loop data beside the
sensor's floor), the logged and stepped env steps, the wall time and the versions.

Identification of one seed takes well under a minute, so a stopped run is not resumed from a
round: ``--resume`` is refused and the run is started again (the same seed gives the same rounds).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from pendulum_lqg.learn.runs import RunContext, run_root, versions, write_json


def identified_rounds(ctx: RunContext, *, steps: int | None) -> list[Any]:
    """The rounds of the closed-loop identification of run ``ctx.seed`` on ``ctx.suite`` with a
    budget of ``steps`` logged env steps (``None``: the default recipe)."""
    from pendulum_lqg.learn.closed_loop import identify_closed_loop

    return list(identify_closed_loop(ctx.suite, root=run_root(ctx.seed), steps=steps,
                                     log=ctx.log))


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
    """Identify, then write the last round's controller and one curve point per round."""
    from pendulum_lqg.errors import ConfigError
    from pendulum_lqg.learn.curve import Curve

    if ctx.resume:
        raise ConfigError(f"--resume: {ctx.method} is not resumed (an identification takes under "
                          "a minute); start it again with --force")
    curve = Curve(ctx.suite, ctx.path("-curve.csv"), name=ctx.name, log=ctx.log)
    rounds = identified_rounds(ctx, steps=ctx.steps)
    if not rounds:
        raise ConfigError(f"{ctx.name}: the identification gave no controller")
    doc: dict[str, Any] = {}
    for k, rr in enumerate(rounds, start=1):
        doc = round_document(ctx, rr, curve.wall_seconds(), k)
        curve.add_linear(int(rr.logged_steps), doc)
    doc["training"]["wall_seconds"] = curve.wall_seconds()
    write_json(ctx.path(".json"), doc)
    return [ctx.path(".json"), ctx.path("-curve.csv")]
