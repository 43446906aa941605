"""The pilots that chose the baselines' settings, on pilot training seeds 100 and 101 only (never
the suites' seed 2026, nor the final runs' seeds 0–4).

``ppo``: the RL baselines' history length K, exploration ``log_std_init`` and γ. One factor at a
time around a centre (K = 32, ``log_std_init`` = −1, γ = 0.995): K ∈ {16, 32, 64},
``log_std_init`` ∈ {−1, −2}, γ ∈ {0.99, 0.995, 0.998}, six PPO-history variants, each trained on
both pilot seeds for ``--steps`` env steps (the ``rl`` extra). The chosen values are then the
``ppo-history`` method's (and the other history methods' K and γ) in
:data:`pendulum_lqg.learn.deep.METHODS`.

``ars``: ARS's step size α and exploration ν at K = 64, from zero (``ars-history``: α ∈ {0.01,
0.02}, ν ∈ {0.01, 0.03}) and, with ``--init-folder`` holding the pilot seeds'
``ls-clone-seedS.json``, from the clone (``ars-history-clone``: α ∈ {1e-4, 5e-4}, ν ∈ {3e-4,
1e-3}, small against the clone's weights, whose perturbations by ν = 3e-3 already fail);
torch-free.

Each variant's last learning-curve point (20 episodes from
:data:`pendulum_lqg.learn.runs.EVAL_SEED`, the deterministic policy) goes into ``OUT/pilot.csv``.
The selection rule: the highest mean failure-aware score over the two pilot seeds; ties broken by
success rate, then by the cheaper setting::

    python -m pendulum_lqg.learn.pilot ppo --steps 300000 --out DIR     # the grid, one run per core
    python -m pendulum_lqg.learn.pilot ppo --summary --out experiments/agents/pilot   # the table
    python -m pendulum_lqg.learn.pilot ars --steps 200000 --out DIR
"""

from __future__ import annotations

import argparse
import csv
import os
import subprocess
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.learn.deep import METHODS, Method
from pendulum_lqg.learn.runs import RUNS_FOLDER, run_name, write_text
from pendulum_lqg.util.scripts import script_status

#: The PPO search space — history length K, the policy's initial log std, the discount γ —
#: walked one factor at a time from CENTRE (a full grid of 18 variants × 2 seeds would cost 3×).
CENTRE = (32, -1.0, 0.995)
HISTORY = (16, 32, 64)
LOG_STD = (-1.0, -2.0)
GAMMA = (0.99, 0.995, 0.998)
#: ARS's grids at K = 64: (α values, ν values) per start.
ARS_GRID = {"ars-history": ((0.01, 0.02), (0.01, 0.03)),
            "ars-history-clone": ((1e-4, 5e-4), (3e-4, 1e-3))}
PILOT_SEEDS = (100, 101)
OUT = RUNS_FOLDER / "pilot"


def variant_name(k: int, log_std: float, gamma: float) -> str:
    return f"ppo-history-K{k}-ls{log_std:g}-g{gamma:g}"


def variant(k: int, log_std: float, gamma: float) -> Method:
    """``ppo-history`` with history K, ``log_std_init`` and γ replaced."""
    base = METHODS["ppo-history"]
    policy_kwargs = {**base.kwargs["policy_kwargs"], "log_std_init": log_std}
    return replace(base, frame_stack=k,
                   kwargs={**base.kwargs, "gamma": gamma, "policy_kwargs": policy_kwargs},
                   what=f"pilot: PPO-MLP, history {k}, log_std_init {log_std:g}, gamma {gamma:g}")


def grid() -> list[tuple[int, float, float]]:
    """The centre, then each factor's other values with the other two at the centre."""
    k0, ls0, g0 = CENTRE
    variants = [CENTRE] + [(k, ls0, g0) for k in HISTORY] + [(k0, ls, g0) for ls in LOG_STD] \
        + [(k0, ls0, g) for g in GAMMA]
    return list(dict.fromkeys(variants))


def ars_grid(clone: bool) -> list[tuple[str, float, float]]:
    methods = ["ars-history"] + (["ars-history-clone"] if clone else [])
    return [(m, a, n) for m in methods for a in ARS_GRID[m][0] for n in ARS_GRID[m][1]]


def ars_folder(out: Path, method: str, alpha: float, nu: float) -> Path:
    return out / f"{method}-a{alpha:g}-n{nu:g}"


def last_points(paths: list[Path]) -> list[dict[str, str]] | None:
    """The last row of each curve, or None if one is missing (a regular file each)."""
    points = []
    for path in paths:
        if not path.is_file():
            return None
        with path.open(encoding="utf-8") as f:
            rows = list(csv.DictReader(f))
        if not rows:
            return None
        points.append(rows[-1])
    return points


def _row(name: str, points: list[dict[str, str]], **settings: Any) -> dict[str, Any]:
    n = len(points)
    return {"variant": name, **settings, "env_steps": int(points[0]["env_steps"]),
            "success": sum(float(p["success_rate"]) for p in points) / n,
            "score": sum(float(p["score_mean"] or 0.0) for p in points) / n}


