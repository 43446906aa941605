"""Typed experiment specs (``experiments/*.toml``), sweeps split into work units, and results.

An experiment file describes a grid::

    name = "lecture"
    description = "…"
    episodes = 200          # per configuration
    seed = 0
    chunk = 250             # episodes per work unit (optional)

    [scenario]              # fixed Scenario fields (see pendulum_lqg.core.scenario.Scenario)
    duration = 10.0

    [noise]                 # fixed NoiseModel fields (see pendulum_lqg.core.noise.NoiseModel)
    process = "state"

    [design]                # fixed DesignSpec fields (see pendulum_lqg.policies.lqg.DesignSpec)
    R = 1.0

    model_file = "my_cartpole.xml"   # optional: your own cart-pole MJCF (default the shipped one)

    [model]                 # fixed overrides of the simulated plant (ModelOverrides)

    [grid]                  # every key a list; the sweep is their Cartesian product
    policy = ["dlqr+luenberger", "dlqr+kalman"]
    noise_scale = [0.0, 1.0]

Analysis studies (not plain grids) add ``study = "margins"`` or ``study = "roa"`` and a table of the
same name with the study's parameters; ``pendulum-lqg bench`` hands them to
:func:`pendulum_lqg.analysis.studies.run_study`.

Grid keys: ``policy`` ("controller+observer", or a user's plugin "MODULE:ATTR" /
"path/to/file.py:ATTR", relative to the experiment file's folder), ``controller``, ``observer``,
``noise_scale``,
``control_period``, ``duration``, ``theta0``, ``estimate0``, ``discretization``,
``pole_mass_scale``, ``pole_length_scale``, ``cart_mass_scale``, ``measurement_delay``,
``actuator_delay``, ``dropout``, ``actuator_tau``, and the pair ``delay`` [s] + ``delay_kind``
(``"measurement"`` or ``"actuator"``: which delay ``delay`` sets — one sweep over both kinds). Unknown
keys anywhere are an error that lists the known ones.

Sensing and actuation in ``[scenario]`` (see :class:`pendulum_lqg.core.scenario.Scenario`):
``measurement_delay``, ``actuator_delay`` [s, whole control periods], ``dropout`` (probability a
sample is lost), ``actuator_tau`` [s], ``randomize = {pole_mass_scale = [0.8, 1.2], …}``.

The sweep is a list of :class:`WorkUnit` (configuration × episode chunk): plain, JSON-serialisable and
independent, so they can run in any order or on other machines; :func:`run_unit` runs one.
"""

from __future__ import annotations

import dataclasses
import hashlib
import itertools
import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

from pendulum_lqg.bench.sources import PlantSource, choose_source
from pendulum_lqg.bench.study_params import parse_study_params
from pendulum_lqg.core.noise import NoiseModel
from pendulum_lqg.errors import ConfigError, PendulumLQGError
from pendulum_lqg.model.overrides import ModelOverrides
from pendulum_lqg.model.plant import Plant
from pendulum_lqg.names import CONTROLLERS, OBSERVERS
from pendulum_lqg.policies.spec import DesignSpec
from pendulum_lqg.problem import defaults
from pendulum_lqg.problem.declare import check
from pendulum_lqg.problem.errors import check_keys
from pendulum_lqg.problem.experiment import RUN_SETTINGS, SCENARIO_GRID_KEYS, SCENARIO_KEYS

if TYPE_CHECKING:
    from pendulum_lqg.core.scenario import Scenario

TOP_KEYS = ("name", "description", "episodes", "seed", "chunk", "model_file", "scenario", "noise",
            "design", "model", "grid", "study", "margins", "roa", "plant", "lti_file")
#: Analysis studies that are not plain grids: ``study = "NAME"`` plus an optional ``[NAME]`` table of
#: its parameters; the grid still defines the configurations the study runs on
#: (see :mod:`pendulum_lqg.analysis.studies`).
STUDIES = ("margins", "roa")
#: The grid's keys: the scenario's are declared (problem/scenario.py, ``grid=True``).
GRID_KEYS = ("policy", "controller", "observer", "noise_scale", *SCENARIO_GRID_KEYS, "theta0",
             "discretization", "pole_mass_scale", "pole_length_scale", "cart_mass_scale", "delay",
             "delay_kind")
