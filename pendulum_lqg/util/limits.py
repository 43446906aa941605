"""Documented ceilings that keep a run finite in memory and time (docs/closed-loop.md, "Limits").

Work that streams to disk unit by unit (``bench``) may be large; what must sit in memory at once
is bounded here, and each bound is checked before any work starts, with a one-line
:class:`~pendulum_lqg.errors.ConfigError` naming the parameter.
"""

from __future__ import annotations

import itertools
import operator
from collections.abc import Iterable
from typing import Any

from pendulum_lqg.errors import ConfigError, PendulumLQGError
from pendulum_lqg.problem.declare import positive_number

#: ``run`` keeps every episode row in memory (and prints them with ``--json``); larger studies go
#: through ``bench``, which streams them to disk unit by unit.
MAX_RUN_EPISODES = 100_000
#: Episodes of one ``run --record``/``--spawn`` (every trajectory is kept for the recording).
MAX_RECORDED_EPISODES = 1_000
#: ``bench`` assembles ``episodes.csv`` and the summary from every row of the experiment
#: (configurations × episodes), about 2 kB of memory each.
MAX_BENCH_ROWS = 2_000_000
#: Configurations of one experiment grid (each is validated — its model compiled once per distinct
#: model — before the first work unit runs).
MAX_CONFIGURATIONS = 100_000
#: Points of a region-of-attraction map (each is one noise-free episode of the batch).
MAX_MAP_POINTS = 40_000
#: Frequencies of a margins study's grid and points of a stored Nyquist curve.
MAX_FREQUENCIES = 100_000
#: Sub-environments of one vector env (``gymnasium.make_vec(…, num_envs=N)``): each is a row of
#: every array of the batched core — a MuJoCo simulation, its noise block, its generator.
MAX_NUM_ENVS = 100_000
#: Alternating bare-physics / closed-loop pairs of one ``perf`` run (each pair runs the whole batch
#: three times).
MAX_PERF_REPEATS = 100
#: Physics steps of one ``perf`` batch (episodes × steps per episode): the bare-physics baselines
#: hold a force for every step of every episode, and the reference rollout with outputs its
#: state and sensor data as well (eight floats a step for the shipped model).
MAX_PERF_STEPS = 10**7
#: Floats the finite-horizon Riccati sweep keeps: ``P`` is (horizon + 1) × n × n (and ``K``
#: horizon × m × n beside it), all in memory.
MAX_RICCATI_FLOATS = 2 * 10**7
#: Episodes per suite of one ``score`` (``--episodes`` or a suite file's ``episodes``): the rows of
#: the entry, its reference and the full-state bound are kept in memory and written to the score file.
MAX_SCORE_EPISODES = 100_000
#: Bytes of one file read at the boundary (experiment and suite TOML, score JSON, training records):
#: read whole into memory; the largest a score file of :data:`MAX_SCORE_EPISODES` per suite needs
#: is about a tenth of this.
MAX_INPUT_BYTES = 256 * 2**20
#: Nesting of tables and lists in a file read at the boundary: the project's formats nest at most
#: five deep; the parsers recurse once per level.
MAX_NESTING = 64
#: Episodes of one :func:`~pendulum_lqg.core.runner.run_episodes` call (the Python API): each is a
#: row of every array of the batched core — a MuJoCo simulation, its noise block, its generator —
#: and keeps its metric row. The front ends stay within it: ``run`` steps :data:`RUN_BATCH` at a
#: time, ``score`` at most :data:`MAX_SCORE_EPISODES`, ``bench`` a work unit.
MAX_BATCH_EPISODES = 100_000
#: Episodes ``run`` steps together: bounded so memory does not grow with ``--episodes`` and long
#: runs report progress between batches (results do not depend on the batching).
RUN_BATCH = 1024
#: Seconds between two progress lines of a long ``run`` (stderr).
PROGRESS_EVERY_S = 2.0


def check_at_most(where: str, value: int, ceiling: int, why: str, *,
                  error: type[PendulumLQGError] = ConfigError) -> int:
    """``value`` if ≤ ``ceiling``; else a one-line ``error`` naming ``where`` and saying ``why``."""
    if value > ceiling:
        raise error(f"{where}: at most {ceiling:,} ({why}), got {value:,}")
    return value


