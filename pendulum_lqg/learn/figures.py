"""The RL baselines' comparisons across training runs: performance profiles, probabilities of
improvement and learning curves, from the committed score files and curves (nothing is trained).

    python -m pendulum_lqg.learn.figures profile docs/leaderboard/scores --out DIR
    python -m pendulum_lqg.learn.figures curves experiments/agents/models --out DIR
    python -m pendulum_lqg.learn.figures budget experiments/agents/models --out DIR

(``profile.png`` and ``improvement.md``; ``curves.png``; ``budget.md``).

Outputs go to ``--out`` (default ``runs/figures/``) by the command line's rule: a new path or a
regular file, never a device, a FIFO or a folder; an existing file replaced only with ``--force``,
and then whole. Inputs are read from regular files only (a FIFO named like a curve is skipped).

``profile``: the score files that name a ``method`` (one per training seed, as ``board``'s methods
table reads them) and the single entries named by ``--entry`` (default the LQG reference
``dlqr+kalman``), on the board's version of every measurement suite. Per method, the runs × suites
array of failure-aware scores (:mod:`pendulum_lqg.scoreboard.stats`: ``J_ref / J``, 0 for a failed
episode) gives

* ``profile.png`` — the performance profile: the share of run × suite scores above each threshold
  τ, with its stratified bootstrap 95 % band (Agarwal et al. 2021, Fig. 5);
* ``improvement.md`` — the probability of improvement ``P(X > Y)`` of each method over each other,
  with its stratified bootstrap 95 % interval, and the suites it is taken over.

``curves``: every ``METHOD-seedS-curve.csv`` (``pendulum-lqg train``: success rate and
failure-aware score on 20 fixed non-suite episodes every ``--eval-every`` env steps) grouped by
method, and ``curves.png``: per method the median and the interquartile range across seeds of
success and score against env steps and against wall time. A run's points are linearly
interpolated onto a common grid inside its own range (a grid point beyond a run's last point
leaves that run out there); the figure says how many seeds each method has.

``budget``: every training record of a run (``METHOD-seedS.json``: an SB3 model's record, its
``budget``, or a linear controller's ``training``) grouped by method, and ``budget.md``: per method
the runs, the env steps of one run, the median wall time of a run, and the CPU-hours of all its
runs (wall seconds × the threads a run used, one for every method here: torch on one thread, one
physics thread). Wall times are those of the machine and load the run had.
"""

from __future__ import annotations

import argparse
import csv
import re
import sys
from pathlib import Path
from typing import Any

import numpy as np

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.learn.runs import RUNS_FOLDER, output_path, write_text
from pendulum_lqg.util.files import save_figure
from pendulum_lqg.util.scripts import script_status

OUT = RUNS_FOLDER / "figures"
#: Thresholds τ of the performance profile (failure-aware score; 1 = the reference).
TAUS = np.linspace(0.0, 1.25, 126)
CURVE_FILE = re.compile(r"^(?P<method>.+)-seed(?P<seed>\d+)-curve\.csv$")


# ---- performance profile and probability of improvement ----------------------------------------
def method_scores(folder: Path, entries: list[str]) -> tuple[list[str], dict[str, np.ndarray]]:
    """``(suites, {method: (runs, suites) failure-aware scores})`` over the measurement suites
    every method was scored on; a named entry (``--entry``) is one run of its own."""
    from pendulum_lqg.scoreboard.board import board_scores, comparable, method_runs

    scores, suites, prints = board_scores(folder)
    groups: dict[str, dict[Any, dict[str, Any]]] = dict(method_runs(scores))
    for name in entries:
        found = [d for _, d in scores if d["policy"] == name]
        if not found:
            raise ConfigError(f"--entry: no score file of {name!r} in {folder}")
        groups[name] = {name: found[0]}
    suites = [s for s in suites if s != "full-state"]
    groups = {m: runs for m, runs in groups.items()      # methods of the measurement suites
              if any(comparable(runs, s, prints) for s in suites)}
    measured = [s for s in suites if all(comparable(runs, s, prints) for runs in groups.values())]
    if not groups or not measured:
        raise ConfigError(f"{folder}: no method with comparable scores on a measurement suite")
    out = {}
    for method, runs in groups.items():
        table = [[comparable({0: d}, s, prints) for s in measured] for d in runs.values()]
        out[method] = np.array([[e[0]["score_mean"] for e in row] for row in table
                                if all(row)], dtype=float)      # runs scored on every suite
    return measured, out


def _share_above(tau: float) -> Any:
    """The statistic ``scores ↦`` the share of scores above ``tau`` (one point of the profile)."""
    from pendulum_lqg.scoreboard.stats import performance_profile

    def share(scores: np.ndarray) -> float:
        return float(performance_profile(scores, np.array([tau]))[0])

    return share


#: Line styles of the methods past each ten colours: matplotlib's cycle has ten colours, and the
#: eleventh method would share the first one's line.
LINE_STYLES = ("-", "--", ":", "-.")


