"""Suites: named, versioned challenge levels on fixed seeds, each with its reference policy.

A suite is a TOML file in ``experiments/suites/`` (shipped with the package)::

    name = "lecture"
    version = 1
    purpose = "The lecture's problem: …"
    reference = "dlqr+kalman"       # the best built-in LQG design for this level
    episodes = 100                  # episode k is seeded episode_seed(seed, k)
    seed = 2026

    [env]                           # the Gymnasium env's keywords: they define the scenario
    duration = 10.0

The ``[env]`` table is what ``gymnasium.make("pendulum_lqg/CartPoleLQG-v0", **env)`` takes, and
the same keywords give the :class:`~pendulum_lqg.core.scenario.Scenario` a batch plug-in runs in
(:class:`~pendulum_lqg.envs.config.EnvConfig`), so a Gymnasium agent and a plug-in face the same
episodes. An unknown key is an error listing the known ones.

**The model the designs know.** The reference, every built-in design, a plug-in's context and the
Kalman filter an observation design shows (:mod:`~pendulum_lqg.scoreboard.obs_design`) are
designed on one plant, :func:`design_plant`: the suite's plant *without its per-episode draws* —
the MJCF of ``model_path`` (default ``models/cartpole.xml``) with the fixed ``model_overrides``
applied, never a ``randomize`` draw. So

* a suite that fixes its plant (``model_path``, fixed ``model_overrides``, no ``randomize``) is
  designed on **the plant played**: the designer knows the plant, and the reference is the
  optimum the gap is taken to (the same plant given as a modified MJCF or as overrides gives the
  same reference);
* a suite that randomises its plant (``randomize``, as ``mismatch``) is designed on **the nominal
  MJCF**: what the designer does not know is the point of the level;
* with both, the design is on the overridden plant: a randomisation multiplies the overridden
  values (:meth:`~pendulum_lqg.model.overrides.Randomization.apply`), so the overridden plant is the
  ×1 member of the family the suite draws from, its nominal in the same sense as ``mismatch``'s
  MJCF; the overrides state the plant and the draws are the unknown. (Were the overrides unknown
  there, adding a small randomisation to a fixed suite would silently move its reference to
  another plant.)

A suite that poses a *fixed* model error the designer does not know writes it as a randomisation
of one value, ``pole_mass_scale = [1.6, 1.6]``. :func:`designed_on` names the case; the score
files and the board carry it.

Unlike a suite, the ``bench`` experiments and :class:`~pendulum_lqg.envs.agent.LQGAgent` (by
default) treat overrides as a mismatch (designs on the MJCF as it is): there the overrides are a
study of a model error, here they define the level.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

from pendulum_lqg.boundary import read_toml
from pendulum_lqg.boundary.fields import Invalid, Where, integer, table, text
from pendulum_lqg.boundary.schemas import DESIGNED_ON
from pendulum_lqg.envs.config import EnvConfig
from pendulum_lqg.errors import ConfigError, PendulumLQGError
from pendulum_lqg.model.plant import Plant, load_plant
from pendulum_lqg.names import CONTROLLERS, OBSERVERS
from pendulum_lqg.util.limits import MAX_SCORE_EPISODES
from pendulum_lqg.util.resources import data_dir

#: The keys of a suite file.
SUITE_KEYS = ("name", "version", "purpose", "reference", "episodes", "seed", "env")
#: The order in which ``--suite all`` runs and the board shows the shipped suites: easiest first, by
#: the reference policy's success rate (docs/leaderboard.md gives the figures).
SUITE_ORDER = ("full-state", "lecture", "mismatch", "delayed", "lossy", "noisy", "hard")
#: What the designs of a suite are designed on (:func:`designed_on`; the module docstring).
PLANT_PLAYED, NOMINAL_MJCF, NOMINAL_WITH_OVERRIDES = DESIGNED_ON


def design_plant(config: EnvConfig) -> Plant:
    """The plant the designs of an env's episodes are designed on (the module docstring): the MJCF
    of ``config.model_path`` with the fixed ``model_overrides``, without any ``randomize`` draw —
    the plant played where the plant is fixed, the nominal of the randomisation where not."""
    return load_plant(config.model_path, overrides=config.scenario.overrides)


def designed_on(config: EnvConfig) -> str:
    """What :func:`design_plant` is for ``config``: :data:`PLANT_PLAYED` (no randomisation),
    :data:`NOMINAL_MJCF` (a randomisation around the MJCF as it is) or
    :data:`NOMINAL_WITH_OVERRIDES` (a randomisation around the overridden plant)."""
    scenario = config.scenario
    if scenario.randomize.is_empty():
        return PLANT_PLAYED
    return NOMINAL_MJCF if scenario.overrides.is_empty() else NOMINAL_WITH_OVERRIDES


@dataclass(frozen=True)
class Suite:
    """One challenge level (see the module docstring for the file format).

    Attributes
    ----------
    name, version, purpose : what it is; a changed level gets a new version
    reference : the built-in policy (``"controller+observer"``) the optimality gap is taken to
    episodes, seed : episode ``k`` (0 ≤ k < episodes) is seeded ``episode_seed(seed, k)``
    env : the Gymnasium env keywords that define the scenario
    origin : where the suite was read (its file), named by the errors found when it is played
    config : the validated :class:`~pendulum_lqg.envs.config.EnvConfig` of ``env``
    designed_on : what the reference and the built-in designs are designed on (:func:`designed_on`)
    """

    name: str
    version: int
    purpose: str
    reference: str
    episodes: int
    seed: int
    env: dict[str, Any] = field(default_factory=dict)
    origin: str = field(default="", compare=False)
    config: EnvConfig = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        try:
            config = EnvConfig.from_keywords(dict(self.env))
        except PendulumLQGError as exc:
            raise type(exc)(f"suite {self.name!r}: [env] {exc}") from exc
        object.__setattr__(self, "config", config)

    @property
    def designed_on(self) -> str:
        """:data:`PLANT_PLAYED`, :data:`NOMINAL_MJCF` or :data:`NOMINAL_WITH_OVERRIDES`: what
        :meth:`plants`' design plant is (the module docstring)."""
        return designed_on(self.config)

    @property
    def observes_state(self) -> bool:
        """The policy observes the true state ``x`` (``observation_mode = "state"``)."""
        return self.config.observation_mode == "state"

    def with_episodes(self, episodes: int | None) -> Suite:
        """The same suite with another episode count (a quick score; its fingerprint differs)."""
        if episodes is None:
            return self
        return Suite(self.name, self.version, self.purpose, self.reference,
                     _episodes(f"suite {self.name!r}: episodes", episodes), self.seed,
                     dict(self.env), origin=self.origin)

    def with_noise_scale(self, noise_scale: float | None) -> Suite:
        """The same suite with its env's ``noise_scale`` set to ``noise_scale`` (both noises'
        standard deviations times it; the designs keep the nominal noise): the noise ladder. Its
        fingerprint differs from the suite's unless the scale is the suite's own."""
        if noise_scale is None:
            return self
        return Suite(self.name, self.version, self.purpose, self.reference, self.episodes,
                     self.seed, {**self.env, "noise_scale": noise_scale}, origin=self.origin)

    def errors_named(self, what: str, exc: PendulumLQGError) -> PendulumLQGError:
        """``exc`` found while playing ``what`` of the suite, as one line naming the suite's file
        (an error in the suite must not read as one in the entry scored on it)."""
        where = self.origin or f"suite {self.name!r}"
        return exc if str(exc).startswith(where) else type(exc)(f"{where}: {what}: {exc}")

    def plants(self) -> tuple[Plant, Plant]:
        """``(simulated, design)`` plants: the simulated one with the scenario's overrides (each
        episode's ``randomize`` draw is applied by the core on top of it), and the one every
        design for the suite is made on, :func:`design_plant` (two loads: the designs never share
        the simulator's model)."""
        try:
            return (load_plant(self.config.model_path, overrides=self.config.scenario.overrides),
                    design_plant(self.config))
        except PendulumLQGError as exc:
            raise self.errors_named("env.model_path", exc) from None

    def fingerprint(self) -> str:
        """sha256 of everything that decides the episodes: the definition, the scenario it makes,
        the model file's bytes, and what the designs are designed on where that is not the MJCF as
        it is. Two scores are comparable only when their fingerprints match. Computed once per
        suite (the model file is read once)."""
        return self._fingerprint

    @cached_property
    def _fingerprint(self) -> str:
        try:
            model = load_plant(self.config.model_path).path
        except PendulumLQGError as exc:
            raise self.errors_named("env.model_path", exc) from None
        definition = {"name": self.name, "version": self.version, "episodes": self.episodes,
                      "seed": self.seed, "reference": self.reference,
                      "scenario": self.config.scenario.to_dict(),
                      "observation_mode": self.config.observation_mode,
                      "model_sha256": hashlib.sha256(Path(model).read_bytes()).hexdigest()}
        if not self.config.scenario.overrides.is_empty():
            # the designs were made on the MJCF as it is before the rule of design_plant; a suite
            # with fixed overrides now has another reference, so its old scores must not compare.
            # Without overrides the design plant is the MJCF as before: the key is absent and the
            # fingerprint is the one the committed score files carry
            definition["designed_on"] = self.designed_on
        blob = json.dumps(definition, sort_keys=True, default=str)
        return hashlib.sha256(blob.encode()).hexdigest()

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "version": self.version, "purpose": self.purpose,
                "reference": self.reference, "episodes": self.episodes, "seed": self.seed,
                "env": dict(self.env)}


