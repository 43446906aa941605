"""Results on disk: written incrementally and atomically, resumable, never silently overwritten.

Layout of a results folder::

    spec.json        the resolved experiment (with its fingerprint) and the versions of
                     pendulum_lqg and the libraries that compute the numbers; its presence marks
                     the folder as ours (``--force`` empties no other folder)
    units/KEY.csv    one file per finished work unit (written to a temp file, then renamed)
    units/KEY.json   the unit's check record: fingerprint, its plugin's source digest,
                     configuration, episode range, row count, columns and the SHA-256 of the
                     CSV's bytes — a resume trusts a unit only if all of them match and the CSV's
                     own ``config``, ``episode`` and ``seed`` columns are the unit's (otherwise it
                     is recomputed, or refused)
    episodes.csv     every episode row with its configuration (assembled at the end); first
                     column ``schema_version``
    summary.json     aggregates per configuration (success rate + Wilson CI, mean ± SE), with
                     ``schema_version`` (docs/results.md)
    summary.md       the same as a Markdown table
    meta.json        timestamps and machine facts (kept apart so the data files are byte-identical
                     for the same seed)
    .lock            present while a run writes into the folder (an flock on it, which the system
                     drops when the run ends however it ends; :class:`~pendulum_lqg.util.files.FileLock`)
"""

from __future__ import annotations

import csv
import functools
import hashlib
import json
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pendulum_lqg.bench.experiments import check_name
from pendulum_lqg.bench.sources import MJCF, LTISource, PlantSource
from pendulum_lqg.boundary import read_bytes
from pendulum_lqg.boundary.schemas import unit_record
from pendulum_lqg.core.metrics import summarize, summary_metrics
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.util.files import FileLock, atomic_write, read_csv, remove_entry, rows_to_csv
from pendulum_lqg.version import SCHEMA_VERSION, versions

if TYPE_CHECKING:
    from pendulum_lqg.bench.experiments import Configuration, ExperimentSpec, WorkUnit

__all__ = ["ResultsDir", "atomic_write", "check_name", "markdown_table", "read_csv",
           "rows_to_csv", "summarize_configs", "unit_columns", "versions"]

def _protected(path: Path) -> str | None:
    """Why ``--force`` must never empty ``path`` (``None`` if it may): the current folder or one
    of its parents, the home folder, the filesystem root."""
    real = path.resolve()
    cwd = Path.cwd().resolve()
    if real == cwd or real in cwd.parents:
        return "it is the current folder or one of its parents"
    if real == Path.home().resolve():
        return "it is the home folder"
    if real == Path(real.anchor):
        return "it is the filesystem root"
    return None


