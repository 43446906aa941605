"""The board page's compact summary: one row per entry, one column per suite, success and gap in one cell.

    uv run python docs/leaderboard/summary.py        # → docs/leaderboard/summary.md, summary.png

Reads the same score files as ``pendulum-lqg board docs/leaderboard/scores`` (the full table,
``board.md``) and keeps, per suite, the success rate and the optimality gap (its interval stays in
the full table). A suite's cell is filled only for the scores made on the board's version of that
suite (its most common fingerprint), as in the full table. The figure is the same data as a
colour map (success rate), written with matplotlib's object API. A training run (a score file
with a ``method`` and a ``seed``) is not a row: ``board``'s methods table aggregates the runs of
each method.
"""

from __future__ import annotations

import sys
from collections import Counter
from pathlib import Path
from typing import Any

from pendulum_lqg.scoreboard.board import read_scores
from pendulum_lqg.scoreboard.suites import SUITE_ORDER

HERE = Path(__file__).resolve().parent


def summary_cells(scores: list[tuple[Path, dict[str, Any]]],
                  ) -> tuple[list[str], list[tuple[str, list[tuple[float, float | None] | str]]]]:
    """``(suites, rows)``: each row an entry and, per suite, ``(success, gap)`` or a note
    (``"n/a"`` not playable as posed, ``""`` not scored on the board's version of the suite)."""
    names = {n for _, d in scores for n in d["suites"]}
    suites = [n for n in SUITE_ORDER if n in names] + sorted(names - set(SUITE_ORDER))
    prints = {s: Counter(d["suites"][s]["fingerprint"] for _, d in scores if s in d["suites"])
              .most_common(1)[0][0] for s in suites}
    rows: list[tuple[str, list[tuple[float, float | None] | str]]] = []
    for _, d in sorted(scores, key=lambda item: item[1]["policy"]):
        if d.get("method") is not None and d.get("seed") is not None:
            continue                         # a training run: the methods table aggregates it
        cells: list[tuple[float, float | None] | str] = []
        for s in suites:
            e = d["suites"].get(s)
            if e is not None and not e.get("applicable", True):
                cells.append("n/a")
            elif e is None or e.get("fingerprint") != prints[s]:
                cells.append("")
            else:
                cells.append((float(e["success_rate"]), e.get("optimality_gap")))
        rows.append((d["policy"], cells))
    return suites, rows


def _cell(cell: tuple[float, float | None] | str) -> str:
    if isinstance(cell, str):
        return cell
    success, gap = cell
    return f"{100 * success:.0f} %" + ("" if gap is None else f" · {gap:+.2f}")


def summary_markdown(scores: list[tuple[Path, dict[str, Any]]]) -> str:
    suites, rows = summary_cells(scores)
    lines = ["| entry | " + " | ".join(suites) + " |", "|---|" + "---|" * len(suites)]
    lines += [f"| `{name}` | " + " | ".join(_cell(c) for c in cells) + " |" for name, cells in rows]
    return "\n".join(lines) + "\n"


def summary_figure(scores: list[tuple[Path, dict[str, Any]]], path: Path) -> None:
    import matplotlib
    import numpy as np
    from matplotlib.figure import Figure

    suites, rows = summary_cells(scores)
    rate = np.array([[c[0] if isinstance(c, tuple) else np.nan for c in cells] for _, cells in rows])
    with matplotlib.rc_context({"font.size": 9}):
        fig = Figure(figsize=(10.0, 0.42 * len(rows) + 1.2), layout="constrained")
        ax = fig.subplots()
        image = ax.imshow(rate, cmap="RdYlGn", vmin=0, vmax=1, aspect="auto")
        ax.set_xticks(range(len(suites)), suites)
        ax.xaxis.tick_top()
        ax.set_yticks(range(len(rows)), [name for name, _ in rows])
        for i, (_, cells) in enumerate(rows):
            for j, c in enumerate(cells):
                ax.text(j, i, _cell(c).replace(" · ", "\n") if c else "", ha="center",
                        va="center", fontsize=7.5, linespacing=1.1)
        fig.colorbar(image, ax=ax, shrink=0.6, label="success rate (cell: success · gap to the "
                                                      "suite's reference)")
        fig.savefig(path, dpi=100)


def main(argv: list[str]) -> int:
    folder = Path(argv[0]) if argv else HERE / "scores"
    scores = read_scores(folder)
    (HERE / "summary.md").write_text(summary_markdown(scores), encoding="utf-8")
    summary_figure(scores, HERE / "summary.png")
    print(f"wrote {HERE / 'summary.md'} and {HERE / 'summary.png'} from {len(scores)} score files")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
