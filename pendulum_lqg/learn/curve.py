"""The learning curve of a run: the controller's figures on 20 fixed non-suite episodes, point by
point, written whole at every point.

Each point plays the curve's episodes (:func:`~pendulum_lqg.learn.runs.eval_suite`) through the
scorer's own batch path — :func:`~pendulum_lqg.scoreboard.linear.linear_rows` for a linear
controller, :func:`~pendulum_lqg.scoreboard.sb3_batch.batched_rows` for an SB3 model — and takes
the success rate and the failure-aware score (:mod:`pendulum_lqg.scoreboard.stats`: ``J_ref / J``
on a survived episode, 0 on a failed one) against the suite's reference on the same episodes.
Beside them: the mean return and length of the training episodes that ended since the previous
point (``nan`` where none did).
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any

from pendulum_lqg.learn.runs import CURVE_COLUMNS, eval_suite, progress_line, write_text


class Curve:
    """The points of one run's curve, kept in ``path`` (a CSV rewritten atomically at each point).

    ``offset_seconds`` is the wall time the run had spent before a resume, so that
    ``wall_seconds`` counts the whole run's time."""

    def __init__(self, suite: Any, path: Path, *, name: str, log: Any,
                 points: list[dict[str, Any]] | None = None) -> None:
        from pendulum_lqg.scoreboard import episodes as ep

        self.suite, self.path, self.name, self.log = eval_suite(suite), path, name, log
        self.reference = ep.policy_rows(self.suite, suite.reference, nthread=1)
        self.points: list[dict[str, Any]] = list(points or [])
        self.offset = float(self.points[-1]["wall_seconds"]) if self.points else 0.0
        self.t0 = time.perf_counter()

    def wall_seconds(self) -> float:
        return round(self.offset + time.perf_counter() - self.t0, 1)

    def add(self, env_steps: int, rows: list[dict[str, Any]], *,
            train_return: float = math.nan, train_length: float = math.nan) -> dict[str, Any]:
        """A point from the curve episodes' ``rows``; the CSV is rewritten with it."""
        from pendulum_lqg.scoreboard.score import success_figures
        from pendulum_lqg.scoreboard.stats import failure_aware_figures

        fig = failure_aware_figures(rows, self.reference)
        lo, hi = fig["score_ci"]
        point = {"env_steps": int(env_steps), "wall_seconds": self.wall_seconds(),
                 "success_rate": success_figures(rows)["success_rate"],
                 "score_mean": fig["score_mean"], "score_ci_lo": lo, "score_ci_hi": hi,
                 "train_return": train_return, "train_length": train_length}
        self.points.append(point)
        write_text(self.path, curve_csv(self.points))
        self.log(progress_line(self.name, point))
        return point

    def add_linear(self, env_steps: int, doc: dict[str, Any], **train: float) -> dict[str, Any]:
        """A point of the linear controller document ``doc``."""
        from pendulum_lqg.scoreboard.linear import linear_rows

        rows = linear_rows(self.suite, doc, name=f"({self.name})", nthread=1)
        return self.add(env_steps, rows, **train)


def curve_csv(points: list[dict[str, Any]]) -> str:
    """The CSV of ``points`` (:data:`~pendulum_lqg.learn.runs.CURVE_COLUMNS`; ``None`` and ``nan``
    as empty cells, floats as ``repr``: read back, they are the same numbers)."""
    def cell(v: Any) -> str:
        if v is None or (isinstance(v, float) and math.isnan(v)):
            return ""
        return repr(v) if isinstance(v, float) else str(v)

    lines = [",".join(CURVE_COLUMNS)]
    lines += [",".join(cell(p.get(k)) for k in CURVE_COLUMNS) for p in points]
    return "\n".join(lines) + "\n"


def read_curve(path: Path) -> list[dict[str, Any]]:
    """The points of a curve CSV written by :func:`curve_csv` (for a resume)."""
    import csv

    def value(k: str, v: str) -> Any:
        if v == "":
            return None if k.startswith("score") else math.nan
        return int(v) if k == "env_steps" else float(v)

    with path.open(newline="", encoding="utf-8") as f:
        return [{k: value(k, r.get(k) or "") for k in CURVE_COLUMNS} for r in csv.DictReader(f)]
