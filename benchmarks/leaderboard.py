"""Score every leaderboard entry on all suites and regenerate the Leaderboard page's table.

    uv run python benchmarks/leaderboard.py                  # built-ins, plug-ins, Gymnasium agents
    python benchmarks/leaderboard.py --rl                    # the RL models (the rl extra)
    uv run pendulum-lqg board docs/leaderboard/scores --out docs/leaderboard/board.md

Each entry's file is exactly what ``pendulum-lqg score ENTRY --suite all --out FILE`` writes (the
same :func:`~pendulum_lqg.scoreboard.score.score_entry`); one process scores them all so that the
suites' reference and full-state rows are computed once, not once per entry.
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from pendulum_lqg.scoreboard.board import make_board
from pendulum_lqg.scoreboard.score import score_entry
from pendulum_lqg.scoreboard.suites import load_suite, suite_names
from pendulum_lqg.util.files import atomic_write

ROOT = Path(__file__).resolve().parents[1]
#: Built-in policies: every controller+observer pair the benchmark ships.
BUILTINS = ("dlqr+kalman", "dlqr+kalman-tv", "dlqr+kalman-predictor", "dlqr+kalman-delay",
            "lqr+kalman-bucy", "dlqr+luenberger", "dlqr+reduced-order", "dlqr+ackermann",
            "dlqr+lmi", "dlqr+h2", "dlqr+hinf", "dlqr+none", "lqr+none")
#: Plug-ins (the batch path) and Gymnasium agents (the env path), by the file name of their score.
PLUGINS = {"plugin_lqg": "experiments/plugin_lqg.py:make",
           "plugin_example": "experiments/plugin_example.py:make"}
AGENTS = {"agent_LQGAgent": "pendulum_lqg.scoreboard.episodes:reference_agent",
          "agent_python_control_lqg": "experiments/agents/python_control_lqg.py:make",
          "agent_zero_force": "experiments/agents/zero_force.py:make"}
#: The first board's RL models (scored with --rl, beside every run ``METHOD-seedS`` of
#: ``pendulum-lqg train`` that the models folder holds).
MODELS = ("ppo-lecture", "recurrentppo-lecture", "sac-lecture", "ppo-full-state")


def rl_entries(models: Path) -> list[tuple[str, dict]]:
    """``(score file stem, score_entry keywords)`` of every RL model: the first board's four, then
    each training run — an SB3 zip, or a linear controller file (a ``.json`` without a zip
    beside it). Runs of the noise ladder (``METHOD-noiseX-seedS``) are not board entries: they
    are scored at their own noise by ``python -m pendulum_lqg.learn.noise_ladder``."""
    out = [(f"rl_{m}", {"agent": f"sb3:{(models / f'{m}.zip').relative_to(ROOT)}"}) for m in MODELS]
    for path in sorted(models.glob("*-seed*.*")):
        if "-noise" in path.stem or path.name.endswith("-curve.csv"):
            continue
        if path.suffix == ".zip":
            out.append((f"rl_{path.stem}", {"agent": f"sb3:{path.relative_to(ROOT)}"}))
        elif path.suffix == ".json" and not path.with_suffix(".zip").exists():
            out.append((f"rl_{path.stem}", {"agent": f"linear:{path.relative_to(ROOT)}"}))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "leaderboard")
    ap.add_argument("--rl", action="store_true", help="score only the RL models (the rl extra)")
    ap.add_argument("--models", type=Path, default=ROOT / "experiments" / "agents" / "models")
    args = ap.parse_args()
    scores = args.out / "scores"
    scores.mkdir(parents=True, exist_ok=True)
    suites = [load_suite(n) for n in suite_names()]
    cache: dict = {}
    entries: list[tuple[str, dict]] = []
    if args.rl:
        entries += rl_entries(args.models)
    else:
        entries += [(p, {"policy": p}) for p in BUILTINS]
        entries += [(f, {"policy": ref}) for f, ref in PLUGINS.items()]
        entries += [(f, {"agent": ref}) for f, ref in AGENTS.items()]
    for file, entry in entries:
        t0 = time.perf_counter()
        doc = score_entry(suites, base_dir=ROOT, cache=cache, **entry)
        atomic_write(scores / f"{file}.json", json.dumps(doc, indent=1, allow_nan=False) + "\n")
        print(f"{file}: {time.perf_counter() - t0:.0f} s", flush=True)
    atomic_write(args.out / "board.md", make_board(scores))
    print(f"board: {args.out / 'board.md'}")


if __name__ == "__main__":
    main()
