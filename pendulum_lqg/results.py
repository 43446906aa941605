"""Results on disk: written incrementally and atomically, resumable, never silently overwritten.

Layout of a results folder::

    spec.json        the resolved experiment (with its fingerprint)
    units/KEY.csv    one file per finished work unit (written to a temp file, then renamed)
    episodes.csv     every episode row with its configuration (assembled at the end); first
                     column ``schema_version``
    summary.json     aggregates per configuration (success rate + Wilson CI, mean ± SE), with
                     ``schema_version`` (README "Results schema")
    summary.md       the same as a Markdown table
    meta.json        timestamps and machine facts (kept apart so the data files are byte-identical
                     for the same seed)
    .lock            present while a run writes into the folder
"""

from __future__ import annotations

import csv
import io
import json
import os
import shutil
import time
from pathlib import Path

from pendulum_lqg import SCHEMA_VERSION
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.experiments import ExperimentSpec, WorkUnit
from pendulum_lqg.metrics import summarize


def atomic_write(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` via a temporary file and ``os.replace`` (never half-written)."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    with open(tmp, "w", encoding="utf-8", newline="") as fh:
        fh.write(text)
        fh.flush()
        os.fsync(fh.fileno())
    os.replace(tmp, path)


def _cell(v: object) -> str:
    if isinstance(v, float):
        return repr(v)
    return str(v)


def rows_to_csv(rows: list[dict[str, object]]) -> str:
    if not rows:
        return ""
    buf = io.StringIO()
    fields = list(rows[0])
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(fields)
    for r in rows:
        w.writerow([_cell(r.get(f, "")) for f in fields])
    return buf.getvalue()


def _parse(v: str) -> object:
    if v in ("True", "False"):
        return v == "True"
    try:
        return int(v)
    except ValueError:
        pass
    try:
        return float(v)
    except ValueError:
        return v


def read_csv(path: Path) -> list[dict[str, object]]:
    with open(path, newline="", encoding="utf-8") as fh:
        return [{k: _parse(v) for k, v in row.items()} for row in csv.DictReader(fh)]


class ResultsDir:
    """A results folder for one experiment; see the module docstring for its layout."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.units_dir = self.path / "units"
        self.lock = self.path / ".lock"
        self._locked = False

    def prepare(self, spec: ExperimentSpec, *, force: bool = False, resume: bool = False) -> None:
        """Create or reopen the folder; refuse to clobber results unless ``force``."""
        if force and resume:
            raise ConfigError("--force and --resume: choose one (overwrite or complete)")
        has_results = self.path.exists() and any(self.path.iterdir())
        if has_results and not (force or resume):
            raise ConfigError(f"out: {self.path} already holds results; pass --force to overwrite "
                              "it or --resume to complete an interrupted sweep")
        self.path.mkdir(parents=True, exist_ok=True)
        self._acquire()
        spec_file = self.path / "spec.json"
        record = {"fingerprint": spec.fingerprint(), "name": spec.name, "spec": spec.source}
        if resume and spec_file.exists():
            old = json.loads(spec_file.read_text())
            if old.get("fingerprint") != record["fingerprint"]:
                self.release()
                raise ConfigError(f"--resume: {self.path} holds a different experiment "
                                  f"({old.get('name')}, fingerprint {old.get('fingerprint')}); "
                                  "use the same file, --episodes and --seed, or --force")
        if force:
            for child in self.path.iterdir():
                if child == self.lock:
                    continue
                shutil.rmtree(child) if child.is_dir() else child.unlink()
        self.units_dir.mkdir(exist_ok=True)
        atomic_write(spec_file, json.dumps(record, indent=2, sort_keys=True, default=str) + "\n")

    def _acquire(self) -> None:
        try:
            fd = os.open(self.lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
        except FileExistsError:
            pid = self.lock.read_text().strip() if self.lock.exists() else "?"
            alive = pid.isdigit() and _pid_alive(int(pid))
            if alive:
                raise ConfigError(f"out: {self.path} is being written by another run (pid {pid})"
                                  ) from None
            self.lock.unlink(missing_ok=True)   # stale lock of a killed run
            fd = os.open(self.lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
        os.write(fd, str(os.getpid()).encode())
        os.close(fd)
        self._locked = True

    def release(self) -> None:
        if self._locked:
            self.lock.unlink(missing_ok=True)
            self._locked = False

    def holds_complete(self, spec: ExperimentSpec) -> bool:
        """The folder holds this very experiment's finished results (same fingerprint, every work
        unit and the summary written)."""
        spec_file = self.path / "spec.json"
        if not (spec_file.is_file() and (self.path / "summary.json").is_file()):
            return False
        try:
            fingerprint = json.loads(spec_file.read_text()).get("fingerprint")
        except (OSError, ValueError):
            return False
        return fingerprint == spec.fingerprint() and {u.key for u in spec.units()} <= self.done()

    def done(self) -> set[str]:
        if not self.units_dir.exists():
            return set()
        return {p.stem for p in self.units_dir.glob("*.csv")}

    def write_unit(self, unit: WorkUnit, rows: list[dict[str, object]]) -> None:
        atomic_write(self.units_dir / f"{unit.key}.csv", rows_to_csv(rows))

    def collect(self, spec: ExperimentSpec) -> list[dict[str, object]]:
        rows: list[dict[str, object]] = []
        for unit in spec.units():
            f = self.units_dir / f"{unit.key}.csv"
            if f.exists():
                rows.extend(read_csv(f))
        return rows

    def finalize(self, spec: ExperimentSpec, meta: dict[str, object]) -> dict[str, object]:
        """Assemble episodes.csv, summary.json, summary.md (and meta.json); return the summary."""
        rows = self.collect(spec)
        atomic_write(self.path / "episodes.csv",
                     rows_to_csv([{"schema_version": SCHEMA_VERSION, **r} for r in rows]))
        summary = summarize_configs(spec, rows)
        atomic_write(self.path / "summary.json",
                     json.dumps(summary, indent=2, sort_keys=True, default=str) + "\n")
        atomic_write(self.path / "summary.md", markdown_table(spec, summary))
        meta = {**meta, "finished": time.strftime("%Y-%m-%dT%H:%M:%S%z")}
        atomic_write(self.path / "meta.json", json.dumps(meta, indent=2, sort_keys=True) + "\n")
        return summary


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def summarize_configs(spec: ExperimentSpec, rows: list[dict[str, object]]) -> dict[str, object]:
    out: dict[str, object] = {"schema_version": SCHEMA_VERSION, "experiment": spec.name,
                              "seed": spec.seed,
                              "episodes_per_config": spec.episodes, "configurations": []}
    for cfg in spec.configurations:
        mine = [r for r in rows if r["config"] == cfg.index]
        entry = {"index": cfg.index, "values": cfg.values, "label": cfg.label,
                 "summary": summarize(mine) if mine else None}
        out["configurations"].append(entry)  # type: ignore[union-attr]
    return out


def _fmt(stat: dict[str, float], digits: int = 3) -> str:
    mean, se = stat["mean"], stat["se"]
    if mean != mean:  # nan
        return "–"
    if se != se or se <= 1e-9 * max(abs(mean), 1e-12):   # single value, or identical episodes
        return f"{mean:.{digits}g}"
    return f"{mean:.{digits}g} ± {se:.2g}"


def markdown_table(spec: ExperimentSpec, summary: dict[str, object]) -> str:
    """The summary as a Markdown table (one row per configuration)."""
    configs = summary["configurations"]  # type: ignore[index]
    keys = list(spec.configurations[0].values) if spec.configurations else []
    head = [*keys, "success [95 % CI]", "J (successes)", "RMS θ [rad]", "max abs θ [rad]",
            "RMS p [m]", "RMS u [N]", "saturated", "RMS θ̂−θ [rad]", "RMS ṗ̂−ṗ [m/s]",
            "failures"]
    lines = [f"**{spec.name}** — {spec.episodes} episodes per configuration, seed {spec.seed}",
             "", "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for c in configs:  # type: ignore[union-attr]
        s = c["summary"]
        if s is None:
            continue
        lo, hi = s["success_ci95"]
        fails = ", ".join(f"{k} {v}" for k, v in sorted(s["failures"].items())) or "–"
        cells = [str(c["values"][k]) for k in keys] + [
            f"{s['success_rate']:.1%} [{lo:.1%}, {hi:.1%}]", _fmt(s["cost"]),
            _fmt(s["rms_theta"]), _fmt(s["max_abs_theta"]), _fmt(s["rms_p"]), _fmt(s["rms_u"]),
            f"{s['saturated_fraction']['mean']:.1%}", _fmt(s["rms_est_err_theta"]),
            _fmt(s["rms_est_err_p_dot"]), fails]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"
