"""The pilot that chose the RL baselines' history length K, exploration ``log_std_init`` and γ.

One factor at a time around a centre (K = 32, ``log_std_init`` = −1, γ = 0.995): K ∈ {16, 32, 64},
``log_std_init`` ∈ {−1, −2}, γ ∈ {0.99, 0.995, 0.998}, six PPO-history variants, each trained on
two pilot training seeds (100 and 101: never the suites' seed 2026, nor the final runs' seeds
0–4) for ``--steps`` env steps; each variant's last
learning-curve point (20 episodes from :data:`train_agents.EVAL_SEED`, the deterministic policy)
is written to ``experiments/agents/pilot/pilot.csv``. The selection rule: the variant with the
highest mean failure-aware score over the two pilot seeds; ties broken by success rate, then by
the shorter history. The chosen values are then the ``ppo-history`` method's (and the other
history methods' K and γ) in :data:`train_agents.METHODS`::

    python benchmarks/pilot_agents.py --steps 300000            # the whole grid, one run per core
    python benchmarks/pilot_agents.py --summary                 # the table and the choice

Needs the ``rl`` extra, as ``train_agents.py`` does.
"""

from __future__ import annotations

import argparse
import csv
import os
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from train_agents import METHODS, Method, run_name, train

#: The search space — history length K, the policy's initial log std, the discount γ — walked one
#: factor at a time from CENTRE (a full grid of 18 variants × 2 seeds would cost 3× the CPU time).
CENTRE = (32, -1.0, 0.995)
HISTORY = (16, 32, 64)
LOG_STD = (-1.0, -2.0)
GAMMA = (0.99, 0.995, 0.998)
PILOT_SEEDS = (100, 101)
OUT = Path("experiments/agents/pilot")


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


def summary(out: Path) -> list[dict[str, object]]:
    """One row per variant: the last curve point of each pilot seed and their mean."""
    rows = []
    for k, log_std, gamma in grid():
        name = variant_name(k, log_std, gamma)
        points = []
        for seed in PILOT_SEEDS:
            path = out / f"{run_name(name, seed)}-curve.csv"
            if path.is_file():
                with path.open(encoding="utf-8") as f:
                    points.append(list(csv.DictReader(f))[-1])
        if len(points) == len(PILOT_SEEDS):
            rows.append({"variant": name, "K": k, "log_std_init": log_std, "gamma": gamma,
                         "env_steps": int(points[0]["env_steps"]),
                         "success": sum(float(p["success_rate"]) for p in points) / len(points),
                         "score": sum(float(p["score_mean"]) for p in points) / len(points)})
    rows.sort(key=lambda r: (-float(r["score"]), -float(r["success"]), int(r["K"])))  # type: ignore[arg-type]
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=300_000, help="env steps per pilot run")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="runs at once")
    ap.add_argument("--one", nargs=4, metavar=("K", "LOG_STD", "GAMMA", "SEED"),
                    help="train one pilot run (what the grid starts, one process each)")
    ap.add_argument("--summary", action="store_true", help="print the table and the choice")
    ap.add_argument("--out", type=Path, default=OUT)
    args = ap.parse_args(argv)
    if args.one:
        k, log_std, gamma, seed = int(args.one[0]), float(args.one[1]), float(args.one[2]), \
            int(args.one[3])
        train(variant_name(k, log_std, gamma), args.out, seed=seed, steps=args.steps,
              eval_every=args.steps // 4, m=variant(k, log_std, gamma))
        return 0
    if not args.summary:
        runs = [(k, ls, g, s) for (k, ls, g) in grid() for s in PILOT_SEEDS
                if not (args.out / f"{run_name(variant_name(k, ls, g), s)}-curve.csv").is_file()]
        procs: list[subprocess.Popen[bytes]] = []
        for k, ls, g, s in runs:
            while len(procs) >= args.jobs:
                procs[0].wait()
                procs = [p for p in procs if p.poll() is None]
            procs.append(subprocess.Popen([sys.executable, __file__, "--steps", str(args.steps),
                                           "--out", str(args.out), "--one", str(k), str(ls),
                                           str(g), str(s)]))
        for p in procs:
            p.wait()
    rows = summary(args.out)
    with (args.out / "pilot.csv").open("w", newline="", encoding="utf-8") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]) if rows else ["variant"])
        writer.writeheader()
        writer.writerows(rows)
    for r in rows:
        print(f"{r['variant']:32s} success {float(r['success']):.2f}  score {float(r['score']):.3f}")
    if rows:
        print(f"chosen: {rows[0]['variant']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