class ResultsDir:
    """A results folder for one experiment; see the module docstring for its layout."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.units_dir = self.path / "units"
        self.lock = self.path / ".lock"
        self._lock = FileLock(self.lock, where=f"out: {self.path}")
        self._spec: ExperimentSpec | None = None    # set by prepare(); its fingerprints enter
                                                    # the check records

    def prepare(self, spec: ExperimentSpec, *, force: bool = False, resume: bool = False,
                allow_version_change: bool = False) -> None:
        """Create or reopen the folder; refuse to clobber results unless ``force``.

        ``force`` empties the folder only if it is ours (it holds our ``spec.json``, or nothing)
        and is not the current folder, a parent of it, the home folder or the root. ``resume``
        refuses a folder written for another experiment or by other versions of pendulum_lqg or
        its numeric libraries (unless ``allow_version_change``).
        """
        if force and resume:
            raise ConfigError("--force and --resume: choose one (overwrite or complete)")
        check_name(spec.name)
        if self.path.exists() and not self.path.is_dir():
            raise ConfigError(f"out: {self.path} is a file; expected a folder path (it is created "
                              "if missing)")
        has_results = self.path.exists() and any(c.name != ".lock" for c in self.path.iterdir())
        if has_results and not (force or resume):
            raise ConfigError(f"out: {self.path} already holds results; pass --force to overwrite "
                              "it or --resume to complete an interrupted sweep")
        spec_file = self.path / "spec.json"
        old = self._read_spec() if has_results else None
        if has_results and force:
            why = _protected(self.path) or (None if old is not None else
                                            "it holds no pendulum_lqg spec.json")
            if why is not None:
                raise ConfigError(f"--force: refusing to empty {self.path}: {why}; give --out a "
                                  "results folder of its own")
        try:
            self.path.mkdir(parents=True, exist_ok=True)
            self._acquire()
        except PermissionError as exc:
            raise ConfigError(f"out: cannot write into {self.path} ({exc.strerror})") from None
        record: dict[str, Any] = {"fingerprint": spec.fingerprint(),
                                  "definition": spec.definition_fingerprint(), "name": spec.name,
                                  "spec": spec.source, "plugin_sources": spec.plugin_sources,
                                  "versions": versions()}
        if resume and old is not None:
            problem = None
            # a folder written before plugin sources were fingerprinted has no "definition"
            if old.get("definition", old.get("fingerprint")) != record["definition"]:
                problem = (f"holds a different experiment ({old.get('name')}, fingerprint "
                           f"{old.get('fingerprint')}); use the same file, model, --episodes and "
                           "--seed, or --force")
            elif old.get("versions", {}) != record["versions"] and not allow_version_change:
                problem = (f"was written by {_describe(old.get('versions', {}))}, this is "
                           f"{_describe(record['versions'])}; finish it with the same versions, "
                           "or pass --allow-version-change to mix them, or --force")
            if problem is not None:
                self.release()
                raise ConfigError(f"--resume: {self.path} {problem}")
        if force:
            for child in self.path.iterdir():
                if child == self.lock:
                    continue
                remove_entry(child)           # a link is removed, never its target
        self.units_dir.mkdir(exist_ok=True)
        self._spec = spec
        atomic_write(spec_file, json.dumps(record, indent=2, sort_keys=True, default=str) + "\n")

    def _read_spec(self) -> dict[str, Any] | None:
        """Our ``spec.json`` as a dict, or ``None`` if missing or not ours."""
        try:
            data = json.loads((self.path / "spec.json").read_text(encoding="utf-8"))
        except (OSError, ValueError, RecursionError):
            return None
        return data if isinstance(data, dict) and "fingerprint" in data else None

    def _acquire(self) -> None:
        self._lock.acquire()

    def release(self) -> None:
        self._lock.release()

    def holds_complete(self, spec: ExperimentSpec) -> bool:
        """The folder holds this very experiment's finished results (same fingerprint, every work
        unit verified and the summary written)."""
        old = self._read_spec() if (self.path / "summary.json").is_file() else None
        return (old is not None and old.get("fingerprint") == spec.fingerprint()
                and {u.key for u in spec.units()} <= self.verified(spec))

    def done(self) -> set[str]:
        """Keys of the unit files present (unverified; see :meth:`verified`)."""
        if not self.units_dir.exists():
            return set()
        return {p.stem for p in self.units_dir.glob("*.csv")}

    def verified(self, spec: ExperimentSpec,
                 on_mismatch: Callable[[str, str], None] | None = None) -> set[str]:
        """Keys of the units whose files match their check record and ``spec`` (fingerprint,
        configuration, episode range, row count, columns, SHA-256). Each unit on disk that does
        not is reported to ``on_mismatch(key, reason)`` and left out (so it is recomputed)."""
        present = self.done()
        ok = set()
        for unit in spec.units():
            if unit.key not in present:
                continue
            reason = self._check_unit(unit, spec)
            if reason is None:
                ok.add(unit.key)
            elif on_mismatch is not None:
                on_mismatch(unit.key, reason)
        return ok

    def _check_unit(self, unit: WorkUnit, spec: ExperimentSpec) -> str | None:
        """Why the files of ``unit`` cannot be trusted, or ``None`` if they can."""
        csv_file = self.units_dir / f"{unit.key}.csv"
        record_file = self.units_dir / f"{unit.key}.json"
        if not record_file.exists():
            return "no check record (the run stopped between writing its CSV and its record)"
        try:
            data = read_bytes(csv_file, where="unit")
        except ConfigError as exc:
            return f"unreadable ({str(exc).removeprefix(f'unit: {csv_file}').lstrip(': ')})"
        try:
            record = unit_record(record_file)
        except ConfigError as exc:
            return f"check record corrupt ({str(exc).removeprefix(f'unit: {record_file}').lstrip(': ')})"
        actual = _unit_record(unit, spec, data)
        expected = {**actual, "rows": unit.stop - unit.start, "columns": unit_columns(unit)}
        for field in ("rows", "columns"):
            if actual[field] != expected[field]:
                return f"{field}: found {actual[field]!r}, expected {expected[field]!r}"
        if record["sha256"] != actual["sha256"]:
            return "its CSV was changed after it was written (SHA-256 differs)"
        if record.get("plugin_source") != expected.get("plugin_source"):
            return (f"written by another version of the plugin {unit.config.plugin} (its source "
                    "changed since)")
        for field in ("fingerprint", "config", "start", "stop", "rows", "columns"):
            if record[field] != expected[field]:
                return f"{field}: recorded {record[field]!r}, expected {expected[field]!r}"
        return _content_problem(unit, data)

    def write_unit(self, unit: WorkUnit, rows: list[dict[str, Any]]) -> None:
        """Write a unit's rows and then its check record (a unit without one is not trusted)."""
        if self._spec is None:
            raise ConfigError("write_unit: prepare() the results folder first")
        text = rows_to_csv(rows)
        atomic_write(self.units_dir / f"{unit.key}.csv", text)
        record = _unit_record(unit, self._spec, text.encode("utf-8"))
        atomic_write(self.units_dir / f"{unit.key}.json", json.dumps(record, sort_keys=True) + "\n")

    def collect(self, spec: ExperimentSpec) -> list[dict[str, Any]]:
        rows: list[dict[str, Any]] = []
        for unit in spec.units():
            f = self.units_dir / f"{unit.key}.csv"
            if f.exists():
                rows.extend(read_csv(f))
        return rows

    def finalize(self, spec: ExperimentSpec, meta: dict[str, Any]) -> dict[str, Any]:
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


