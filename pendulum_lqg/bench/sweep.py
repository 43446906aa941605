"""Sweeps: an experiment's work units run on an executor, each finished unit kept on disk at once.

The Python API behind ``pendulum-lqg bench``::

    from pendulum_lqg.bench.executors import LocalExecutor
    from pendulum_lqg.bench.experiments import load_spec
    from pendulum_lqg.bench.sweep import run_sweep

    result = run_sweep(load_spec("lecture"), "results/lecture", executor=LocalExecutor())
    result.summary["configurations"][0]["summary"]["success_rate"]

One driver for every executor: it prepares the results folder (lock, ``--resume``, ``--force``),
hands the pending :class:`~pendulum_lqg.bench.experiments.WorkUnit` s to the executor, writes each unit
atomically as it comes back (in whatever order), shows the progress (units done / total, ETA) and
assembles ``episodes.csv`` / ``summary.json`` at the end. A unit's rows depend only on the unit
(its configuration, seed and episode range), never on the executor or the thread count, so the
results are byte-identical for any executor (:mod:`pendulum_lqg.bench.executors`: in this process, or
Ray tasks on a cluster) on machines of one CPU model and library versions; a cluster mixing CPUs
gives each unit the last digits of the machine that ran it (docs: Concepts, reproducibility).
"""

from __future__ import annotations

import contextlib
import os
import platform
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pendulum_lqg.bench.experiments import ExperimentSpec, WorkUnit
from pendulum_lqg.bench.results import ResultsDir, versions
from pendulum_lqg.errors import ConfigError

if TYPE_CHECKING:
    from pendulum_lqg.bench.executors import Executor

Log = Callable[[str], None] | None


@dataclass(frozen=True)
class UnitFailure:
    """A work unit that kept failing on the executor (after its retries)."""

    key: str
    error: str


@dataclass
class SweepResult:
    """What :func:`run_sweep` did.

    Attributes
    ----------
    path : the results folder
    summary : ``summary.json`` as a dict (``None`` if units failed and nothing was assembled)
    units_total, units_run : units of the sweep / run by this call (the rest were already there)
    failures : units that failed on the executor; the sweep is then incomplete (``--resume`` reruns
        only them)
    """

    path: Path
    summary: dict[str, Any] | None
    units_total: int
    units_run: int
    failures: list[UnitFailure] = field(default_factory=list)

    @property
    def complete(self) -> bool:
        return not self.failures


class SweepInterrupted(KeyboardInterrupt):
    """Ctrl-C / SIGTERM during a sweep: finished units are on disk; ``done`` of ``total``."""

    def __init__(self, path: Path, done: int, total: int) -> None:
        super().__init__(f"{done}/{total} work units are saved in {path}")
        self.path, self.done, self.total = path, done, total