DELAY_KINDS = ("measurement", "actuator")
NOISE_KEYS = tuple(f.name for f in dataclasses.fields(NoiseModel))
DESIGN_KEYS = tuple(f.name for f in dataclasses.fields(DesignSpec))
MODEL_KEYS = tuple(f.name for f in dataclasses.fields(ModelOverrides))


#: What an experiment name may look like: it names a folder under ``results/`` and files.
NAME_PATTERN = re.compile(r"[A-Za-z0-9][A-Za-z0-9._+-]{0,99}")


def check_name(name: object) -> str:
    """An experiment name fit to be a folder name: letters, digits and ``. _ + -``, starting with
    a letter or digit, at most 100 characters (so never ``""``, ``..``, ``a/b`` or ``/abs``)."""
    if not isinstance(name, str) or NAME_PATTERN.fullmatch(name) is None:
        raise ConfigError(f"name: expected a plain name (letters, digits and . _ + -, starting "
                          f"with a letter or digit, at most 100 characters), got {name!r}")
    return name


@dataclass(frozen=True)
class Configuration:
    """One point of the grid: everything needed to run its episodes.

    ``values`` are the grid values that define it (for tables); ``scenario``/``noise``/``design``/
    ``model`` are the resolved tables, as plain data; ``plugin`` names a user's policy (grid
    ``policy = ["my_module:make"]``), which then replaces the built-in controller and observer.
    """

    index: int
    values: dict[str, Any]
    scenario: dict[str, Any]
    noise: dict[str, Any]
    design: dict[str, Any]
    model: dict[str, Any]
    #: a user's policy plugin (``MODULE:ATTR`` or an absolute ``file.py:ATTR``) instead of the
    #: built-in ``design`` controller/observer
    plugin: str | None = None
    #: the cart-pole MJCF (absolute path) instead of the shipped ``cartpole.xml``
    model_file: str | None = None
    #: SHA-256 of the plugin's source (:func:`~pendulum_lqg.policies.loading.source_digest`), read when
    #: the configuration is made (the experiment is parsed, right after the plugin was imported);
    #: a unit refuses to run on another source, and its record keeps it
    plugin_source: str | None = None
    #: an LTI plant file (absolute path) simulated instead of the cart-pole
    #: (:mod:`pendulum_lqg.bench.lti`)
    lti_file: str | None = None

    def __post_init__(self) -> None:
        if self.plugin is not None and self.plugin_source is None:
            from pendulum_lqg.policies.loading import source_digest

            object.__setattr__(self, "plugin_source", source_digest(self.plugin))

    @property
    def label(self) -> str:
        return ", ".join(f"{k}={v}" for k, v in self.values.items()) or "default"

    @property
    def source(self) -> PlantSource:
        """Where its plant comes from: the cart-pole's MJCF or its ``lti_file``
        (:mod:`pendulum_lqg.bench.sources`)."""
        return choose_source(self.lti_file)

    def build(self) -> tuple[Scenario, DesignSpec]:
        """``(Scenario, DesignSpec)`` of this configuration (validated)."""
        return self.source.build(self)

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)

    def plants(self, scenario: Scenario | None = None) -> tuple[Plant, Plant]:
        """``(nominal, simulated)``: the model the designs believe in (the XML as it is) and the
        one simulated (with the scenario's mismatch overrides; the same object when there are
        none)."""
        return self.source.plants(self, scenario)

    def validate(self) -> None:
        """Build the configuration, check it against the (possibly overridden) model and design
        its built-in policy (once per distinct design), so that a design that fails — a Kalman
        filter on a singular ``measurement_variance``, say — stops the parse, not the sweep."""
        self.source.validate(self)


