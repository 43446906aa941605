"""One training run on disk: its names, its seeds, its folder and files, its stop and its progress.

A run is a method and a training seed ``S``. It writes, in its folder ``DIR``:

* ``METHOD-seedS.json`` — the controller file (linear methods) or the SB3 model's training record,
  with ``METHOD-seedS.zip`` beside it (SB3 methods);
* ``METHOD-seedS-curve.csv`` — the learning curve, rewritten whole (temp + rename) at every point,
  so that a stopped run leaves whole rows;
* ``METHOD-seedS-checkpoint.*`` — what ``--resume`` continues from, removed once the run is complete.

Seeds: run seed ``S`` has the root ``TRAIN_SEED_BASE + 1000·S``; the curve's episodes derive from
:data:`EVAL_SEED`. Neither is a suite's seed (2026), so no run trains or is judged on a suite's
episodes. Files are replaced only when the caller asked (``--force``), and then atomically
(:func:`pendulum_lqg.util.files.atomic_write`): a folder, a device or a FIFO in the way is refused.
"""

from __future__ import annotations

import signal
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from pendulum_lqg.errors import ConfigError

#: Root seed of the learning curve's 20 evaluation episodes (not a suite's seed).
EVAL_SEED, EVAL_EPISODES = 90_001, 20
#: Training env seeds: run seed S has the root TRAIN_SEED_BASE + 1000·S.
TRAIN_SEED_BASE = 500_000
#: Where runs go when no ``--out`` is given: never the committed models or the docs.
RUNS_FOLDER = Path("runs")
#: The curve's columns: the evaluation (deterministic policy, 20 fixed episodes) then the mean
#: return and length of the training episodes that ended since the previous point.
CURVE_COLUMNS = ("env_steps", "wall_seconds", "success_rate", "score_mean", "score_ci_lo",
                 "score_ci_hi", "train_return", "train_length")


def run_root(seed: int) -> int:
    """The root seed of run ``seed``'s training episodes."""
    return TRAIN_SEED_BASE + 1000 * seed


def run_name(method: str, seed: int) -> str:
    return f"{method}-seed{seed}"


def eval_suite(suite: Any) -> Any:
    """``suite`` with the curve's 20 episodes (:data:`EVAL_SEED`) instead of its own."""
    return replace(suite, seed=EVAL_SEED, episodes=EVAL_EPISODES)


def default_out(method: str, seed: int) -> Path:
    """A fresh run folder ``runs/METHOD-seedS-<UTC time>``."""
    stamp = time.strftime("%Y%m%dT%H%M%SZ", time.gmtime())
    return RUNS_FOLDER / f"{run_name(method, seed)}-{stamp}"


def versions() -> dict[str, str]:
    """The versions a run depends on (the RL libraries ``"absent"`` where not installed)."""
    from importlib import metadata

    from pendulum_lqg.scoreboard.sb3 import rl_versions

    out = {lib: metadata.version(lib) for lib in ("pendulum-lqg", "numpy", "gymnasium", "mujoco")}
    return {**out, **rl_versions()}


class Stopped(Exception):
    """A run stopped by Ctrl-C at ``steps`` env steps, its files ``wrote`` whole."""

    def __init__(self, steps: int, wrote: list[Path]) -> None:
        super().__init__(f"stopped at {steps:,} steps")
        self.steps, self.wrote = steps, wrote


class StopFlag:
    """Ctrl-C as a request: the first SIGINT sets :attr:`requested` and the training loop stops at
    its next safe point (an ARS iteration, an SB3 env step, an identification round); a second
    one interrupts at once (``KeyboardInterrupt``)."""

    def __init__(self) -> None:
        self.requested = False

    def _handle(self, signum: int, frame: Any) -> None:
        if self.requested:
            raise KeyboardInterrupt
        self.requested = True

    @contextmanager
    def installed(self) -> Iterator[StopFlag]:
        """Handle SIGINT while the block runs (in the main thread only: signals are delivered
        there; not where SIGINT is ignored, as in a shell's background job), then restore the
        previous handler."""
        import threading

        if (threading.current_thread() is not threading.main_thread()
                or signal.getsignal(signal.SIGINT) is signal.SIG_IGN):
            yield self
            return
        old = signal.signal(signal.SIGINT, self._handle)
        try:
            yield self
        finally:
            signal.signal(signal.SIGINT, old)


@dataclass
class RunContext:
    """What a method's trainer is given: the run, where it writes, how it reports and stops."""

    method: str
    seed: int
    suite: Any
    out: Path
    steps: int | None = None
    eval_every: int = 50_000
    resume: bool = False
    options: dict[str, Any] = field(default_factory=dict)
    log: Callable[[str], None] = lambda line: print(line, file=sys.stderr, flush=True)
    stop: StopFlag = field(default_factory=StopFlag)

    @property
    def name(self) -> str:
        return run_name(self.method, self.seed)

    def path(self, suffix: str) -> Path:
        """``DIR/METHOD-seedS<suffix>`` (``.json``, ``-curve.csv``, ``-checkpoint.json`` …)."""
        return self.out / f"{self.name}{suffix}"


def check_out_folder(out: Path, name: str, *, force: bool, resume: bool,
                     checkpoint: str) -> None:
    """The run folder ``out`` checked before any training: a folder (or a new path), its run files
    regular files or absent; existing run files only with ``--force`` or ``--resume``, and
    ``--resume`` only where a checkpoint ``out/NAME<checkpoint>`` exists."""
    from pendulum_lqg.util.files import file_kind, regular_target

    if out.exists() and not out.is_dir():
        import os

        raise ConfigError(f"--out: {out} is {file_kind(os.stat(out).st_mode)}; expected a folder "
                          "or a new path for the run (it is left as it is)")
    files = [out / f"{name}{s}" for s in (".json", ".zip", "-curve.csv", checkpoint)]
    for path in files:
        regular_target("--out", path)
    if resume:
        if not (out / f"{name}{checkpoint}").is_file():
            raise ConfigError(f"--resume: {out} holds no checkpoint of {name} "
                              f"({name}{checkpoint}); start the run without --resume")
        return
    existing = [p.name for p in files if p.exists()]
    if existing and not force:
        raise ConfigError(f"--out: {out} already holds {', '.join(existing)}; give --force to "
                          "replace the run, --resume to continue it, or another --out")


def write_text(path: Path, text: str) -> None:
    """``text`` to ``path``, whole or not at all (temp + rename; only a regular file replaced)."""
    from pendulum_lqg.util.files import atomic_write

    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(path, text)


def write_json(path: Path, doc: dict[str, Any]) -> None:
    import json

    write_text(path, json.dumps(doc, indent=1, allow_nan=False) + "\n")


def progress_line(name: str, point: dict[str, Any]) -> str:
    """``NAME: 100,000 steps, success 0.85, score 0.812`` (a missing score shown as –)."""
    score = point.get("score_mean")
    shown = "–" if score is None else f"{score:.3f}"
    return (f"{name}: {point['env_steps']:,} steps, success {point['success_rate']:.2f}, "
            f"score {shown}")


def output_path(where: str, path: str | Path, *, force: bool, what: str) -> Path:
    """An output file checked before any work (:func:`pendulum_lqg.util.files.output_file`: a new
    path or a regular file, never a device, a FIFO, a folder or a symlink loop), and an existing
    one only with ``--force``."""
    from pendulum_lqg.util.files import output_file

    target = output_file(where, path, what=what)
    if target.exists() and not force:
        raise ConfigError(f"{where}: {path} exists; give --force to replace it")
    return target