def summary(out: Path) -> list[dict[str, Any]]:
    """One row per PPO variant: the mean of the pilot seeds' last curve points, best first."""
    rows = []
    for k, log_std, gamma in grid():
        name = variant_name(k, log_std, gamma)
        points = last_points([out / f"{run_name(name, s)}-curve.csv" for s in PILOT_SEEDS])
        if points:
            rows.append(_row(name, points, K=k, log_std_init=log_std, gamma=gamma))
    rows.sort(key=lambda r: (-r["score"], -r["success"], r["K"]))
    return rows


def ars_summary(out: Path) -> list[dict[str, Any]]:
    """One row per ARS setting, best first (the smaller α, then ν, on ties)."""
    rows = []
    for method, alpha, nu in ars_grid(clone=True):
        folder = ars_folder(out, method, alpha, nu)
        points = last_points([folder / f"{run_name(method, s)}-curve.csv" for s in PILOT_SEEDS])
        if points:
            rows.append(_row(folder.name, points, method=method, alpha=alpha, nu=nu))
    rows.sort(key=lambda r: (-r["score"], -r["success"], r["alpha"], r["nu"]))
    return rows


def _commands(args: argparse.Namespace) -> list[list[str]]:
    """The runs of the grid not yet on disk, each a command line."""
    py = [sys.executable, "-m"]
    if args.what == "ppo":
        return [[*py, "pendulum_lqg.learn.pilot", "ppo", "--steps", str(args.steps), "--out",
                 str(args.out), "--one", str(k), str(ls), str(g), str(s)]
                for (k, ls, g) in grid() for s in PILOT_SEEDS
                if not (args.out / f"{run_name(variant_name(k, ls, g), s)}-curve.csv").is_file()]
    out = []
    for method, alpha, nu in ars_grid(clone=args.init_folder is not None):
        folder = ars_folder(args.out, method, alpha, nu)
        for s in PILOT_SEEDS:
            if (folder / f"{run_name(method, s)}.json").is_file():
                continue
            cmd = [*py, "pendulum_lqg.cli", "train", method, "--seed", str(s), "--steps",
                   str(args.steps), "--alpha", str(alpha), "--nu", str(nu),
                   "--eval-every", str(max(args.steps // 4, 1)), "--out", str(folder), "--force"]
            if method == "ars-history-clone":
                cmd += ["--init", str(args.init_folder / f"ls-clone-seed{s}.json")]
            out.append(cmd)
    return out


def _run_all(commands: list[list[str]], jobs: int) -> None:
    procs: list[subprocess.Popen[bytes]] = []
    for cmd in commands:
        while len(procs) >= jobs:
            procs[0].wait()
            procs = [p for p in procs if p.poll() is None]
        procs.append(subprocess.Popen(cmd))
    for p in procs:
        p.wait()


def _one(args: argparse.Namespace) -> int:
    """One PPO pilot run (what the grid starts, one process each)."""
    from pendulum_lqg.learn.deep import train_sb3, training_suite
    from pendulum_lqg.learn.methods import METHODS as ALL
    from pendulum_lqg.learn.runs import RunContext
    from pendulum_lqg.learn.train import check_extra

    k, log_std, gamma, seed = (int(args.one[0]), float(args.one[1]), float(args.one[2]),
                               int(args.one[3]))
    check_extra(ALL["ppo-history"])
    m = variant(k, log_std, gamma)
    ctx = RunContext(method=variant_name(k, log_std, gamma), seed=seed, suite=training_suite(m),
                     out=args.out, steps=args.steps, eval_every=max(args.steps // 4, 1))
    args.out.mkdir(parents=True, exist_ok=True)
    train_sb3(ctx, m)
    return 0


def main(argv: list[str] | None = None) -> int:
    return script_status(lambda: _main(argv))


def _main(argv: list[str] | None) -> int:
    ap = argparse.ArgumentParser(prog="python -m pendulum_lqg.learn.pilot",
                                 description=__doc__.splitlines()[0])
    ap.add_argument("what", choices=("ppo", "ars"), help="the pilot")
    ap.add_argument("--steps", type=int, default=300_000, help="env steps per pilot run")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="runs at once")
    ap.add_argument("--one", nargs=4, metavar=("K", "LOG_STD", "GAMMA", "SEED"),
                    help="ppo: train one pilot run (what the grid starts, one process each)")
    ap.add_argument("--init-folder", type=Path, default=None, metavar="DIR",
                    help="ars: the folder of ls-clone-seed100.json and ls-clone-seed101.json "
                         "(also pilots ars-history-clone)")
    ap.add_argument("--summary", action="store_true", help="print the table and the choice")
    ap.add_argument("--out", type=Path, default=OUT, help=f"the pilot's folder (default {OUT})")
    args = ap.parse_args(argv)
    if args.steps < 1 or args.jobs < 1:
        raise ConfigError(f"--steps, --jobs: expected positive integers, got {args.steps}, "
                          f"{args.jobs}")
    if args.one:
        return _one(args)
    if not args.summary:
        _run_all(_commands(args), args.jobs)
    rows = summary(args.out) if args.what == "ppo" else ars_summary(args.out)
    if not args.summary:
        fields = list(rows[0]) if rows else ["variant"]
        text = ",".join(fields) + "\n" + "".join(
            ",".join(str(r[f]) for f in fields) + "\n" for r in rows)
        write_text(args.out / "pilot.csv", text)
    for r in rows:
        print(f"{r['variant']:32s} success {float(r['success']):.2f}  score {float(r['score']):.3f}")
    if rows:
        print(f"chosen: {rows[0]['variant']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
