"""Score every leaderboard entry on all suites and regenerate the Leaderboard page's table.

    uv run python benchmarks/leaderboard.py --out docs/leaderboard --force   # built-ins, plug-ins,
                                                                            # Gymnasium agents
    python benchmarks/leaderboard.py --rl --out docs/leaderboard --force     # the RL models (rl extra)
    uv run pendulum-lqg board docs/leaderboard/scores --out docs/leaderboard/board.md

Without ``--out`` the scores and the board go to a fresh folder ``runs/leaderboard-<UTC time>``;
an existing score or board is replaced only with ``--force`` (each file atomically).

Each entry's file is exactly what ``pendulum-lqg score ENTRY --suite all --out FILE`` writes (the
same :func:`~pendulum_lqg.scoreboard.score.score_entry`); one process scores them all so that the
suites' reference and full-state rows are computed once, not once per entry.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.scoreboard.board import make_board
from pendulum_lqg.scoreboard.score import score_entry
from pendulum_lqg.scoreboard.suites import load_suite, suite_names
from pendulum_lqg.util.files import atomic_write, output_folder, regular_target
from pendulum_lqg.util.scripts import ScriptParser, requires, run_script

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
    out = [(f"rl_{m}", {"agent": f"sb3:{_ref(models / f'{m}.zip')}"}) for m in MODELS]
    for path in sorted(models.glob("*-seed*.*")):
        if "-noise" in path.stem or path.name.endswith("-curve.csv"):
            continue
        if path.suffix == ".zip":
            out.append((f"rl_{path.stem}", {"agent": f"sb3:{_ref(path)}"}))
        elif path.suffix == ".json" and not path.with_suffix(".zip").exists():
            out.append((f"rl_{path.stem}", {"agent": f"linear:{_ref(path)}"}))
    return out


def _ref(path: Path) -> Path:
    """``path`` as the reference of an agent: relative to the checkout where it lies inside it
    (the score files then name no machine's folders), else absolute."""
    full = path.resolve()
    return full.relative_to(ROOT) if full.is_relative_to(ROOT) else full


def main(argv: list[str] | None = None) -> None:
    ap = ScriptParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=None,
                    help="folder of the scores/ and board.md (default: a fresh "
                         "runs/leaderboard-<UTC time>; docs/leaderboard is the committed one)")
    ap.add_argument("--force", action="store_true",
                    help="replace the scores and the board that --out already holds")
    ap.add_argument("--rl", action="store_true", help="score only the RL models (the rl extra)")
    ap.add_argument("--models", type=Path, default=ROOT / "experiments" / "agents" / "models")
    args = ap.parse_args(argv)
    if args.rl:
        requires("stable_baselines3", needed_for="--rl (the RL models)",
                 install="the rl extra: uv sync --extra rl")
        if not args.models.is_dir():
            raise ConfigError(f"--models: expected the folder of the trained models, got "
                              f"{str(args.models)!r}")
    out = args.out if args.out is not None else (
        Path("runs") / f"leaderboard-{time.strftime('%Y%m%dT%H%M%SZ', time.gmtime())}")
    entries = rl_entries(args.models) if args.rl else [
        *[(p, {"policy": p}) for p in BUILTINS],
        *[(f, {"policy": ref}) for f, ref in PLUGINS.items()],
        *[(f, {"agent": ref}) for f, ref in AGENTS.items()]]
    scores = output_folder("--out", out, what="scores and the board") / "scores"
    output_folder("--out", scores, what="score files")
    targets = [scores / f"{file}.json" for file, _ in entries] + [out / "board.md"]
    for target in targets:      # only regular files, checked before any scoring
        regular_target("--out", target, what="score or board")
    taken = [t for t in targets if t.exists()]
    if taken and not args.force:
        raise ConfigError(f"--out: {out} already holds {len(taken)} of these files (e.g. "
                          f"{taken[0].relative_to(out)}); pass --force to replace them")
    suites = [load_suite(n) for n in suite_names()]
    cache: dict = {}
    for file, entry in entries:
        t0 = time.perf_counter()
        doc = score_entry(suites, base_dir=ROOT, cache=cache, **entry)
        atomic_write(scores / f"{file}.json", json.dumps(doc, indent=1, allow_nan=False) + "\n")
        print(f"{file}: {time.perf_counter() - t0:.0f} s", flush=True)
    atomic_write(out / "board.md", make_board(scores))
    print(f"board: {out / 'board.md'}")


if __name__ == "__main__":
    run_script(main)
