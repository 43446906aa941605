"""Reading a recording back: its entities and columns, and a check that it is complete."""

from __future__ import annotations

import collections
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.record.writer import TIMELINE


@dataclass(frozen=True)
class RecordingContents:
    """A recording read back from a ``.rrd`` file with Rerun's own reader (:func:`read_recording`).

    Attributes
    ----------
    application_ids : application id of each recording store in the file
    recording_ids : recording id of each recording store
    blueprints : number of blueprint stores in the file
    entity_paths : every entity path with data, sorted
    rows : temporal rows per entity path (summed over chunks)
    static : entity paths with static data
    timelines : names of the timelines seen
    """

    application_ids: list[str]
    recording_ids: list[str]
    blueprints: int
    entity_paths: list[str]
    rows: dict[str, int]
    static: set[str]
    timelines: set[str]
    _path: Path = field(repr=False, default=Path())


@dataclass(frozen=True)
class VerifyResult:
    """Outcome of ``rerun rrd verify``: ``ok`` iff the command exited with 0; its output."""

    ok: bool
    returncode: int
    output: str


# ---- reading back and verifying -------------------------------------------------------------
def read_recording(path: str | Path) -> RecordingContents:
    """Read a ``.rrd`` file back with ``rerun.chunk.RrdReader``: stores, entities, row counts.

    Rows are counted per entity over the temporal chunks (a batch may span several chunks);
    static chunks are listed in ``static``.
    """
    from rerun.chunk import RrdReader

    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"path: no recording at {path}")
    reader = RrdReader(str(path))
    recs = reader.recordings()
    rows: collections.Counter[str] = collections.Counter()
    static: set[str] = set()
    timelines: set[str] = set()
    entities: set[str] = set()
    for chunk in reader.stream():
        entities.add(chunk.entity_path)
        if chunk.is_static:
            static.add(chunk.entity_path)
        else:
            rows[chunk.entity_path] += int(chunk.num_rows)
            timelines.update(chunk.timeline_names)
    return RecordingContents(
        application_ids=[r.application_id for r in recs], recording_ids=[r.recording_id for r in recs],
        blueprints=len(reader.blueprints()), entity_paths=sorted(entities), rows=dict(rows),
        static=static, timelines=timelines, _path=path)


def read_column(path: str | Path, entity: str, component: str = "Scalars:scalars",
                ) -> tuple[np.ndarray, np.ndarray]:
    """Times [s] (M,) and values of one component of one entity, read back from a ``.rrd``.

    Values come back as an (M, k) float array for list components (``Scalars`` with k series);
    rows are sorted by time. Text components come back as an object array of strings.
    """
    from rerun.chunk import RrdReader

    times: list[np.ndarray] = []
    values: list[Any] = []
    for chunk in RrdReader(str(path)).stream():
        if chunk.entity_path != entity:
            continue
        rb = chunk.to_record_batch()
        names = rb.schema.names
        col = next((n for n in names if n == component or n.endswith(":" + component)), None)
        if col is None:
            continue
        vals = rb.column(col).to_pylist()
        if TIMELINE in names:
            t = rb.column(TIMELINE).cast("int64").to_numpy(zero_copy_only=False) * 1e-9
        else:
            t = np.full(len(vals), np.nan)
        times.append(np.asarray(t, dtype=float))
        values.extend(vals)
    if not times:
        raise ConfigError(f"entity: no component {component!r} for {entity!r} in {path}")
    t_all = np.concatenate(times)
    order = np.argsort(t_all, kind="stable")
    first = next((v for v in values if v is not None), None)
    if isinstance(first, list) and first and not isinstance(first[0], str):
        arr = np.array([v for v in values], dtype=float)
    else:
        arr = np.array([v[0] if isinstance(v, list) and len(v) == 1 else v for v in values],
                       dtype=object)
    return t_all[order], arr[order]


def rerun_executable() -> Path:
    """The ``rerun`` command installed with rerun-sdk (next to the running interpreter)."""
    exe = Path(sys.executable).parent / ("rerun.exe" if sys.platform == "win32" else "rerun")
    if not exe.is_file():
        raise ConfigError(f"rerun: the rerun CLI is not installed next to {sys.executable}")
    return exe


def verify_recording(path: str | Path, *, timeout: float = 120.0) -> VerifyResult:
    """Run ``rerun rrd verify PATH`` (Rerun's own consistency check of a recording file)."""
    proc = subprocess.run([str(rerun_executable()), "rrd", "verify", str(path)],
                          capture_output=True, text=True, timeout=timeout, check=False)
    return VerifyResult(ok=proc.returncode == 0, returncode=proc.returncode,
                        output=(proc.stdout + proc.stderr).strip())