def method_styles(methods: list[str]) -> dict[str, dict[str, Any]]:
    """A colour and a line style per method, sorted by name: the ten colours of ``tab10`` with
    the first line style, then again with the next (distinct for up to 40 methods)."""
    return {m: {"color": f"C{i % 10}", "ls": LINE_STYLES[(i // 10) % len(LINE_STYLES)]}
            for i, m in enumerate(sorted(methods))}


def draw_profile(scores: dict[str, np.ndarray], suites: list[str], path: Path) -> None:
    from matplotlib.figure import Figure

    from pendulum_lqg.scoreboard.stats import performance_profile, stratified_bootstrap_ci

    fig = Figure(figsize=(7.0, 4.2), layout="constrained")
    ax = fig.add_subplot()
    styles = method_styles(list(scores))
    for method, x in sorted(scores.items()):
        curve = performance_profile(x, TAUS)
        line, = ax.plot(TAUS, curve, label=f"{method} ({x.shape[0]} runs)", **styles[method])
        if x.shape[0] > 1:
            band = np.array([stratified_bootstrap_ci(x, _share_above(t), resamples=500)
                             for t in TAUS])
            ax.fill_between(TAUS, band[:, 0], band[:, 1], color=line.get_color(), alpha=0.2)
    ax.axvline(1.0, color="0.5", lw=0.8, ls=":")
    ax.set(xlabel="failure-aware score τ (J_ref / J, 0 for a failure; 1 = the LQG reference)",
           ylabel="share of run × suite scores > τ", ylim=(-0.02, 1.02),
           title="Performance profile over " + ", ".join(suites))
    ax.legend(fontsize=8, loc="lower left")
    save_figure(fig, path, where="--out", what="figure", dpi=120)


def improvement_table(scores: dict[str, np.ndarray], suites: list[str]) -> str:
    from pendulum_lqg.scoreboard.stats import (
        probability_of_improvement,
        probability_of_improvement_ci,
    )

    names = sorted(scores)
    lines = ["| P(row > column) | " + " | ".join(f"`{n}`" for n in names) + " |",
             "|---|" + "---|" * len(names)]
    for a in names:
        cells = []
        for b in names:
            if a == b:
                cells.append("–")
                continue
            p = probability_of_improvement(scores[a], scores[b])
            lo, hi = probability_of_improvement_ci(scores[a], scores[b])
            cells.append(f"{p:.2f} [{lo:.2f}, {hi:.2f}]")
        lines.append(f"| `{a}` | " + " | ".join(cells) + " |")
    lines += ["", "P(X > Y): the probability that a run of X has a higher failure-aware score than "
              "a run of Y on the same suite (ties ½), averaged over the suites "
              + ", ".join(f"`{s}`" for s in suites) + ", with its 95 % stratified bootstrap "
              "interval (runs resampled within each suite, 2 000 resamples). Made by `uv run "
              "python -m pendulum_lqg.learn.figures profile docs/leaderboard/scores`."]
    return "\n".join(lines) + "\n"


# ---- learning curves ------------------------------------------------------------------------------
def read_curves(folder: Path) -> dict[str, list[dict[str, np.ndarray]]]:
    """``{method: [run, …]}``, each run its curve's columns as arrays (``METHOD-seedS-curve.csv``)."""
    out: dict[str, list[dict[str, np.ndarray]]] = {}
    for path in sorted(folder.glob("*-curve.csv")):
        match = CURVE_FILE.match(path.name)
        if match is None or not path.is_file():        # a FIFO or a folder is never opened
            continue
        with path.open(newline="", encoding="utf-8") as f:
            rows = list(csv.DictReader(f))
        if not rows:
            continue
        cols = {k: np.array([float(r[k]) if r[k] not in ("", "None") else np.nan for r in rows])
                for k in ("env_steps", "wall_seconds", "success_rate", "score_mean")}
        out.setdefault(match["method"], []).append(cols)
    if not out:
        raise ConfigError(f"{folder}: no METHOD-seedS-curve.csv (regular files)")
    return out


def median_iqr(runs: list[dict[str, np.ndarray]], x: str, y: str,
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(grid, median, q25, q75)`` across runs of ``y`` against ``x``, each run interpolated
    inside its own range (nan outside it)."""
    grid = np.linspace(0.0, max(float(r[x].max()) for r in runs), 101)
    table = np.array([np.where((grid >= r[x].min()) & (grid <= r[x].max()),
                               np.interp(grid, r[x], r[y]), np.nan) for r in runs])
    seen = np.isfinite(table).any(axis=0)
    q = np.full((3, grid.size), np.nan)
    q[:, seen] = np.nanpercentile(table[:, seen], [50, 25, 75], axis=0)
    return grid, q[0], q[1], q[2]


def draw_curves(curves: dict[str, list[dict[str, np.ndarray]]], path: Path) -> None:
    save_figure(curves_figure(curves), path, where="--out", what="figure", dpi=120)


def curves_figure(curves: dict[str, list[dict[str, np.ndarray]]]) -> Any:
    """The learning curves' figure (``curves.png``): a colour and line style per method
    (:func:`method_styles`)."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10.0, 6.5), layout="constrained")
    axes = fig.subplots(2, 2, sharey="row")
    styles = method_styles(list(curves))
    for method, runs in sorted(curves.items()):
        for col, (x, scale, label) in enumerate((("env_steps", 1e6, "env steps [millions]"),
                                                 ("wall_seconds", 3600.0, "wall time [h]"))):
            for row, (y, name) in enumerate((("success_rate", "success rate"),
                                             ("score_mean", "failure-aware score"))):
                ax = axes[row, col]
                grid, med, lo, hi = median_iqr(runs, x, y)
                line, = ax.plot(grid / scale, med, label=f"{method} ({len(runs)} seeds)",
                                **styles[method])
                ax.fill_between(grid / scale, lo, hi, color=line.get_color(), alpha=0.2)
                ax.set(xlabel=label, ylabel=name)
    axes[0, 0].legend(fontsize=8)
    fig.suptitle("Learning curves: median and interquartile range across seeds "
                 "(20 fixed non-suite episodes per point)")
    return fig


# ---- training budgets ----------------------------------------------------------------------------
RUN_FILE = re.compile(r"^(?P<method>.+)-seed(?P<seed>\d+)\.json$")


def read_budgets(folder: Path) -> dict[str, list[tuple[int, float, int]]]:
    """``{method: [(env steps, wall seconds, threads) per run]}`` from the runs' records."""
    import json

    out: dict[str, list[tuple[int, float, int]]] = {}
    for path in sorted(folder.glob("*-seed*.json")):
        if not RUN_FILE.match(path.name) or not path.is_file():
            continue
        try:
            doc = json.loads(path.read_text(encoding="utf-8"))
        except (UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise ConfigError(f"{path}: expected a training record (JSON), got {exc}") from None
        if not isinstance(doc, dict):
            continue
        if "budget" in doc:                                     # an SB3 model's training record
            budget = doc["budget"]
            run = (int(budget["steps"]), float(budget["wall_seconds"]), int(budget["threads"]))
        elif "training" in doc:                                 # a linear controller's
            t = doc["training"]
            run = (int(t["budget"]["steps"]), float(t["wall_seconds"]), 1)
        else:
            continue
        out.setdefault(str(doc["method"]), []).append(run)
    return out


def budget_table(budgets: dict[str, list[tuple[int, float, int]]]) -> str:
    lines = ["| method | runs | env steps per run | wall time of a run (median) | CPU-hours, all runs |",
             "|---|---|---|---|---|"]
    total = 0.0
    for method, runs in sorted(budgets.items()):
        steps = sorted({r[0] for r in runs})
        shown = f"{steps[0]:,}" if len(steps) == 1 else f"{steps[0]:,} – {steps[-1]:,}"
        hours = sum(r[1] * r[2] for r in runs) / 3600
        total += hours
        lines.append(f"| `{method}` | {len(runs)} | {shown} | "
                     f"{float(np.median([r[1] for r in runs])):.0f} s | {hours:.2f} |")
    lines.append(f"| all | {sum(len(r) for r in budgets.values())} | | | {total:.2f} |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    return script_status(lambda: _main(argv))


def _main(argv: list[str] | None) -> int:
    ap = argparse.ArgumentParser(prog="python -m pendulum_lqg.learn.figures",
                                 description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="what", required=True)
    p = sub.add_parser("profile", help="performance profile and probability of improvement")
    p.add_argument("scores", type=Path, help="folder of score files (board's)")
    p.add_argument("--entry", action="append", default=None,
                   help="a single entry to add by its policy name (default: dlqr+kalman)")
    q = sub.add_parser("curves", help="learning curves across seeds")
    q.add_argument("models", type=Path, help="folder of METHOD-seedS-curve.csv")
    b = sub.add_parser("budget", help="runs, env steps, wall time and CPU-hours per method")
    b.add_argument("models", type=Path, help="folder of the runs' METHOD-seedS.json records")
    for x in (p, q, b):
        x.add_argument("--out", type=Path, default=OUT, help=f"output folder (default {OUT})")
        x.add_argument("--force", action="store_true", help="replace existing output files")
    args = ap.parse_args(argv)
    folder = args.scores if args.what == "profile" else args.models
    if not folder.is_dir():
        raise ConfigError(f"{folder}: expected a folder of "
                          + ("score files" if args.what == "profile" else "training runs"))
    names = {"profile": ("profile.png", "improvement.md"), "curves": ("curves.png",),
             "budget": ("budget.md",)}[args.what]
    paths = [output_path("--out", args.out / n, force=args.force, what=n) for n in names]
    if args.what == "profile":
        suites, scores = method_scores(args.scores, args.entry or ["dlqr+kalman"])
        draw_profile(scores, suites, paths[0])
        write_text(paths[1], improvement_table(scores, suites))
        print(f"wrote {paths[0]} and {paths[1]}")
    elif args.what == "budget":
        table = budget_table(read_budgets(args.models))
        write_text(paths[0], table)
        print(table, end="")
    else:
        draw_curves(read_curves(args.models), paths[0])
        print(f"wrote {paths[0]}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