def _episodes(where: str, value: object) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise ConfigError(f"{where}: expected a positive integer, got {value!r}")
    if value > MAX_SCORE_EPISODES:
        raise ConfigError(f"{where}: at most {MAX_SCORE_EPISODES:,} (the rows of the entry, its "
                          f"reference and the full-state bound are kept in memory), got {value:,}")
    return value


def _reference(value: object) -> str:
    """A built-in ``controller+observer`` (the suite's reference is designed, never a plug-in)."""
    name = text(value)
    controller, _, observer = name.partition("+")
    if controller not in CONTROLLERS or observer not in OBSERVERS:
        raise Invalid(f"a built-in 'controller+observer' (controllers {', '.join(CONTROLLERS)}; "
                      f"observers {', '.join(OBSERVERS)})")
    return name


def parse_suite(data: dict[str, Any], *, path: str = "suite") -> Suite:
    """A :class:`Suite` from the parsed TOML ``data``; errors are one line naming ``path`` and the
    key (``my.toml: reference: expected …``)."""
    where = Where(path)
    data = where.check(data, table)
    unknown = sorted(set(data) - set(SUITE_KEYS))
    if unknown:
        raise where.error(f"unknown key {unknown[0]!r}; known: {', '.join(SUITE_KEYS)}")
    fields = {"name": where.get(data, "name", text), "purpose": where.get(data, "purpose", text),
              "reference": where.get(data, "reference", _reference),
              "version": where.get(data, "version", integer(1)),
              "seed": where.get(data, "seed", integer(0)),
              "env": dict(where.get(data, "env", table, default={}))}
    if "episodes" not in data:
        raise where.error("missing", "episodes")
    try:
        episodes = _episodes(where.label("episodes"), data["episodes"])
        return Suite(episodes=episodes, origin=path, **fields)
    except PendulumLQGError as exc:
        raise type(exc)(f"{exc} (in {path})" if path not in str(exc) else str(exc)) from None


def suites_dir() -> Path:
    """The folder of the shipped suites (``experiments/suites``)."""
    return data_dir("experiments") / "suites"


def suite_names() -> list[str]:
    """The shipped suites, in :data:`SUITE_ORDER` (then any others by name)."""
    names = {p.stem for p in suites_dir().glob("*.toml")}
    return [n for n in SUITE_ORDER if n in names] + sorted(names - set(SUITE_ORDER))


def load_suite(name_or_path: str) -> Suite:
    """A shipped suite by name (``lecture``) or a suite file by path (a regular file, read through
    :mod:`pendulum_lqg.boundary`)."""
    path = Path(name_or_path)
    if not path.suffix and len(path.parts) == 1:
        path = suites_dir() / f"{name_or_path}.toml"
        if not path.is_file():
            raise ConfigError(f"suite: no suite {name_or_path!r}; shipped: "
                              + ", ".join(suite_names()))
    suite = parse_suite(read_toml(path, where="suite"), path=str(path))
    if path.parent == suites_dir() and suite.name != path.stem:
        raise ConfigError(f"suite: {path} names itself {suite.name!r}; a shipped suite's name is "
                          "its file name")
    return suite