#: Names the designs give their data, and the experiment keys those come from.
DESIGN_NAMES = {"V": "noise.measurement_variance", "W": "noise.process_density"}


@dataclass(frozen=True)
class ExperimentSpec:
    """A parsed, validated experiment file."""

    name: str
    description: str
    episodes: int
    seed: int
    chunk: int
    configurations: tuple[Configuration, ...]
    source: dict[str, Any] = field(default_factory=dict)
    study: str | None = None
    study_params: dict[str, Any] = field(default_factory=dict)
    #: folder of the experiment file (relative plugin paths), not part of the fingerprint
    base_dir: Path | None = None

    def __post_init__(self) -> None:
        check_rows(self.episodes, len(self.configurations))

    @property
    def plugin_sources(self) -> dict[str, str]:
        """Each plugin of the grid and the SHA-256 of its source (:attr:`Configuration.plugin_source`)."""
        return {c.plugin: c.plugin_source for c in self.configurations
                if c.plugin is not None and c.plugin_source is not None}

    def with_overrides(self, *, episodes: int | None = None, seed: int | None = None,
                       model_file: str | None = None) -> ExperimentSpec:
        """The same experiment with ``--episodes`` / ``--seed`` / ``--model`` of the command line
        (a model path given here is taken from the current folder)."""
        if episodes is None and seed is None and model_file is None:
            return self                     # nothing to change: no second validation
        return parse_spec(_overridden(self.source, episodes, seed, model_file), name=self.name,
                          base_dir=self.base_dir)

    def units(self) -> list[WorkUnit]:
        out = []
        for cfg in self.configurations:
            for start in range(0, self.episodes, self.chunk):
                out.append(WorkUnit(config=cfg, seed=self.seed, start=start,
                                    stop=min(self.episodes, start + self.chunk)))
        return out

    def fingerprint(self) -> str:
        """Hash of everything that makes the rows: the resolved spec, a custom model file's bytes
        and each plugin's source. Two specs with the same fingerprint compute the same rows."""
        sources = sorted({d for d in self.plugin_sources.values()})
        if not sources:
            return self.definition_fingerprint()
        blob = self.definition_fingerprint().encode() + "".join(sources).encode()
        return hashlib.sha256(blob).hexdigest()[:16]

    def definition_fingerprint(self) -> str:
        """Hash of the resolved spec and of a custom model file's bytes, without the plugins'
        sources: a resumed sweep must have the same one (the units whose plugin changed since
        are then stale, see :attr:`Configuration.plugin_source`)."""
        blob = json.dumps(self.source, sort_keys=True, default=str).encode()
        first = self.configurations[0] if self.configurations else None
        for file in (first.model_file, first.lti_file) if first is not None else ():
            if file is not None:
                blob += Path(file).read_bytes()
        return hashlib.sha256(blob).hexdigest()[:16]


@dataclass(frozen=True)
class WorkUnit:
    """An independent piece of a sweep: episodes ``[start, stop)`` of one configuration."""

    config: Configuration
    seed: int
    start: int
    stop: int

    @property
    def key(self) -> str:
        return f"c{self.config.index:03d}_e{self.start:06d}-{self.stop:06d}"

    def to_json(self) -> str:
        """Plain JSON; the grid values keep their order (it is the column order of the rows)."""
        return json.dumps(dataclasses.asdict(self))

    @classmethod
    def from_json(cls, text: str) -> WorkUnit:
        d = json.loads(text)
        return cls(config=Configuration(**d["config"]), seed=d["seed"], start=d["start"],
                   stop=d["stop"])


def _overridden(data: dict[str, Any], episodes: int | None, seed: int | None,
                model_file: str | None) -> dict[str, Any]:
    """``data`` with the command line's ``--episodes`` / ``--seed`` / ``--model`` (a model path
    given there is taken from the current folder)."""
    src = dict(data)
    if episodes is not None:
        src["episodes"] = episodes
    if seed is not None:
        src["seed"] = seed
    if model_file is not None:
        src["model_file"] = str(Path(model_file).resolve())
    return src


