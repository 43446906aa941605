"""Documented ceilings that keep a run finite in memory and time (README "Limits").

Work that streams to disk unit by unit (``bench``) may be large; what must sit in memory at once
is bounded here, and each bound is checked before any work starts, with a one-line
:class:`~pendulum_lqg.errors.ConfigError` naming the parameter.
"""

from __future__ import annotations

from pendulum_lqg.errors import ConfigError

#: ``run`` keeps every episode row in memory (and prints them with ``--json``); larger studies go
#: through ``bench``, which streams them to disk unit by unit.
MAX_RUN_EPISODES = 100_000
#: Episodes of one ``run --record``/``--spawn`` (every trajectory is kept for the recording).
MAX_RECORDED_EPISODES = 1_000
#: ``bench`` assembles ``episodes.csv`` and the summary from every row of the experiment
#: (configurations × episodes), about 2 kB of memory each.
MAX_BENCH_ROWS = 2_000_000
#: Points of a region-of-attraction map (each is one noise-free episode of the batch).
MAX_MAP_POINTS = 40_000
#: Frequencies of a margins study's grid and points of a stored Nyquist curve.
MAX_FREQUENCIES = 100_000
#: Episodes ``run`` steps together: bounded so memory does not grow with ``--episodes`` and long
#: runs report progress between batches (results do not depend on the batching).
RUN_BATCH = 1024
#: Seconds between two progress lines of a long ``run`` (stderr).
PROGRESS_EVERY_S = 2.0


def check_at_most(where: str, value: int, ceiling: int, why: str) -> int:
    """``value`` if ≤ ``ceiling``; else a one-line error naming ``where`` and saying ``why``."""
    if value > ceiling:
        raise ConfigError(f"{where}: at most {ceiling:,} ({why}), got {value:,}")
    return value
