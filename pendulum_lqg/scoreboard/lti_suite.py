"""Suites of a plant given as matrices: the score of a built-in policy on an LTI plant's fixed seeds.

An LTI suite is a TOML file that names its plant (``lti_file``: beside the suite file, from the
current folder, or a shipped ``experiments/lti/…`` file), its reference design and its episodes::

    name = "two-mass"
    version = 1
    purpose = "…"
    lti_file = "two_mass.toml"
    reference = "dlqr+kalman"       # the plant's own LQG design: it scores exactly 1
    episodes = 100                  # episode k is seeded episode_seed(seed, k)
    seed = 2026

    [scenario]                      # what the episodes run under (lti_scenario's fields)
    duration = 10.0
    noise_scale = 1.0
    estimate0 = "zero"

``lti_file`` is any plant file: a plant given as matrices or a MuJoCo plant (``model = "x.xml"``).

**A plant's own suite** (``score --plant NAME|FILE``, ``train --plant``; :func:`plant_suite`) is
the suite of :data:`PLANT_SUITE` on the plant NAME or FILE names: its name the plant's, its
episodes the plant file's scenario (its x0, noise, cost and limits) for 10 s, seeded as the
cart-pole suites (2026), the reference ``dlqr+kalman`` designed on it. The shipped
``experiments/lti/two_mass_suite.toml`` writes exactly these keys, so ``score --plant
experiments/lti/two_mass.toml`` and ``score --suite experiments/lti/two_mass_suite.toml`` give
the same score file.

Every entry is a built-in policy ``controller+observer`` designed on the file's plant
(:func:`~pendulum_lqg.policies.lti.design_lti_policy`: the plant played, so the reference is the
optimum the gap is taken to), or a linear controller file (``--agent linear:FILE``, of the
plant's p outputs: :mod:`pendulum_lqg.scoreboard.linear`), played on the same seeded episodes
through the one loop. The figures are the cart-pole suites' (:mod:`pendulum_lqg.scoreboard.score`):
success rate, mean J, the optimality gap and the failure-aware score to the reference, the
full-state bound (``dlqr+none``). Other Gymnasium agents and plug-ins are not scored here
(``"applicable": false`` and the reason).

An LTI suite answers what the learning methods ask of a suite (:attr:`LTISuite.env`,
:attr:`LTISuite.config`, :meth:`LTISuite.plants`), so ``train --plant`` trains on the plant's env
and its curve is judged on the plant's episodes.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

from pendulum_lqg.boundary.fields import Where, integer, number, one_of, table, text
from pendulum_lqg.boundary.schemas import DESIGNED_ON_LTI
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.util.limits import MAX_SCORE_EPISODES

#: The keys of an LTI suite file, and of its ``[scenario]`` table.
LTI_SUITE_KEYS = ("name", "version", "purpose", "lti_file", "reference", "episodes", "seed",
                  "scenario")
SCENARIO_KEYS = ("duration", "noise_scale", "estimate0", "burn_in")
#: A plant's own suite (:func:`plant_suite`): every key of a suite file but its name, purpose and
#: plant, as the cart-pole suites seed and time their episodes.
PLANT_SUITE: dict[str, Any] = {
    "version": 1, "reference": "dlqr+kalman", "episodes": 100, "seed": 2026,
    "scenario": {"duration": 10.0, "noise_scale": 1.0, "estimate0": "zero"}}
#: The scenario keys the environments take beside ``plant`` (:attr:`LTISuite.env`).
_ENV_KEYS = ("duration", "noise_scale")
# What the designs of an LTI suite are designed on, DESIGNED_ON_LTI (the file's plant, the plant
# played), is kept where the score files' schema reads it: pendulum_lqg.boundary.schemas.


@dataclass(frozen=True)
class LTISuite:
    """One LTI suite (the module docstring); ``origin`` the file it was read from."""

    name: str
    purpose: str
    lti_file: Path
    reference: str
    episodes: int
    seed: int
    version: int = 1
    scenario: dict[str, Any] = field(default_factory=dict)
    origin: str = ""
    designed_on: str = DESIGNED_ON_LTI
    #: the plant as ``--plant`` named it (a shipped NAME stays a name in the env's keywords)
    plant_ref: str = ""

    def plant(self) -> Any:
        """The suite's plant (:func:`~pendulum_lqg.model.catalog.load_plant_at`: matrices or a
        MuJoCo model)."""
        from pendulum_lqg.model.catalog import load_plant_at

        return load_plant_at(self.lti_file)

    # ---- what a cart-pole suite answers too (the learning methods, linear controllers) ----
    observes_state = False            # a plant's suite observes its outputs y

    def plants(self) -> tuple[Any, Any]:
        """``(simulated, design)``: the plant played, loaded twice (the designs never share the
        simulator's model)."""
        return self.plant(), self.plant()

    @cached_property
    def config(self) -> Any:
        """The :class:`~pendulum_lqg.envs.config.EnvConfig` of the suite's episodes: the plant's
        scenario (:func:`~pendulum_lqg.policies.lti.lti_scenario` of the ``[scenario]`` keys),
        observing y."""
        from pendulum_lqg.envs.config import DEFAULT_REWARD_SCALE, EnvConfig
        from pendulum_lqg.policies.lti import lti_scenario

        plant = self.plant()
        return EnvConfig(scenario=lti_scenario(plant, **self.scenario),
                         observation_mode="measurement", reward_scale=DEFAULT_REWARD_SCALE,
                         model_path=None, plant_file=plant)

    @property
    def env(self) -> dict[str, Any]:
        """The environments' keywords of the suite's plant (``plant``: its file) and scenario:
        what ``train --plant`` trains on."""
        return {"plant": self.plant_ref or str(self.lti_file),
                **{k: v for k, v in self.scenario.items() if k in _ENV_KEYS}}

    def errors_named(self, what: str, exc: Any) -> Any:
        """``exc`` found while playing ``what`` of the suite, naming the suite's file."""
        where = self.origin or f"suite {self.name!r}"
        return exc if str(exc).startswith(where) else type(exc)(f"{where}: {what}: {exc}")

    def fingerprint(self) -> str:
        """sha256 of what decides the episodes: the definition and the plant file's bytes."""
        definition = {"name": self.name, "version": self.version, "reference": self.reference,
                      "episodes": self.episodes, "seed": self.seed, "scenario": self.scenario}
        h = hashlib.sha256(json.dumps(definition, sort_keys=True).encode())
        h.update(self.lti_file.read_bytes())
        return h.hexdigest()

    def rows(self, policy: str) -> list[dict[str, Any]]:
        """The score rows (``episode, seed, success, failure_reason, cost``, as the cart-pole
        suites') of the built-in ``policy`` on the suite's seeds."""
        from pendulum_lqg.core.runner import run_episodes
        from pendulum_lqg.policies.lti import design_lti_policy, lti_scenario

        plant = self.plant()
        scenario = lti_scenario(plant, **self.scenario)
        res = run_episodes(plant, scenario, design_lti_policy(plant, policy), seed=self.seed,
                           episodes=range(self.episodes))
        return [{k: r[k] for k in ("episode", "seed", "success", "failure_reason", "cost")}
                for r in res.rows]


def plant_suite(ref: str | Path, *, what: str = "--plant") -> LTISuite:
    """The plant's own suite (module docstring, :data:`PLANT_SUITE`) of the plant ``ref``
    names (a shipped NAME or a plant file; the cart-pole's suites are the shipped ones)."""
    from pendulum_lqg.model.catalog import is_cartpole, load_plant_at, plant_path

    if is_cartpole(ref):
        raise ConfigError(f"{what}: the cart-pole's suites are the shipped ones (score --suite "
                          "NAME), not one plant suite")
    path = plant_path(ref, what=what).resolve()
    plant = load_plant_at(path)                # the file checked: one line naming it and the key
    name = plant.name.replace("_", "-")
    return LTISuite(name=name, purpose=f"the plant {name}'s own suite ({path.name})",
                    lti_file=path, origin=str(ref), plant_ref=str(ref), **PLANT_SUITE)


def names_an_lti_plant(name_or_path: str) -> bool:
    """Whether ``name_or_path`` is a TOML file that names an ``lti_file`` (an LTI suite)."""
    from pendulum_lqg.boundary import read_toml

    path = Path(name_or_path)
    if path.suffix != ".toml" or not path.is_file():
        return False
    data = read_toml(path, where="suite")
    return isinstance(data, dict) and "lti_file" in data


def load_lti_suite(path: str | Path) -> LTISuite:
    """An :class:`LTISuite` from its file; errors are one line ``FILE: key: expected …, got …``."""
    from pendulum_lqg.boundary import read_toml
    from pendulum_lqg.util.resources import find_file

    path = Path(path)
    where = Where(str(path))
    data = where.check(read_toml(path, where="suite"), table)
    unknown = sorted(set(data) - set(LTI_SUITE_KEYS))
    if unknown:
        raise where.error(f"unknown key {unknown[0]!r}; known: {', '.join(LTI_SUITE_KEYS)}")
    for key in ("lti_file", "reference", "episodes"):
        if key not in data:
            raise where.error("missing", key)
    sc = dict(where.get(data, "scenario", table, default={}))
    bad = sorted(set(sc) - set(SCENARIO_KEYS))
    if bad:
        raise where.error(f"unknown key {bad[0]!r}; known: {', '.join(SCENARIO_KEYS)}",
                          "scenario")
    inner = where.at("scenario")
    scenario = {k: inner.get(sc, k, v) for k, v in (
        ("duration", number(low=0.0)), ("noise_scale", number(low=0.0)),
        ("estimate0", one_of(("zero", "true"))), ("burn_in", number(low=0.0))) if k in sc}
    lti = find_file(where.get(data, "lti_file", text), base_dir=path.parent)
    episodes = where.get(data, "episodes", integer(1))
    if episodes > MAX_SCORE_EPISODES:
        raise where.error(f"expected at most {MAX_SCORE_EPISODES}, got {episodes}", "episodes")
    return LTISuite(name=where.get(data, "name", text), purpose=where.get(data, "purpose", text),
                    lti_file=lti,
                    reference=where.get(data, "reference", text),
                    episodes=episodes,
                    seed=where.get(data, "seed", integer(0), default=0),
                    version=where.get(data, "version", integer(1), default=1),
                    scenario=scenario, origin=str(path))


def lti_suite_entry(suite: LTISuite, policy: str,
                    cache: dict[str, list[dict[str, Any]]] | None = None, *,
                    entry_rows: Any = None) -> dict[str, Any]:
    """The score file's entry of the built-in ``policy`` on ``suite``: the cart-pole suites'
    figures (:func:`~pendulum_lqg.scoreboard.score.suite_figures`) against the suite's reference
    and the full-state bound, on the same seeds. ``cache`` keeps rows by policy;
    ``entry_rows()``, where given, plays the entry instead (a linear controller file)."""
    from pendulum_lqg.scoreboard.score import FULL_STATE_POLICY, suite_figures

    memo = {} if cache is None else cache

    def rows(name: str) -> list[dict[str, Any]]:
        if name not in memo:
            memo[name] = suite.rows(name)
        return memo[name]

    try:
        reference, bound = rows(suite.reference), rows(FULL_STATE_POLICY)
    except ConfigError as exc:
        raise ConfigError(f"{suite.origin}: reference: {exc}") from None
    played = rows(policy) if entry_rows is None else entry_rows()
    out = suite_figures(played, reference, bound, reference_policy=suite.reference)
    return {"applicable": True, **out, "version": suite.version,
            "fingerprint": suite.fingerprint(), "designed_on": suite.designed_on,
            "lti_file": str(suite.lti_file), "rows": [dict(r) for r in played]}


def lti_suite_entries(suites: list[LTISuite], *, policy: str | None, agent: str | None,
                      episodes: int | None = None, noise_scale: float | None = None,
                      nthread: int | None = None) -> dict[str, dict[str, Any]]:
    """The score file's ``suites`` entries of one entry on LTI ``suites`` (``score --suite
    FILE``, ``score --plant``): a built-in ``policy`` is scored (:func:`lti_suite_entry`), and a
    linear controller file (``agent`` ``linear:FILE``) through the same batch; another Gymnasium
    agent or a plug-in gets ``"applicable": false`` and the reason, as does a controller of
    another number of outputs. ``episodes`` and ``noise_scale`` as ``score``'s options (every
    suite's own by default)."""
    import dataclasses

    from pendulum_lqg.errors import NotApplicable
    from pendulum_lqg.policies.loading import is_plugin_ref

    factory = None
    if agent is not None and agent.startswith("linear:"):
        from pendulum_lqg.scoreboard.linear import linear_agent

        factory = linear_agent(agent.removeprefix("linear:"))
    out: dict[str, dict[str, Any]] = {}
    for s in suites:
        if episodes is not None:
            s = dataclasses.replace(s, episodes=episodes)
        if noise_scale is not None:
            s = dataclasses.replace(s, scenario={**s.scenario, "noise_scale": noise_scale})
        reason = None
        if factory is not None:
            try:
                out[s.name] = lti_suite_entry(s, s.reference,
                                              entry_rows=_linear_rows(s, factory, nthread))
                continue
            except NotApplicable as exc:
                reason = str(exc)
        elif agent is not None or policy is None or is_plugin_ref(policy):
            what = "a Gymnasium agent" if agent is not None else "a plug-in"
            reason = (f"a plant's suite scores the built-in policies and linear controller "
                      f"files (linear:FILE); {what} is played on the cart-pole's suites")
        if reason is not None:
            out[s.name] = {"applicable": False, "episodes": s.episodes, "version": s.version,
                           "reason": reason, "fingerprint": s.fingerprint(),
                           "designed_on": s.designed_on}
        else:
            assert policy is not None
            out[s.name] = lti_suite_entry(s, policy)
    return out


def _linear_rows(suite: LTISuite, factory: Any, nthread: int | None) -> Any:
    """The rows of a linear controller file on ``suite``
    (:func:`~pendulum_lqg.scoreboard.linear.linear_rows`), played when asked; a controller of
    another p is refused before the suite's own rows are run."""
    from pendulum_lqg.scoreboard.linear import linear_policy, linear_rows

    plant = suite.plant()
    linear_policy(factory.doc, 1.0, outputs=plant.layout(suite.config.scenario).p,
                  name=factory.name)
    return lambda: linear_rows(suite, factory.doc, name=factory.name, nthread=nthread)