def run_sweep(spec: ExperimentSpec, out: str | Path | ResultsDir, *,
              executor: Executor | None = None, resume: bool = False, force: bool = False,
              progress: bool | None = None, log: Log = None,
              record: str | Path | None = None, nthread: int | None = None,
              on_mismatch: str = "recompute", allow_version_change: bool = False,
              ) -> SweepResult:
    """Run the grid experiment ``spec`` into the results folder ``out``.

    Parameters
    ----------
    spec : a grid experiment (analysis studies go through
        :func:`pendulum_lqg.analysis.studies.run_study`)
    out : the results folder (created; refused if it holds results unless ``resume``/``force``)
    executor : where units run (default :class:`~pendulum_lqg.bench.executors.LocalExecutor`)
    resume : complete an interrupted sweep (units already on disk are kept)
    force : overwrite the folder's results
    progress : a progress bar on stderr, never stdout (default: when stderr is a terminal); ``log``
        gets one line per unit instead when there is no bar
    record : folder for Rerun recordings of each configuration's telling episodes
    nthread : rollout threads of the local executor / of each task
    on_mismatch : what a resume does with a unit file that fails its check (changed, cut, from
        another configuration): ``"recompute"`` it (reported through ``log``) or ``"refuse"``
        (:class:`~pendulum_lqg.errors.ConfigError` naming the unit)
    allow_version_change : resume results written by other versions of pendulum_lqg or of its
        numeric libraries (refused by default)

    Raises
    ------
    SweepInterrupted : on Ctrl-C or SIGTERM (finished units stay; the lock is released)
    """
    from pendulum_lqg.bench.executors import LocalExecutor

    _check_sweep_options(spec, record, on_mismatch)
    folder = out if isinstance(out, ResultsDir) else ResultsDir(out)
    folder.prepare(spec, force=force, resume=resume, allow_version_change=allow_version_change)
    units = spec.units()
    try:
        done = _verified_units(folder, spec, on_mismatch, log)
        executor = executor or LocalExecutor(nthread=nthread)
        todo = [u for u in units if u.key not in done]
        started = time.strftime("%Y-%m-%dT%H:%M:%S%z")
        t0 = time.perf_counter()
        failures = _run_units(executor, todo, folder, spec, len(units), progress, log)
        if failures:
            return SweepResult(folder.path, None, len(units), len(todo) - len(failures), failures)
        meta = {"started": started, "elapsed_s": round(time.perf_counter() - t0, 3),
                "units_run_now": len(todo), "executor": executor.describe(),
                "python": platform.python_version(), "machine": platform.machine(),
                "cpus": os.cpu_count(), "versions": versions()}
        summary = folder.finalize(spec, meta)
        if record is not None:
            record_telling_episodes(spec, folder, Path(record), nthread=nthread, log=log)
    finally:
        folder.release()
    return SweepResult(folder.path, summary, len(units), len(todo))


def _check_sweep_options(spec: ExperimentSpec, record: str | Path | None,
                         on_mismatch: str) -> None:
    """A grid (not a study), a folder (or nothing) to record into, a known ``on_mismatch``."""
    if spec.study is not None:
        raise ConfigError(f"experiment: {spec.name} is a {spec.study} study; run it with "
                          "pendulum_lqg.analysis.studies.run_study")
    if record is not None and not str(record).strip():
        raise ConfigError(f"--record: expected a folder for the recordings, got {str(record)!r}")
    if record is not None and Path(record).exists() and not Path(record).is_dir():
        raise ConfigError(f"--record: {record} is a file; expected a folder for the recordings "
                          "(it is created if missing)")
    if on_mismatch not in ("recompute", "refuse"):
        raise ConfigError(f"on_mismatch: expected 'recompute' or 'refuse', got {on_mismatch!r}")


def _verified_units(folder: ResultsDir, spec: ExperimentSpec, on_mismatch: str,
                    log: Log) -> set[str]:
    """The keys of the units on disk that pass their check; one that fails is recomputed (said
    through ``log``) or, with ``on_mismatch = "refuse"``, stops the run naming it."""
    mismatched: list[tuple[str, str]] = []
    done = folder.verified(spec, lambda key, why: mismatched.append((key, why)))
    if mismatched and on_mismatch == "refuse":
        key, why = mismatched[0]
        raise ConfigError(f"--resume: unit {key} fails its check: {why} "
                          f"({len(mismatched)} unit(s) in all); drop --on-mismatch refuse to "
                          "recompute them")
    for key, why in mismatched:
        if log is not None:
            log(f"unit {key}: {why}; recomputing it")
    return done


def _run_units(executor: Executor, todo: list[WorkUnit], folder: ResultsDir,
               spec: ExperimentSpec, total: int, progress: bool | None,
               log: Log) -> list[UnitFailure]:
    """Run ``todo`` on ``executor``, writing each unit as it arrives: the units that failed.
    Ctrl-C or SIGTERM stops the run (:class:`SweepInterrupted`); the executor is closed either
    way."""
    failures: list[UnitFailure] = []
    with sigterm_as_interrupt():
        try:
            for unit, rows, error in _with_progress(executor.run(todo), todo, total,
                                                    total - len(todo), progress, log):
                if error is not None:
                    failures.append(UnitFailure(unit.key, error))
                    continue
                folder.write_unit(unit, rows)  # type: ignore[arg-type]
        except KeyboardInterrupt:
            raise SweepInterrupted(folder.path, len(folder.verified(spec)), total) from None
        finally:
            executor.close()
    return failures