def check_episodes(episodes: Iterable[Any], *, trajectory: bool = False) -> list[int]:
    """The episode numbers of one batch as a list of ints, counted before any is made.

    At least one, at most :data:`MAX_BATCH_EPISODES` (:data:`MAX_RECORDED_EPISODES` with
    ``trajectory``: every period of every episode is kept); a ``range`` or an array is counted by
    its length, any other iterable read at most one past the ceiling, so ``range(10**9)`` is
    refused at once. Otherwise one :class:`ConfigError` line naming ``episodes``."""
    ceiling, why = ((MAX_RECORDED_EPISODES, "trajectory=True keeps every period of every episode")
                    if trajectory else
                    (MAX_BATCH_EPISODES, "each is a row of every array of the batched core and "
                     "keeps its metric row; run larger studies in batches, or through bench"))
    try:
        count = len(episodes)                        # type: ignore[arg-type]
    except TypeError:                                # a generator: read one past the ceiling
        episodes = list(itertools.islice(episodes, ceiling + 1))
        count = len(episodes)
        if count > ceiling:
            raise ConfigError(f"episodes: at most {ceiling:,} ({why}), got more") from None
    check_at_most("episodes", count, ceiling, why)
    if count == 0:
        raise ConfigError("episodes: expected at least one episode number, got an empty "
                          "collection")
    try:
        return [operator.index(e) for e in episodes]
    except TypeError:
        bad = next(e for e in episodes if not _is_index(e))
        raise ConfigError(f"episodes: expected integer episode numbers, got {bad!r}") from None


def _is_index(value: Any) -> bool:
    try:
        operator.index(value)
    except TypeError:
        return False
    return True


#: Ceiling of the control period T [s]. The cart-pole's unstable pole (≈ 4 rad/s) grows by e⁴ over
#: one second; far longer periods overflow the designs (e^{AT}) and mean nothing for this problem.
MAX_CONTROL_PERIOD = 1.0
#: Floor of the control period T [s]: a megahertz sampled controller. Below it no episode of a
#: useful length fits in :data:`MAX_PERIODS` periods (at the floor one may last 100 s).
MIN_CONTROL_PERIOD = 1e-6
#: Ceiling of the physics steps per control period (bounds the per-period work of the loop and of
#: the composed ``mjd_transitionFD``, whatever the model's timestep).
MAX_STEPS_PER_PERIOD = 10_000
#: Ceiling of the control periods per episode (duration / T): keeps an episode finite (10⁸ periods
#: are ~10⁹ physics steps, hours per episode) and its metrics' counters exact.
MAX_PERIODS = 10**8
#: Ceiling of a noise scale (it multiplies the noise's standard deviations, its covariances by its
#: square): far beyond any physical noise, and far below where the theory's covariances or a
#: period's noise overflow a float (scale² past 10³⁰⁸ is inf).
MAX_NOISE_SCALE = 1e12
#: Ceiling of a measurement or actuator delay in control periods (a ring buffer of that many slots
#: per episode).
MAX_DELAY_PERIODS = 10_000


def check_control_period(control_period: object) -> float:
    """``control_period`` [s] as a float within [:data:`MIN_CONTROL_PERIOD`,
    :data:`MAX_CONTROL_PERIOD`]; otherwise a one-line :class:`ConfigError` naming
    ``control_period`` (checked before the duration, which is counted in periods)."""
    T = positive_number("control_period", control_period)
    if T > MAX_CONTROL_PERIOD * (1 + 1e-12):
        raise ConfigError(f"control_period: expected at most {MAX_CONTROL_PERIOD:g} s (the "
                          f"ceiling), got {control_period!r} s")
    if T < MIN_CONTROL_PERIOD * (1 - 1e-12):
        raise ConfigError(f"control_period: expected at least {MIN_CONTROL_PERIOD:g} s (the "
                          f"floor), got {control_period!r} s")
    return T


def check_duration(duration: float, control_period: float) -> float:
    """``duration`` [s] as a float, finite, positive and at most :data:`MAX_PERIODS` control
    periods long; otherwise a one-line :class:`ConfigError` naming ``duration``."""
    value = positive_number("duration", duration)
    T = float(control_period)
    if not value / T <= MAX_PERIODS:               # also catches an overflow to inf
        raise ConfigError(f"duration: expected at most {MAX_PERIODS:.0e} control periods "
                          f"({MAX_PERIODS * T:g} s at T = {T:g} s; the ceiling), got "
                          f"{duration!r} s")
    return value
