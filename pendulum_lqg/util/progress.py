"""Progress of a long command, on stderr only: one mechanism for ``run``, ``bench`` and ``score``.

When stderr is a terminal, a rich progress bar (done / total, elapsed, ETA) drawn on stderr;
otherwise nothing, or — with ``lines=True`` (``run``) — one plain line every
:data:`~pendulum_lqg.util.limits.PROGRESS_EVERY_S` seconds once the work takes that long. stdout stays
free for the command's output (``--json``, a table, a pipe).
"""

from __future__ import annotations

import sys
import time
from typing import Any

from pendulum_lqg.util import limits


class Progress:
    """``with Progress("run", total, unit="episodes") as p: … p.advance(n)``.

    Parameters
    ----------
    label : what is counted, shown before the bar and at the start of a line
    total : the count when done
    done : the count already done (a resumed sweep)
    unit : the name of what is counted (``episodes``, ``work units``)
    enabled : draw the bar (default: stderr is a terminal)
    lines : without a bar, print a line every few seconds instead (default: no)
    """

    def __init__(self, label: str, total: int, *, done: int = 0, unit: str = "",
                 enabled: bool | None = None, lines: bool = False) -> None:
        self.label, self.total, self.done, self.unit = label, total, done, unit
        self.enabled = sys.stderr.isatty() if enabled is None else enabled
        self.lines = lines and not self.enabled
        self._bar: Any = None

    def __enter__(self) -> Progress:
        self._t0 = self._last = time.perf_counter()
        if self.enabled and self.total > self.done:
            from rich.console import Console
            from rich.progress import (
                BarColumn,
                MofNCompleteColumn,
                TextColumn,
                TimeElapsedColumn,
                TimeRemainingColumn,
            )
            from rich.progress import Progress as Bar

            self._bar = Bar(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                            TimeElapsedColumn(), TextColumn("ETA"), TimeRemainingColumn(),
                            console=Console(stderr=True), transient=False)
            self._bar.__enter__()
            self._task = self._bar.add_task(self.label, total=self.total, completed=self.done)
        return self

    def __exit__(self, *exc: object) -> None:
        if self._bar is not None:
            self._bar.__exit__(*exc)
            self._bar = None

    def advance(self, n: int = 1, *, description: str | None = None) -> None:
        """``n`` more done; ``description`` replaces the bar's label (e.g. the current item)."""
        self.done += n
        if self._bar is not None:
            self._bar.update(self._task, advance=n,
                             description=self.label if description is None else description)
            return
        now = time.perf_counter()
        if self.lines and self.done < self.total and now - self._last >= limits.PROGRESS_EVERY_S:
            eta = (now - self._t0) / max(self.done, 1) * (self.total - self.done)
            print(f"{self.label}: {self.done:,}/{self.total:,} {self.unit}, {now - self._t0:.0f} s, "
                  f"about {eta:.0f} s left", file=sys.stderr)
            self._last = now


__all__ = ["Progress"]