@contextlib.contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """Within the block, SIGTERM raises KeyboardInterrupt (as Ctrl-C does), so a sweep stopped by
    ``kill`` keeps its finished units and releases its lock; the previous handler is restored on
    leaving. Only the main thread may install signal handlers: elsewhere nothing changes."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def _raise(signum: int, frame: object) -> None:
        raise KeyboardInterrupt

    old = signal.signal(signal.SIGTERM, _raise)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, old)


Outcome = tuple[WorkUnit, list[dict[str, Any]] | None, str | None]


def _with_progress(outcomes: Iterable[Outcome], todo: list[WorkUnit], total: int, already: int,
                   progress: bool | None, log: Log) -> Iterator[Outcome]:
    """Pass the executor's outcomes through, showing units done / total with an ETA."""
    if progress is None:
        progress = sys.stderr.isatty()
    if not progress or not todo:
        for i, (unit, rows, error) in enumerate(outcomes, start=already + 1):
            if log is not None:
                status = f"FAILED: {error}" if error is not None else ""
                log(f"[{i}/{total}] {unit.config.label} episodes {unit.start}-{unit.stop - 1}"
                    + (f" {status}" if status else ""))
            yield unit, rows, error
        return
    from pendulum_lqg.util.progress import Progress

    with Progress("work units", total, done=already, enabled=True) as bar:
        for unit, rows, error in outcomes:
            bar.advance(description=unit.config.label[:60])
            yield unit, rows, error


def recording_name(experiment: str, index: int, values: dict[str, Any]) -> str:
    """``lecture_c003_dlqr+kalman_noise_scale1.0.rrd``: the experiment, the configuration index and
    its grid values (a plugin policy by its file or module name), in characters safe for any
    file system."""
    import re

    parts = [experiment, f"c{index:03d}"]
    for key, value in values.items():
        text = str(value)
        if key == "policy" and ":" in text:           # a plugin: file stem or module, and attr
            module, _, attr = text.rpartition(":")
            text = f"{Path(module).stem}.{attr}"
        parts.append(text if key == "policy" else f"{key}{text}")
    return re.sub(r"[^A-Za-z0-9.+=-]+", "_", "_".join(parts))[:180] + ".rrd"


def record_telling_episodes(spec: ExperimentSpec, out: ResultsDir, record_dir: Path, *,
                            nthread: int | None = None, log: Log = None) -> list[Path]:
    """Rerun recordings of the worst / median / best / first failing episode of each
    configuration, re-simulated from their seeds (bit-identical to the sweep's)."""
    import dataclasses

    from pendulum_lqg.core.runner import run_episodes
    from pendulum_lqg.policies.loading import build_policy, check_source
    from pendulum_lqg.record import record_episodes, telling_episodes

    record_dir.mkdir(parents=True, exist_ok=True)
    rows = out.collect(spec)
    written = []
    for cfg in spec.configurations:
        picks = telling_episodes([r for r in rows if r["config"] == cfg.index])
        if not picks:
            continue
        scenario, dspec = cfg.build()
        nominal, simulated = cfg.plants(scenario)
        if cfg.plugin is not None:
            check_source(cfg.plugin, cfg.plugin_source)
        policy = build_policy(cfg.plugin, plant=nominal, scenario=scenario, spec=dspec)
        res = run_episodes(simulated, scenario, policy, seed=spec.seed,
                           episodes=sorted(set(picks.values())), nthread=nthread,
                           trajectory=True)
        path = record_dir / recording_name(spec.name, cfg.index, cfg.values)
        config: dict[str, Any] = {"experiment": spec.name, "configuration": cfg.values,
                                  "seed": spec.seed, "telling_episodes": picks,
                                  "scenario": scenario.to_dict(),
                                  "design": None if cfg.plugin else dataclasses.asdict(dspec)}
        record_episodes(res.trajectories or [], plant=simulated, scenario=scenario, policy=policy,
                        config=config, path=path, labels=picks)
        written.append(path)
        if log is not None:
            log(f"recorded {path} ({', '.join(f'{k}: {v}' for k, v in picks.items())})")
    return written
