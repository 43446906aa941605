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

Every entry is a built-in policy ``controller+observer`` designed on the file's plant
(:func:`~pendulum_lqg.policies.lti.design_lti_policy`: the plant played, so the reference is the
optimum the gap is taken to), played on the same seeded episodes through the one loop. The figures
are the cart-pole suites' (:mod:`pendulum_lqg.scoreboard.score`): success rate, mean J, the
optimality gap and the failure-aware score to the reference, the full-state bound (``dlqr+none``).
Gymnasium agents and plug-ins play the cart-pole env and are not scored here (``score`` says so,
one line).
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
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

    def plant(self) -> Any:
        """The suite's plant (:func:`~pendulum_lqg.model.catalog.load_plant_at`: matrices or a
        MuJoCo model)."""
        from pendulum_lqg.model.catalog import load_plant_at

        return load_plant_at(self.lti_file)

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
                    cache: dict[str, list[dict[str, Any]]] | None = None) -> dict[str, Any]:
    """The score file's entry of the built-in ``policy`` on ``suite``: the cart-pole suites'
    figures (:func:`~pendulum_lqg.scoreboard.score.suite_figures`) against the suite's reference
    and the full-state bound, on the same seeds. ``cache`` keeps rows by policy."""
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
    out = suite_figures(rows(policy), reference, bound, reference_policy=suite.reference)
    return {"applicable": True, **out, "version": suite.version,
            "fingerprint": suite.fingerprint(), "designed_on": suite.designed_on,
            "lti_file": str(suite.lti_file), "rows": [dict(r) for r in rows(policy)]}


def lti_suite_entries(suites: list[LTISuite], *, policy: str | None, agent: str | None,
                      episodes: int | None = None, noise_scale: float | None = None,
                      ) -> dict[str, dict[str, Any]]:
    """The score file's ``suites`` entries of one entry on LTI ``suites`` (``score --suite
    FILE``): a built-in ``policy`` is scored (:func:`lti_suite_entry`); a Gymnasium agent or a
    plug-in, which play the cart-pole, gets ``"applicable": false`` and the reason. ``episodes``
    and ``noise_scale`` as ``score``'s options (every suite's own by default)."""
    import dataclasses

    from pendulum_lqg.policies.loading import is_plugin_ref

    out: dict[str, dict[str, Any]] = {}
    for s in suites:
        if episodes is not None:
            s = dataclasses.replace(s, episodes=episodes)
        if noise_scale is not None:
            s = dataclasses.replace(s, scenario={**s.scenario, "noise_scale": noise_scale})
        if agent is not None or policy is None or is_plugin_ref(policy):
            what = "a Gymnasium agent" if agent is not None else "a plug-in"
            out[s.name] = {"applicable": False, "episodes": s.episodes, "version": s.version,
                           "reason": f"an LTI suite scores the built-in policies; {what} plays "
                                     "the cart-pole", "fingerprint": s.fingerprint(),
                           "designed_on": s.designed_on}
        else:
            out[s.name] = lti_suite_entry(s, policy)
    return out