def check_rows(episodes: int, configurations: int) -> None:
    """The ceiling of an experiment's rows (:data:`~pendulum_lqg.util.limits.MAX_BENCH_ROWS`)."""
    from pendulum_lqg.util.limits import MAX_BENCH_ROWS, check_at_most

    check_at_most("episodes × configurations", episodes * configurations, MAX_BENCH_ROWS,
                  "the summary holds every row of the experiment in memory")


def _grid_point(values: dict[str, Any], base: dict[str, dict[str, Any]],
                base_dir: Path | None = None,
                ) -> tuple[dict[str, dict[str, Any]], str | None]:
    """The resolved tables of one grid point, and its plugin reference (``None``: built-in)."""
    from pendulum_lqg.policies.loading import is_plugin_ref, load_factory, resolve_ref, split_builtin

    tables = {k: dict(v) for k, v in base.items()}
    plugin = None
    for key, value in values.items():
        if key == "policy":
            if is_plugin_ref(value):
                load_factory(value, base_dir=base_dir)   # importable now, not mid-sweep
                plugin = resolve_ref(value, base_dir)
                continue
            try:
                ctrl, obs = split_builtin(value)
            except ConfigError:
                raise ConfigError(f"grid.policy: expected 'controller+observer' (e.g. "
                                  f"'dlqr+kalman') or a plugin 'MODULE:ATTR' / "
                                  f"'path/to/file.py:ATTR', got {value!r}") from None
            tables["design"]["controller"], tables["design"]["observer"] = ctrl, obs
        elif key in ("controller", "observer", "discretization"):
            tables["design"][key] = value
        elif key == "noise_scale":
            tables["noise"]["scale"] = value
        elif key in SCENARIO_GRID_KEYS:
            tables["scenario"][key] = value
        elif key == "delay_kind":
            continue                                     # with ``delay`` below
        elif key == "delay":
            kind = check("grid.delay_kind", values["delay_kind"], Literal[DELAY_KINDS])
            tables["scenario"][f"{kind}_delay"] = value
        elif key == "theta0":
            x0 = list(tables["scenario"].get("x0", defaults.X0))
            x0[1] = value
            tables["scenario"]["x0"] = x0
        else:  # model scales
            tables["model"][key] = value
    return tables, plugin


def _model_file(value: object, base_dir: Path | None) -> str | None:
    """``model_file`` as an absolute path (relative to the experiment file's folder, else the
    current folder: :func:`~pendulum_lqg.util.resources.find_file`), checked to exist."""
    from pendulum_lqg.util.resources import find_file

    if value is None:
        return None
    if not isinstance(value, str) or not value:
        raise ConfigError(f"model_file: expected a path to an MJCF file, got {value!r}")
    path = find_file(value, base_dir)
    if not path.is_file():
        raise ConfigError(f"model_file: no file {value!r}")
    return str(path)


def _located(exc: PendulumLQGError, base: dict[str, dict[str, Any]],
             values: dict[str, Any]) -> PendulumLQGError:
    """``exc`` with the TOML location of its parameter: ``R: …`` → ``design.R: …`` when the key
    was given in ``[design]`` (and not by the grid), plus the grid point that failed."""
    msg = str(exc)
    name = msg.split(":", 1)[0]
    if name in DESIGN_NAMES:                 # a design's V or W: the noise key it came from
        msg = f"{DESIGN_NAMES[name]} ({name}){msg[len(name):]}"
    elif name not in values:
        for table, entries in base.items():
            if name in entries:
                msg = f"{table}.{msg}"
                break
    if values:
        msg += " (grid point " + ", ".join(f"{k}={v!r}" for k, v in values.items()) + ")"
    return type(exc)(msg)


