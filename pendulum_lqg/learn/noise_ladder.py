"""The noise ladder: RL models and the LQG reference scored at noise_scale 0, 0.25, 0.5 and 1.

::

    python -m pendulum_lqg.learn.noise_ladder score --scores DIR MODELS/ppo-history-seed*.zip
    python -m pendulum_lqg.learn.noise_ladder score --scores DIR --matched \\
        MODELS/ppo-history-noise*-seed*.zip
    python -m pendulum_lqg.learn.noise_ladder figure --scores DIR --figure FIG/noise_ladder.png

``score`` (the ``rl`` extra for SB3 models) plays one suite (``--suite``, default ``lecture``) with
its env's ``noise_scale`` set to each of ``--scales`` — both noises' standard deviations times the
scale, the designs keeping the nominal noise model
(:meth:`~pendulum_lqg.scoreboard.suites.Suite.with_noise_scale`) — for the suite's reference
policy and for every model given. Each score file goes to ``--scores`` (default
``runs/noise_ladder/``; ``docs/leaderboard/noise_ladder/`` holds the committed ones),
``STEM-atX.json``, as ``pendulum-lqg score … --noise-scale X --out FILE`` writes it (the same
:func:`~pendulum_lqg.scoreboard.score.score_entry`, with ``noise_scale`` in the file). Without
``--matched`` every model is scored at every scale (a model trained at the suite's noise, asked
how it fares with less); with ``--matched`` a model is scored only at the scale it was trained at
(its training record's ``env.noise_scale``: ``pendulum-lqg train METHOD --seed S --noise-scale X``).

``figure`` reads those score files and draws success rate and failure-aware score against the noise
scale: per group of runs (a method, and whether its models were trained at the scored noise or at
the suite's) the median across seeds with its interquartile range, and the reference LQG design.
It writes the numbers beside the figure (``noise_ladder.md``; default
``runs/figures/noise_ladder.png``). The reference's failure-aware score against itself is its
success rate (``J_ref / J = 1`` on every episode it survives).

Outputs follow the command line's rule: a new path or a regular file, never a device, a FIFO or a
folder; an existing file is replaced only with ``--force``, and then whole (temp + rename).
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path
from typing import Any

import numpy as np

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.learn.runs import RUNS_FOLDER, output_path, write_text
from pendulum_lqg.problem import defaults
from pendulum_lqg.util.files import save_figure
from pendulum_lqg.util.scripts import script_status

SCORES = RUNS_FOLDER / "noise_ladder"
FIGURE = RUNS_FOLDER / "figures" / "noise_ladder.png"
SCALES = (0.0, 0.25, 0.5, 1.0)
LADDER_METHOD = re.compile(r"^(?P<base>.+)-noise(?P<scale>[0-9.e+-]+)$")


def trained_noise(model: Path) -> float:
    """The noise scale a model was trained at (its record's ``env.noise_scale``, default 1)."""
    from pendulum_lqg.scoreboard.sb3 import read_metadata

    return float(read_metadata(model)["env"].get("noise_scale", defaults.NOISE_SCALE))


def score(models: list[Path], scales: list[float], suite_name: str, out: Path, *,
          matched: bool, episodes: int | None, force: bool = False) -> None:
    from pendulum_lqg.scoreboard.score import score_entry
    from pendulum_lqg.scoreboard.suites import load_suite

    suite = load_suite(suite_name).with_episodes(episodes)
    jobs: list[tuple[float, str, dict[str, Any]]] = []
    for x in scales:
        jobs += [(x, "reference", {"policy": suite.reference})]
        jobs += [(x, m.stem, {"agent": f"sb3:{m}"}) for m in models
                 if not matched or trained_noise(m) == x]
    paths = [output_path("--scores", out / f"{stem}-at{x:g}.json", force=force, what="score file")
             for x, stem, _ in jobs]                      # every target checked before any work
    cache: dict[Any, Any] = {}
    for (x, _, entry), path in zip(jobs, paths, strict=True):
        doc = score_entry([suite], cache=cache, noise_scale=x, **entry)
        write_text(path, json.dumps(doc, indent=1, allow_nan=False) + "\n")
        e = doc["suites"][suite.name]
        shown = "–" if e.get("score_mean") is None else f"{e['score_mean']:.3f}"
        print(f"{path.name}: success {e['success_rate']:.2f}, score {shown}", flush=True)


def group_of(doc: dict[str, Any]) -> str:
    """The figure's group of a score file: the reference, or a method and how it was trained."""
    if doc.get("method") is None:
        return f"LQG reference ({doc['policy']})"
    ladder = LADDER_METHOD.match(doc["method"])
    if ladder:
        return f"{ladder['base']} (trained at the scored noise)"
    return f"{doc['method']} (trained at the suite's noise)"


def ladder_table(folder: Path, suite: str) -> dict[str, dict[float, list[tuple[float, float]]]]:
    """``{group: {scale: [(success, score), …one per run]}}`` from the score files of ``folder``."""
    from pendulum_lqg.scoreboard.board import read_scores

    out: dict[str, dict[float, list[tuple[float, float]]]] = {}
    for path, doc in read_scores(folder):
        raw = json.loads(path.read_text(encoding="utf-8"))
        e = doc["suites"].get(suite)
        if "noise_scale" not in raw or e is None or not e.get("applicable", True):
            continue
        score = e.get("score_mean")
        out.setdefault(group_of(doc), {}).setdefault(float(raw["noise_scale"]), []).append(
            (e["success_rate"], np.nan if score is None else score))
    if not out:
        raise ConfigError(f"--scores: {folder}: no score file with a noise_scale on suite {suite!r}")
    return out


def quartiles(values: list[float]) -> tuple[float, float, float]:
    q25, med, q75 = np.percentile(np.asarray(values, dtype=float), [25, 50, 75])
    return float(med), float(q25), float(q75)


def draw(table: dict[str, dict[float, list[tuple[float, float]]]], suite: str, path: Path) -> None:
    from matplotlib.figure import Figure

    fig = Figure(figsize=(9.0, 3.8), layout="constrained")
    axes = fig.subplots(1, 2, sharex=True)
    for group, by_scale in sorted(table.items()):
        scales = sorted(by_scale)
        for ax, k, name in ((axes[0], 0, "success rate"), (axes[1], 1, "failure-aware score")):
            q = np.array([quartiles([run[k] for run in by_scale[x]]) for x in scales])
            runs = max(len(by_scale[x]) for x in scales)
            style = {"color": "k", "ls": "--"} if group.startswith("LQG") else {}
            line, = ax.plot(scales, q[:, 0], marker="o", label=f"{group}, {runs} run(s)",
                            **style)
            if runs > 1:
                ax.fill_between(scales, q[:, 1], q[:, 2], color=line.get_color(), alpha=0.2)
            ax.set(xlabel="noise_scale (× both noises' std)", ylabel=name)
    axes[0].set_ylim(-0.02, 1.02)
    axes[0].legend(fontsize=7, loc="best")
    fig.suptitle(f"Noise ladder on `{suite}`: median and interquartile range across seeds")
    save_figure(fig, path, where="--out", what="figure", dpi=120)


def markdown(table: dict[str, dict[float, list[tuple[float, float]]]], suite: str) -> str:
    scales = sorted({x for by_scale in table.values() for x in by_scale})
    lines = ["| group | runs | " + " | ".join(f"noise {x:g}: success, score" for x in scales)
             + " |", "|---|---|" + "---|" * len(scales)]
    for group, by_scale in sorted(table.items()):
        cells = []
        for x in scales:
            if x not in by_scale:
                cells.append("")
                continue
            s, f = (quartiles([run[k] for run in by_scale[x]]) for k in (0, 1))
            cells.append(f"{100 * s[0]:.0f} % [{100 * s[1]:.0f}, {100 * s[2]:.0f}], "
                         f"{f[0]:.2f} [{f[1]:.2f}, {f[2]:.2f}]")
        runs = max(len(v) for v in by_scale.values())
        lines.append(f"| {group} | {runs} | " + " | ".join(cells) + " |")
    lines += ["", f"Suite `{suite}` at each noise scale: median [interquartile range] across runs "
              "of the success rate and the failure-aware score. Made by `uv run python -m "
              "pendulum_lqg.learn.noise_ladder figure`."]
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    return script_status(lambda: _main(argv))


def _main(argv: list[str] | None) -> int:
    ap = argparse.ArgumentParser(prog="python -m pendulum_lqg.learn.noise_ladder",
                                 description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="what", required=True)
    p = sub.add_parser("score", help="score the models and the reference at each noise scale")
    p.add_argument("models", type=Path, nargs="*", help="sb3 model zips (their records beside)")
    p.add_argument("--scales", type=float, nargs="+", default=list(SCALES))
    p.add_argument("--matched", action="store_true",
                   help="score a model only at the noise scale it was trained at")
    p.add_argument("--episodes", type=int, default=None, help="default: the suite's own")
    f = sub.add_parser("figure", help="draw the ladder from the score files")
    f.add_argument("--figure", type=Path, default=FIGURE,
                   help=f"the figure; the table goes beside it (.md) (default {FIGURE})")
    for q in (p, f):
        q.add_argument("--suite", default="lecture")
        q.add_argument("--scores", type=Path, default=SCORES,
                       help=f"folder of the ladder's score files (default {SCORES})")
        q.add_argument("--force", action="store_true", help="replace existing output files")
    args = ap.parse_args(argv)
    if args.what == "score":
        bad = [x for x in args.scales if not 0 <= x < float("inf")]
        if bad:
            raise ConfigError(f"--scales: expected finite numbers ≥ 0, got {bad[0]}")
        if args.episodes is not None and args.episodes < 1:
            raise ConfigError(f"--episodes: expected a positive integer, got {args.episodes}")
        score(args.models, args.scales, args.suite, args.scores, matched=args.matched,
              episodes=args.episodes, force=args.force)
        return 0
    figure = output_path("--figure", args.figure, force=args.force, what="figure")
    table_path = output_path("--figure", figure.with_suffix(".md"), force=args.force,
                             what="table")
    table = ladder_table(args.scores, args.suite)
    draw(table, args.suite, figure)
    write_text(table_path, markdown(table, args.suite))
    print(f"wrote {figure} and {table_path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
