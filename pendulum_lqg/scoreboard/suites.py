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
"""

from __future__ import annotations

import hashlib
import json
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pendulum_lqg.envs.config import EnvConfig
from pendulum_lqg.errors import ConfigError, PendulumLQGError
from pendulum_lqg.plant import Plant, load_plant
from pendulum_lqg.resources import data_dir

#: The keys of a suite file.
SUITE_KEYS = ("name", "version", "purpose", "reference", "episodes", "seed", "env")
#: The order in which ``--suite all`` runs and the board shows the shipped suites: easiest first, by
#: the reference policy's success rate (docs/leaderboard.md gives the figures).
SUITE_ORDER = ("full-state", "lecture", "mismatch", "delayed", "lossy", "noisy", "hard")


@dataclass(frozen=True)
class Suite:
    """One challenge level (see the module docstring for the file format).

    Attributes
    ----------
    name, version, purpose : what it is; a changed level gets a new version
    reference : the built-in policy (``"controller+observer"``) the optimality gap is taken to
    episodes, seed : episode ``k`` (0 ≤ k < episodes) is seeded ``episode_seed(seed, k)``
    env : the Gymnasium env keywords that define the scenario
    config : the validated :class:`~pendulum_lqg.envs.config.EnvConfig` of ``env``
    """

    name: str
    version: int
    purpose: str
    reference: str
    episodes: int
    seed: int
    env: dict[str, Any] = field(default_factory=dict)
    config: EnvConfig = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        try:
            config = EnvConfig.from_keywords(dict(self.env))
        except PendulumLQGError as exc:
            raise type(exc)(f"suite {self.name!r}: [env] {exc}") from exc
        object.__setattr__(self, "config", config)

    @property
    def observes_state(self) -> bool:
        """The policy observes the true state ``x`` (``observation_mode = "state"``)."""
        return self.config.observation_mode == "state"

    def with_episodes(self, episodes: int | None) -> Suite:
        """The same suite with another episode count (a quick score; its fingerprint differs)."""
        if episodes is None:
            return self
        return Suite(self.name, self.version, self.purpose, self.reference,
                     _positive_int(f"suite {self.name!r}: episodes", episodes), self.seed,
                     dict(self.env))

    def plants(self) -> tuple[Plant, Plant]:
        """``(simulated, nominal)`` plants: the simulated one with the scenario's overrides, the
        nominal one (the MJCF as it is) for the designs."""
        path = self.config.model_path
        return load_plant(path, overrides=self.config.scenario.overrides), load_plant(path)

    def fingerprint(self) -> str:
        """sha256 of everything that decides the episodes: the definition, the scenario it makes and
        the model file's bytes. Two scores are comparable only when their fingerprints match."""
        model = load_plant(self.config.model_path).path
        blob = json.dumps({"name": self.name, "version": self.version, "episodes": self.episodes,
                           "seed": self.seed, "reference": self.reference,
                           "scenario": self.config.scenario.to_dict(),
                           "observation_mode": self.config.observation_mode,
                           "model_sha256": hashlib.sha256(Path(model).read_bytes()).hexdigest()},
                          sort_keys=True, default=str)
        return hashlib.sha256(blob.encode()).hexdigest()

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "version": self.version, "purpose": self.purpose,
                "reference": self.reference, "episodes": self.episodes, "seed": self.seed,
                "env": dict(self.env)}


def _positive_int(where: str, value: object) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise ConfigError(f"{where}: expected a positive integer, got {value!r}")
    return value


def parse_suite(data: dict[str, Any], *, path: str = "suite") -> Suite:
    """A :class:`Suite` from the parsed TOML ``data`` (errors name ``path`` and the key)."""
    unknown = sorted(set(data) - set(SUITE_KEYS))
    if unknown:
        raise ConfigError(f"{path}: unknown key {unknown[0]!r}; known: {', '.join(SUITE_KEYS)}")
    missing = [k for k in SUITE_KEYS if k not in data and k != "env"]
    if missing:
        raise ConfigError(f"{path}: key {missing[0]!r} is missing")
    for key in ("name", "purpose", "reference"):
        if not isinstance(data[key], str) or not data[key]:
            raise ConfigError(f"{path}: {key}: expected a non-empty string, got {data[key]!r}")
    if "+" not in data["reference"]:
        raise ConfigError(f"{path}: reference: expected a built-in 'controller+observer', got "
                          f"{data['reference']!r}")
    env = data.get("env", {})
    if not isinstance(env, dict):
        raise ConfigError(f"{path}: env: expected a table of env keywords, got {env!r}")
    seed = data["seed"]
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ConfigError(f"{path}: seed: expected a non-negative integer, got {seed!r}")
    try:
        return Suite(name=data["name"], version=_positive_int(f"{path}: version", data["version"]),
                     purpose=data["purpose"], reference=data["reference"],
                     episodes=_positive_int(f"{path}: episodes", data["episodes"]), seed=seed,
                     env=dict(env))
    except PendulumLQGError as exc:
        raise type(exc)(f"{exc} (in {path})") from exc


def suites_dir() -> Path:
    """The folder of the shipped suites (``experiments/suites``)."""
    return data_dir("experiments") / "suites"


def suite_names() -> list[str]:
    """The shipped suites, in :data:`SUITE_ORDER` (then any others by name)."""
    names = {p.stem for p in suites_dir().glob("*.toml")}
    return [n for n in SUITE_ORDER if n in names] + sorted(names - set(SUITE_ORDER))


def load_suite(name_or_path: str) -> Suite:
    """A shipped suite by name (``lecture``) or a suite file by path."""
    path = Path(name_or_path)
    if not path.suffix and len(path.parts) == 1:
        path = suites_dir() / f"{name_or_path}.toml"
        if not path.is_file():
            raise ConfigError(f"suite: no suite {name_or_path!r}; shipped: "
                              + ", ".join(suite_names()))
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(f"suite: cannot read {path}: {exc}") from exc
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"suite: {path} is not valid TOML: {' '.join(str(exc).split())}") from exc
    suite = parse_suite(data, path=str(path))
    if path.parent == suites_dir() and suite.name != path.stem:
        raise ConfigError(f"suite: {path} names itself {suite.name!r}; a shipped suite's name is "
                          "its file name")
    return suite