def parse_spec(data: dict[str, Any], *, name: str = "experiment",
               base_dir: Path | None = None) -> ExperimentSpec:
    """Validate an experiment mapping (as read from TOML).

    ``base_dir`` is the folder relative plugin files (``policy = ["my_ctrl.py:make"]``) are taken
    from: the experiment file's own folder (then the current folder).
    """
    from pendulum_lqg.bench.lti import check_lti_experiment, plant_key
    from pendulum_lqg.util.limits import MAX_BATCH_EPISODES, check_at_most

    base = _checked_tables(data)
    grid = _checked_grid(data.get("grid", {}))
    study, study_params = _study(data)
    model_file = _model_file(data.get("model_file"), base_dir)
    lti = plant_key(data, base_dir)
    if lti is not None:
        check_lti_experiment(data)
    episodes, seed, chunk = (check(d.name, data.get(d.name, d.default), d.type)
                             for d in RUN_SETTINGS.values())
    check_at_most("chunk", chunk, MAX_BATCH_EPISODES,
                  "episodes per work unit, one batch of run_episodes")
    configs = _configurations(grid, base, episodes, base_dir, model_file=model_file, lti=lti)
    return ExperimentSpec(name=str(data.get("name", name)), description=str(
        data.get("description", "")), episodes=episodes, seed=seed, chunk=chunk,
        configurations=tuple(configs), source=dict(data),
        study=study, study_params=study_params, base_dir=base_dir)