def unit_columns(unit: WorkUnit) -> list[str]:
    """The columns of a unit's CSV: ``config``, the grid keys, then the episode fields."""
    return ["config", *unit.config.values, *config_fields(unit.config)]


def config_fields(cfg: Configuration) -> tuple[str, ...]:
    """The episode fields of a configuration: the cart-pole's, or an LTI plant's (named after
    its states)."""
    return cfg.source.fields(cfg)


def _unit_record(unit: WorkUnit, spec: ExperimentSpec, data: bytes) -> dict[str, Any]:
    """The check record of ``unit`` whose CSV is ``data``: the experiment's definition
    fingerprint, the unit's plugin source digest, its configuration and range, and the CSV's
    SHA-256, row count and header."""
    text = data.decode("utf-8", errors="replace")
    lines = text.splitlines()
    header = next(csv.reader(lines[:1]), []) if lines else []
    record = {"fingerprint": spec.definition_fingerprint(), "config": unit.config.index,
              "start": unit.start, "stop": unit.stop, "sha256": hashlib.sha256(data).hexdigest(),
              "rows": max(len(lines) - 1, 0), "columns": header if lines else []}
    source = unit.config.plugin_source
    if source is not None:                     # only a plug-in's units carry its source digest
        record["plugin_source"] = source
    return record


