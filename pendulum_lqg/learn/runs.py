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

import os
import signal
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from pendulum_lqg.boundary.schemas import CURVE_COLUMNS as SCHEMA_CURVE_COLUMNS
from pendulum_lqg.errors import ConfigError

#: Root seed of the learning curve's 20 evaluation episodes (not a suite's seed).
EVAL_SEED, EVAL_EPISODES = 90_001, 20
#: Training env seeds: run seed S has the root TRAIN_SEED_BASE + 1000·S.
TRAIN_SEED_BASE = 500_000
#: Where runs go when no ``--out`` is given: never the committed models or the docs.
RUNS_FOLDER = Path("runs")
#: The curve's columns: the evaluation (deterministic policy, 20 fixed episodes) then the mean
#: return and length of the training episodes that ended since the previous point (the schema:
#: :func:`pendulum_lqg.boundary.schemas.curve_file`).
CURVE_COLUMNS = SCHEMA_CURVE_COLUMNS


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
    #: the run folder's lock (:class:`RunFolder`), held from :func:`~pendulum_lqg.learn.train.prepare`
    #: until the run ends
    folder: RunFolder | None = None
    #: ``--resume``: the checkpoint, read and checked at the boundary before any work
    checkpoint: dict[str, Any] | None = None

    def resumed(self) -> dict[str, Any]:
        """The checkpoint ``--resume`` continues, as :mod:`pendulum_lqg.learn.checkpoint` read it
        (:func:`pendulum_lqg.learn.train.run` reads it before any training)."""
        if self.checkpoint is None:
            raise ConfigError("--resume: the checkpoint is read by pendulum_lqg.learn.train.run; "
                              "train the run through it")
        return self.checkpoint

    @property
    def name(self) -> str:
        return run_name(self.method, self.seed)

    def path(self, suffix: str) -> Path:
        """``DIR/METHOD-seedS<suffix>`` (``.json``, ``-curve.csv``, ``-checkpoint.json`` …)."""
        return self.out / f"{self.name}{suffix}"


class RunFolder:
    """The run folder held by one run: the lock on its run files (``DIR/.METHOD-seedS.lock``, a
    :class:`~pendulum_lqg.util.files.FileLock`, ``bench``'s lock), taken before any training and
    held until the run ends however it ends, so two runs of one method and seed never write into
    one folder: a second start, a ``--force`` or a second ``--resume`` is refused in one line,
    ``--out: DIR (NAME) is being written by another run (pid N)``. Taking it is also the proof that
    the folder can be written: a folder that cannot be is refused before any work."""

    def __init__(self, out: Path, name: str) -> None:
        from pendulum_lqg.util.files import FileLock

        self.out, self.name = out, name
        self.made: list[Path] = []                 # the folders this run created, deepest first
        self.lock = FileLock(out / f".{name}.lock", where=f"--out: {out} ({name})")

    def open(self) -> None:
        """Create the folder (with its parents) and take the lock; one line if either fails."""
        missing = [p for p in (self.out, *self.out.parents) if not p.exists()]
        try:
            self.out.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise ConfigError(f"--out: cannot create the folder {self.out}: "
                              f"{exc.strerror or exc}") from None
        self.made = missing
        try:
            self.lock.acquire()
        except OSError as exc:
            self.abandon()
            raise ConfigError(f"--out: cannot write into {self.out} ({exc.strerror or exc}); "
                              "give --out a folder this user can write") from None
        except ConfigError:
            self.abandon()
            raise

    def release(self) -> None:
        self.lock.release()

    def abandon(self) -> None:
        """Release the lock and remove the folders this run created if they are still empty (a
        run refused after its folder was made leaves nothing behind)."""
        self.lock.release()
        for folder in self.made:
            try:
                folder.rmdir()
            except OSError:
                break
        self.made = []


def out_folder(out: str | os.PathLike[str]) -> Path:
    """``--out`` as given, checked before it becomes a :class:`~pathlib.Path` (``Path("")`` is
    the current folder): an empty or blank text is refused, never a run written into the current
    folder or into a folder named by blanks."""
    text = os.fspath(out)
    if not text.strip():
        raise ConfigError(f"--out: expected a folder for the run, got {text!r}")
    return Path(text)


def check_out_folder(out: Path, name: str, *, force: bool, resume: bool,
                     checkpoint: str) -> RunFolder:
    """The run folder ``out`` checked before any training, and held: a folder (or a new path), its
    run files regular files or absent; existing run files only with ``--force`` or ``--resume``,
    and ``--resume`` only where a checkpoint ``out/NAME<checkpoint>`` exists. The folder is made
    and locked (:class:`RunFolder`) before the files are looked at, so what is checked is what the
    run finds; the caller releases it (:func:`pendulum_lqg.learn.train.run` does)."""
    from pendulum_lqg.util.files import file_kind, regular_target

    if out.exists() and not out.is_dir():
        raise ConfigError(f"--out: {out} is {file_kind(os.stat(out).st_mode)}; expected a folder "
                          "or a new path for the run (it is left as it is)")
    files = run_files(out, name, checkpoint)
    for path in files:
        regular_target("--out", path)
    folder = RunFolder(out, name)
    folder.open()
    try:
        if resume:
            if not (out / f"{name}{checkpoint}").is_file():
                raise ConfigError(f"--resume: {out} holds no checkpoint of {name} "
                                  f"({name}{checkpoint}); start the run without --resume")
            return folder
        existing = [p.name for p in files if p.is_symlink() or p.exists()]
        if existing and not force:
            raise ConfigError(f"--out: {out} already holds {', '.join(existing)}; give --force to "
                              "replace the run, --resume to continue it, or another --out")
    except BaseException:
        folder.abandon()
        raise
    return folder


def run_files(out: Path, name: str, checkpoint: str = "-checkpoint.json") -> list[Path]:
    """The files of run ``name`` in ``out``: controller or record, model, curve, checkpoint."""
    return [out / f"{name}{s}" for s in (".json", ".zip", "-curve.csv", checkpoint)]


def clear_run(out: Path, name: str) -> None:
    """Remove run ``name``'s files from ``out`` (a run started again with ``--force``), its
    checkpoints too, so that nothing of the old run is mixed into the new one and a later
    ``--resume`` can only continue the new one. A symbolic link is removed, never its target
    (:func:`pendulum_lqg.util.files.remove_entry`, ``bench --force``'s rule)."""
    from pendulum_lqg.util.files import remove_entry

    for path in [*run_files(out, name), *sorted(out.glob(f"{name}-checkpoint*"))]:
        if path.is_symlink() or path.is_file():
            remove_entry(path)


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