def _checked_tables(data: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """The top-level keys and those of the ``[scenario]``, ``[noise]``, ``[design]`` and
    ``[model]`` tables checked, ``name`` and ``description`` too: copies of the four tables."""
    check_keys("experiment", data, TOP_KEYS)
    for table, known in (("scenario", SCENARIO_KEYS), ("noise", NOISE_KEYS),
                         ("design", DESIGN_KEYS), ("model", MODEL_KEYS)):
        check_keys(table, data.get(table, {}), known)
    base = {table: dict(data.get(table, {}))
            for table in ("scenario", "noise", "design", "model")}
    for key in ("name", "description"):
        check(key, data.get(key, ""), str)
    if "name" in data:
        check_name(str(data["name"]))
    return base


def _checked_grid(grid: dict[str, Any]) -> dict[str, Any]:
    """``[grid]``: known keys, non-empty lists, built-in controller and observer names, and
    ``delay`` with ``delay_kind``."""
    check_keys("grid", grid, GRID_KEYS)
    for key, values in grid.items():
        if not isinstance(values, list) or not values:
            raise ConfigError(f"grid.{key}: expected a non-empty list, got {values!r}")
    for key, values in grid.items():
        if key == "controller":
            bad = [v for v in values if v not in CONTROLLERS]
        elif key == "observer":
            bad = [v for v in values if v not in OBSERVERS]
        else:
            bad = []
        if bad:
            known = CONTROLLERS if key == "controller" else OBSERVERS
            raise ConfigError(f"grid.{key}: unknown {bad[0]!r}; expected one of " + ", ".join(known))
    if ("delay" in grid) != ("delay_kind" in grid):
        raise ConfigError("grid.delay: give delay and delay_kind together (delay_kind = "
                          "['measurement', 'actuator'] says which delay the values set)")
    return grid


def _study(data: dict[str, Any]) -> tuple[str | None, dict[str, Any]]:
    """``study`` and its parameter table (defaults filled in); a study's table without
    ``study`` naming it is refused."""
    study = data.get("study")
    study_params: dict[str, Any] = {}
    if study is not None:
        if study not in STUDIES:
            raise ConfigError(f"study: unknown {study!r}; expected one of " + ", ".join(STUDIES))
        study_params = parse_study_params(str(study), data.get(str(study), {}))
    for other in STUDIES:
        if other in data and other != study:
            raise ConfigError(f"{other}: a [{other}] table needs study = {other!r}")
    return (None if study is None else str(study)), study_params


def _configurations(grid: dict[str, Any], base: dict[str, dict[str, Any]], episodes: int,
                    base_dir: Path | None, *, model_file: str | None, lti: str | None,
                    ) -> list[Configuration]:
    """Every point of the grid (the Cartesian product of its lists, in the file's key order) as
    a validated configuration, their number and rows checked against the ceilings first; an
    error names the key (``design.R``) and the grid point."""
    from pendulum_lqg.util.limits import MAX_CONFIGURATIONS, check_at_most

    keys = list(grid)
    n_configs = math.prod(len(grid[k]) for k in keys)
    check_at_most("grid", n_configs, MAX_CONFIGURATIONS,
                  "configurations, each validated before the first unit runs")
    check_rows(episodes, n_configs)             # before validating them
    configs = []
    combos = itertools.product(*[grid[k] for k in keys]) if keys else [()]
    for i, combo in enumerate(combos):
        values = dict(zip(keys, combo, strict=True))
        try:
            tables, plugin = _grid_point(values, base, base_dir)
            cfg = Configuration(index=i, values=values, scenario=tables["scenario"],
                                noise=tables["noise"], design=tables["design"],
                                model=tables["model"], plugin=plugin, model_file=model_file,
                                lti_file=lti)
            cfg.validate()  # every configuration now, not in the middle of a sweep
        except PendulumLQGError as exc:
            raise _located(exc, base, values) from exc
        configs.append(cfg)
    return configs


def load_spec(name_or_path: str, *, episodes: int | None = None, seed: int | None = None,
              model_file: str | None = None) -> ExperimentSpec:
    """Load a shipped experiment by name (``lecture``) or a TOML file by path.

    A bare name (no suffix, no folder) is looked up among the shipped experiments first, then as
    ``NAME.toml`` in the current folder; anything else is a path (the current folder's, else the
    shipped copy: :func:`~pendulum_lqg.util.resources.find_file`). ``episodes``, ``seed`` and
    ``model_file`` replace the file's (``bench --episodes/--seed/--model``; as
    :meth:`ExperimentSpec.with_overrides`, but the file is validated once, with them).
    """
    from pendulum_lqg.boundary import read_toml
    from pendulum_lqg.util.resources import experiment_names, experiment_path, find_file

    path = Path(name_or_path)
    if not path.suffix and len(path.parts) == 1:
        shipped = experiment_path(name_or_path)
        if shipped is not None:
            path = shipped
        elif Path(f"{name_or_path}.toml").is_file():
            path = Path(f"{name_or_path}.toml")
    elif not path.is_file():
        path = find_file(path)          # experiments/NAME.toml from an installed package
    if not path.is_file():
        raise ConfigError(f"experiment: no file {name_or_path!r}; known experiments: "
                          + ", ".join(experiment_names()))
    data = read_toml(path, where="experiment")       # a regular file, size and nesting bounded
    try:
        return parse_spec(_overridden(data, episodes, seed, model_file), name=path.stem,
                          base_dir=path.resolve().parent)
    except PendulumLQGError as exc:       # every message names the file it came from
        raise type(exc)(f"{exc} (in {path})") from exc


def run_unit(unit: WorkUnit, *, nthread: int | None = None) -> list[dict[str, Any]]:
    """Run one work unit; rows carry the configuration's grid values and index."""
    from pendulum_lqg.core.runner import run_episodes
    from pendulum_lqg.policies.loading import check_source

    scenario, spec = unit.config.build()
    nominal, simulated = unit.config.plants(scenario)
    if unit.config.plugin is not None:       # the code the experiment's fingerprint describes
        check_source(unit.config.plugin, unit.config.plugin_source)
    policy = unit.config.source.policy(unit.config, scenario, spec, nominal)
    res = run_episodes(simulated, scenario, policy, seed=unit.seed,
                       episodes=range(unit.start, unit.stop), nthread=nthread)
    out = []
    for row in res.rows:
        out.append({"config": unit.config.index, **_flat(unit.config.values), **row})
    return out


def _flat(values: dict[str, Any]) -> dict[str, Any]:
    return {k: (json.dumps(v) if isinstance(v, list | dict) else v) for k, v in values.items()}