def _content_problem(unit: WorkUnit, data: bytes) -> str | None:
    """Whether the CSV's own ``config``, ``episode`` and ``seed`` columns are ``unit``'s: a unit
    file swapped or edited with a recomputed SHA-256 in its record is caught here."""
    from pendulum_lqg.core.seeding import episode_seeds

    rows = list(csv.reader(data.decode("utf-8", errors="replace").splitlines()))
    header, body = rows[0], rows[1:]
    episodes = list(range(unit.start, unit.stop))
    wanted = {"config": [str(unit.config.index)] * len(episodes),
              "episode": [str(e) for e in episodes],
              "seed": [str(s) for s in episode_seeds(unit.seed, episodes)]}
    for column, values in wanted.items():
        i = header.index(column)
        found = [r[i] if i < len(r) else "" for r in body]
        if found != values:
            k = next(j for j, (a, b) in enumerate(zip(found, values, strict=True)) if a != b)
            return (f"its CSV holds other episodes: row {k + 1} has {column} {found[k]!r}, "
                    f"expected {values[k]!r}")
    return None


def _describe(v: dict[str, str]) -> str:
    return ", ".join(f"{k} {v[k]}" for k in sorted(v)) or "unknown versions"


def summarize_configs(spec: ExperimentSpec, rows: list[dict[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {"schema_version": SCHEMA_VERSION, "experiment": spec.name,
                              "seed": spec.seed,
                              "episodes_per_config": spec.episodes, "configurations": []}
    for cfg in spec.configurations:
        mine = [r for r in rows if r["config"] == cfg.index]
        entry = {"index": cfg.index, "values": cfg.values, "label": cfg.label,
                 "summary": summarize(mine, summary_metrics(config_fields(cfg))) if mine else None,
                 "theory": config_theory(cfg)}
        out["configurations"].append(entry)
    return out


def config_theory(cfg: Configuration) -> dict[str, Any] | None:
    """The closed-form stationary loop of a configuration (:func:`~pendulum_lqg.policies.theory.
    policy_theory`, on the linearisation of the simulated plant: its own linear plant, or the
    exact ZOH for MuJoCo), as the summary's ``theory`` entry; ``None`` for what the theory does
    not model (plugins, delays, dropout, lags, force noise, randomised plants). Its ``episode``
    holds the expected RMS over one episode from the configuration's x₀ and x̂₀ (after its
    ``burn_in``) and the expected J, in the Monte Carlo's column names (the Markdown table shows
    it in each *theory* cell, the stationary value beside it)."""
    if cfg.plugin is not None:
        return None
    return cfg.source.theory(cfg)


def _stat_cell(stat: dict[str, float], digits: int = 3) -> str:
    mean, se = stat["mean"], stat["se"]
    if mean != mean:  # nan
        return "–"
    if se != se or se <= 1e-9 * max(abs(mean), 1e-12):   # single value, or identical episodes
        return f"{mean:.{digits}g}"
    return f"{mean:.{digits}g} ± {se:.2g}"


def _theory_cell(theory: dict[str, Any], key: str) -> str:
    """A *theory* cell: the expected RMS over the episode from its x₀ and x̂₀ (the finite-horizon
    theory, ``theory.episode``), the value the simulated RMS estimates, with the stationary value
    of the loop in parentheses; the stationary value alone where the episode theory is absent."""
    if key not in theory:
        return "–"
    stationary = _stat_cell({"mean": theory[key], "se": float("nan")})
    episode = theory.get("episode") or {}
    if key not in episode:
        return stationary
    return f"{_stat_cell({'mean': episode[key], 'se': float('nan')})} ({stationary})"


#: How the tables' caption says what a *theory* cell holds (:func:`_theory_cell`).
THEORY_CAPTION = ("each *theory* cell is the expected RMS over the episode from its x₀ and x̂₀ "
                  "(the finite-horizon theory of `summary.json`'s `theory.episode`), with the "
                  "stationary value of the loop in parentheses")


def markdown_table(spec: ExperimentSpec, summary: dict[str, Any]) -> str:
    """The summary as a Markdown table (one row per configuration)."""
    if not spec.configurations:
        return _table(MJCF, spec, summary)
    return _table(spec.configurations[0].source, spec, summary)


@functools.singledispatch
def _table(source: PlantSource, spec: ExperimentSpec, summary: dict[str, Any]) -> str:
    """The cart-pole's table; a plant given as matrices has its own (:func:`_lti_markdown_table`,
    registered below)."""
    configs = summary["configurations"]
    keys = list(spec.configurations[0].values) if spec.configurations else []
    head = [*keys, "success [95 % CI]", "J (successes)", "RMS θ [rad]", "theory", "max abs θ [rad]",
            "RMS p [m]", "theory", "RMS u [N]", "theory", "saturated", "RMS θ̂−θ [rad]", "theory",
            "RMS ṗ̂−ṗ [m/s]", "loop radius", "failures"]
    lines = [f"**{spec.name}** — {spec.episodes} episodes per configuration, seed {spec.seed}; "
             f"{THEORY_CAPTION}, both of the linearised loop with the limits off "
             "(`pendulum-lqg theory`); the loop radius is its spectral radius",
             "", "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for c in configs:
        s = c["summary"]
        if s is None:
            continue
        lo, hi = s["success_ci95"]
        fails = ", ".join(f"{k} {v}" for k, v in sorted(s["failures"].items())) or "–"
        th = c.get("theory") or {}
        cells = [str(c["values"][k]) for k in keys] + [
            f"{s['success_rate']:.1%} [{lo:.1%}, {hi:.1%}]", _stat_cell(s["cost"]),
            _stat_cell(s["rms_theta"]), _theory_cell(th, "rms_theta"), _stat_cell(s["max_abs_theta"]),
            _stat_cell(s["rms_p"]), _theory_cell(th, "rms_p"), _stat_cell(s["rms_u"]),
            _theory_cell(th, "rms_u"),
            f"{s['saturated_fraction']['mean']:.1%}", _stat_cell(s["rms_est_err_theta"]),
            _theory_cell(th, "rms_est_err_theta"), _stat_cell(s["rms_est_err_p_dot"]),
            f"{th['spectral_radius']:.4f}" if th else "–", fails]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


@_table.register(LTISource)
def _lti_markdown_table(source: LTISource, spec: ExperimentSpec, summary: dict[str, Any]) -> str:
    """The summary of an experiment on an LTI plant: per state its RMS and the theory's, per
    state the RMS estimation error and the theory's (the state names of the plant's file)."""
    cfg0 = spec.configurations[0]
    fields = config_fields(cfg0)
    states = [f.removeprefix("rms_est_err_") for f in fields if f.startswith("rms_est_err_")]
    inputs = [f.removeprefix("rms_") for f in fields if f.startswith("rms_")    # u, or m names
              and not f.startswith("rms_est_err_") and f.removeprefix("rms_") not in states]
    keys = list(cfg0.values)
    head = [*keys, "success [95 % CI]", "J (successes)",
            *(h for s in states for h in (f"RMS {s}", "theory")),
            *(h for u in inputs for h in (f"RMS {u}", "theory")), "saturated",
            *(h for s in states for h in (f"RMS error {s}", "theory")), "loop radius",
            "failures"]
    lines = [f"**{spec.name}** — LTI plant `{Path(source.path).name}`, {spec.episodes} "
             f"episodes per configuration, seed {spec.seed}; {THEORY_CAPTION} "
             "(`pendulum-lqg theory --lti`); the loop radius is its spectral radius", "",
             "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for c in summary["configurations"]:
        s = c["summary"]
        if s is None:
            continue
        lo, hi = s["success_ci95"]
        th = c.get("theory") or {}
        cells = [str(c["values"][k]) for k in keys] + [
            f"{s['success_rate']:.1%} [{lo:.1%}, {hi:.1%}]", _stat_cell(s["cost"])]
        for prefix in ("rms_", None, "rms_est_err_"):
            if prefix is None:
                for u in inputs:
                    cells += [_stat_cell(s[f"rms_{u}"]), _theory_cell(th, f"rms_{u}")]
                cells.append(f"{s['saturated_fraction']['mean']:.1%}")
                continue
            for name in states:
                cells += [_stat_cell(s[prefix + name]), _theory_cell(th, prefix + name)]
        cells += [f"{th['spectral_radius']:.4f}" if th else "–",
                  ", ".join(f"{k} {v}" for k, v in sorted(s["failures"].items())) or "–"]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"
