"""The score of a policy or agent on the suites: success, cost and the optimality gap to LQG.

Per suite, over its ``episodes`` fixed seeds (the same episodes for every entry):

* **success rate** — the share of episodes that reach the end without failing, with its 95 %
  Wilson score interval;
* **mean J** — the mean cost ``J = ∫ xᵀQx + R u² dt`` of the successful episodes, with its standard
  error (failed episodes end early, so their J is not comparable);
* **optimality gap** — on the episodes that *both* the entry and the suite's reference policy
  survived (set ``S``), ``gap = mean_S(J) / mean_S(J_ref) − 1``: 0 means as good as the
  reference LQG design, 0.5 means 50 % more cost, a negative gap beats it. Episodes either one
  failed are left out of the gap and counted by the success rate instead; with no common
  survivor the gap is ``null``. Its 95 % interval is a paired bootstrap over ``S`` (the same
  resampled episodes for both; 2 000 resamples, a fixed seed, so it is reproducible). The
  reference's gap to itself is exactly 0 (the same rows, the same sums).
* **failure-aware score** — per episode ``J_ref / J`` if the entry survived, 0 if it failed
  (:func:`pendulum_lqg.scoreboard.stats.failure_aware_scores`); ``score_mean`` is its mean over
  the suite's episodes, ``score_ci`` its 95 % bootstrap interval over the episodes. Unlike the
  gap it counts failures, so it compares entries whose success rates differ: 1 is the
  reference, 0 every episode failed.
* **full-state bound** — the full-state LQR (``dlqr+none``, observing the true state without
  noise) on the same seeds: its success rate and mean J say what observation costs, the floor no
  estimator reaches.

The reference, the bound and every built-in entry are designed on the suite's design plant
(:func:`~pendulum_lqg.scoreboard.suites.design_plant`: the plant played where the suite fixes it,
the nominal MJCF where it randomises it), which each suite entry names (``designed_on``).

The score never uses the Gymnasium reward: only success and J.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from pendulum_lqg.boundary.schemas import SCORE_VERSION
from pendulum_lqg.core.metrics import mean_se, wilson_interval
from pendulum_lqg.errors import NotApplicable, PendulumLQGError
from pendulum_lqg.scoreboard.stats import failure_aware_figures
from pendulum_lqg.scoreboard.suites import Suite

__all__ = ["SCORE_VERSION", "optimality_gap", "score_document", "score_entry", "success_figures",
           "suite_figures", "suite_score"]
#: Paired bootstrap resamples of the gap's interval, and their seed.
BOOTSTRAP_RESAMPLES, BOOTSTRAP_SEED = 2000, 0
#: The full-state LQR whose figures bound what observation costs.
FULL_STATE_POLICY = "dlqr+none"


def success_figures(rows: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """Success rate with its Wilson interval, mean J of the successes with its standard error."""
    n = len(rows)
    wins = sum(bool(r["success"]) for r in rows)
    lo, hi = wilson_interval(wins, n)
    mean, se = mean_se(np.array([r["cost"] for r in rows if r["success"]], dtype=float))
    return {"episodes": n, "successes": wins, "success_rate": wins / n if n else math.nan,
            "success_ci": [lo, hi], "cost_mean": _finite(mean), "cost_se": _finite(se)}


def optimality_gap(rows: Sequence[dict[str, Any]], reference: Sequence[dict[str, Any]],
                   ) -> dict[str, Any]:
    """The gap to ``reference`` on the episodes both survived, with its paired bootstrap interval
    (see the module docstring). Rows are matched by ``episode``."""
    ref = {r["episode"]: r for r in reference}
    both = [(r["cost"], ref[r["episode"]]["cost"]) for r in rows
            if r["success"] and r["episode"] in ref and ref[r["episode"]]["success"]]
    if not both:
        return {"optimality_gap": None, "gap_ci": [None, None], "gap_episodes": 0}
    j, j_ref = np.array(both, dtype=float).T
    gap = float(j.mean() / j_ref.mean() - 1.0)
    rng = np.random.default_rng(BOOTSTRAP_SEED)
    idx = rng.integers(0, j.size, size=(BOOTSTRAP_RESAMPLES, j.size))
    gaps = j[idx].mean(axis=1) / j_ref[idx].mean(axis=1) - 1.0
    lo, hi = np.percentile(gaps, [2.5, 97.5])
    return {"optimality_gap": gap, "gap_ci": [float(lo), float(hi)], "gap_episodes": int(j.size)}


def suite_score(suite: Suite, rows: Sequence[dict[str, Any]], reference: Sequence[dict[str, Any]],
                bound: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """One suite's entry of a score file (see :func:`score_document`)."""
    if [r["episode"] for r in rows] != list(range(suite.episodes)):
        raise ValueError(f"suite {suite.name!r}: the rows are not episodes 0 … {suite.episodes - 1}")
    out = suite_figures(rows, reference, bound, reference_policy=suite.reference)
    out["version"] = suite.version
    out["fingerprint"] = suite.fingerprint()
    out["designed_on"] = suite.designed_on
    out["rows"] = [dict(r) for r in rows]
    return out


def suite_figures(rows: Sequence[dict[str, Any]], reference: Sequence[dict[str, Any]],
                  bound: Sequence[dict[str, Any]], *, reference_policy: str) -> dict[str, Any]:
    """The figures of one suite's entry (success, J, gap, failure-aware score) and those of its
    ``reference`` and full-state ``bound``, for any suite (cart-pole or LTI)."""
    out = {**success_figures(rows), **optimality_gap(rows, reference),
           **failure_aware_figures(rows, reference)}
    ref = success_figures(reference)
    out["reference"] = {"policy": reference_policy, "success_rate": ref["success_rate"],
                        "cost_mean": ref["cost_mean"]}
    full = success_figures(bound)
    out["full_state_bound"] = {"policy": FULL_STATE_POLICY, "success_rate": full["success_rate"],
                               "cost_mean": full["cost_mean"]}
    return out


def score_document(policy: str, kind: str, suites: Sequence[Suite],
                   rows_of: Callable[[Suite], list[dict[str, Any]]],
                   reference_of: Callable[[Suite], list[dict[str, Any]]],
                   bound_of: Callable[[Suite], list[dict[str, Any]]],
                   versions: dict[str, str],
                   on_suite: Callable[[str], None] | None = None,
                   run: dict[str, Any] | None = None) -> dict[str, Any]:
    """The score file of ``policy``: ``{"policy", "kind", "score_version", "versions", "suites":
    {name: {"applicable", "episodes", "success_rate", "success_ci", "cost_mean", "cost_se",
    "optimality_gap", "gap_ci", "gap_episodes", "score_mean", "score_ci", "reference",
    "full_state_bound", "version", "fingerprint", "designed_on", "rows"}}}`` (``score_entry``
    adds ``exact``, :func:`~pendulum_lqg.scoreboard.exact.exact_entry`, for a linear controller
    file or a built-in policy) (``designed_on``:
    what the reference and the built-in designs are designed on,
    :func:`~pendulum_lqg.scoreboard.suites.designed_on`), and the ``run`` keys (``method``,
    ``seed``: one training run of a method, which ``board`` aggregates) where given; a suite the
    entry cannot play as posed (:class:`~pendulum_lqg.scoreboard.episodes.NotApplicable`) has
    ``"applicable": false`` and the ``"reason"`` instead of the figures. ``kind`` is
    ``"builtin"``, ``"plugin"`` or ``"agent"``;
    ``on_suite(name)`` is told when each suite is done (progress)."""
    entries: dict[str, Any] = {}
    for s in suites:
        # the suite's own rows first: an error there (its model file, a reference its [env]
        # cannot design) names the suite's file, not the entry scored on it
        try:
            reference_of(s)
            bound_of(s)
        except PendulumLQGError as exc:
            raise s.errors_named(f"its reference {s.reference!r}", exc) from None
        try:
            rows = rows_of(s)
        except NotApplicable as exc:        # a row that says why, not a number
            entries[s.name] = {"applicable": False, "reason": str(exc), "episodes": s.episodes,
                               "version": s.version, "fingerprint": s.fingerprint(),
                               "designed_on": s.designed_on}
        else:
            entries[s.name] = {"applicable": True,
                               **suite_score(s, rows, reference_of(s), bound_of(s))}
        if on_suite is not None:
            on_suite(s.name)
    return {"policy": policy, "kind": kind, "score_version": SCORE_VERSION, "versions": versions,
            **(run or {}), "suites": entries}


def score_entry(suites: Sequence[Suite], *, policy: str | None = None, agent: str | None = None,
                normalize_action: bool = False, nthread: int | None = None,
                base_dir: Path | None = None,
                cache: dict[tuple[str, str, str], list[dict[str, Any]]] | None = None,
                on_suite: Callable[[str], None] | None = None,
                noise_scale: float | None = None) -> dict[str, Any]:
    """The score file of one entry — a built-in or plug-in ``policy`` (the batch path), or a
    Gymnasium ``agent`` reference (the env path) — on ``suites``: what ``pendulum-lqg score``
    writes. ``cache`` (suite fingerprint, kind, policy) → rows keeps the references' and the
    full-state bounds' rows between entries (the leaderboard scores many entries at once; the
    rows are the same ones either way); ``on_suite(name)`` is told when a suite is done;
    ``noise_scale`` plays every suite at that noise (the noise ladder:
    :meth:`~pendulum_lqg.scoreboard.suites.Suite.with_noise_scale`) and is written into the
    score file."""
    from pendulum_lqg.bench.results import versions
    from pendulum_lqg.errors import ConfigError
    from pendulum_lqg.policies.loading import guard, is_plugin_ref
    from pendulum_lqg.scoreboard import episodes as ep

    if (policy is None) == (agent is None):
        raise ConfigError("score: give one POLICY or one --agent REF")
    suites = [s.with_noise_scale(noise_scale) for s in suites]
    memo: dict[tuple[str, str, str], list[dict[str, Any]]] = {} if cache is None else cache

    def cached(s: Suite, kind: str, name: str,
               run: Callable[[], list[dict[str, Any]]]) -> list[dict[str, Any]]:
        key = (s.fingerprint(), kind, name)
        if key not in memo:
            memo[key] = run()
        return memo[key]

    def reference_of(s: Suite) -> list[dict[str, Any]]:
        return cached(s, "policy", s.reference,
                      lambda: ep.policy_rows(s, s.reference, nthread=nthread))

    def bound_of(s: Suite) -> list[dict[str, Any]]:
        return cached(s, "bound", FULL_STATE_POLICY,
                      lambda: ep.full_state_rows(s, nthread=nthread))

    rows_of: Callable[[Suite], list[dict[str, Any]]]
    factory: Any = None
    if agent is not None:
        factory = ep.load_agent(agent, base_dir=base_dir)
        normalized = normalize_action or guard(
            f"agent {agent!r}", "reading normalize_action",
            lambda: bool(getattr(factory, "normalize_action", False)))
        name, kind = agent, "agent"
        run, extra_versions = _run_of(factory)
        rows_of = _agent_rows_of(agent, factory, normalized, nthread)
    else:
        assert policy is not None
        if not policy:
            raise ConfigError("policy: expected 'controller+observer' or a plug-in MODULE:ATTR, got ''")
        name, kind = policy, ("plugin" if is_plugin_ref(policy) else "builtin")
        run, extra_versions = _run_of(None)
        rows_of = _policy_rows_of(policy, kind, reference_of, base_dir, nthread)
    doc = score_document(name, kind, suites, rows_of, reference_of, bound_of,
                         {**versions(), **extra_versions}, on_suite, run)
    _add_exact(doc, suites, factory=factory, policy=policy if kind == "builtin" else None)
    return doc if noise_scale is None else {**doc, "noise_scale": noise_scale}


def _add_exact(doc: dict[str, Any], suites: Sequence[Suite], *, factory: Any,
               policy: str | None) -> None:
    """Each applicable suite entry's ``exact``: the exact stationary J and gap of a linear
    controller file or a built-in policy on the suite's plant linearised
    (:func:`~pendulum_lqg.scoreboard.exact.exact_entry`, ``{"reason"}`` where the theory has no
    single linear loop); nothing for plug-ins and other agents."""
    from pendulum_lqg.scoreboard.exact import exact_entry
    from pendulum_lqg.scoreboard.linear import LinearFactory

    doc_of = factory.doc if isinstance(factory, LinearFactory) else None
    if doc_of is None and policy is None:
        return
    for s in suites:
        entry = doc["suites"][s.name]
        if entry.get("applicable"):
            entry["exact"] = exact_entry(s, doc=doc_of, policy=policy)


def _policy_rows_of(policy: str, kind: str, reference_of: Callable[[Suite], list[dict[str, Any]]],
                    base_dir: Path | None, nthread: int | None,
                    ) -> Callable[[Suite], list[dict[str, Any]]]:
    """The rows of a built-in or plug-in ``policy`` on a suite (the batch path); the suite's
    reference itself is the reference's one run."""
    from pendulum_lqg.scoreboard import episodes as ep

    def rows_of(s: Suite) -> list[dict[str, Any]]:
        if kind == "builtin" and policy == s.reference:
            return reference_of(s)
        return ep.policy_rows(s, policy, base_dir=base_dir, nthread=nthread)

    return rows_of


def _run_of(factory: Any) -> tuple[dict[str, Any] | None, dict[str, str]]:
    """An sb3 model's or a linear controller's run (method, seed, the file's sha256), and the
    libraries' versions an sb3 model depends on."""
    from pendulum_lqg.scoreboard.linear import LinearFactory
    from pendulum_lqg.scoreboard.sb3 import SB3Factory

    if isinstance(factory, SB3Factory):
        return factory.run, factory.versions
    if isinstance(factory, LinearFactory):
        return factory.run, {}
    return None, {}


def _agent_rows_of(agent: str, factory: Any, normalized: bool, nthread: int | None,
                   ) -> Callable[[Suite], list[dict[str, Any]]]:
    """The rows of an agent on a suite: an sb3 model batched (all episodes at once, one predict
    per control period), a linear controller through the core's batch, any other agent one
    episode after another."""
    from pendulum_lqg.scoreboard import episodes as ep
    from pendulum_lqg.scoreboard.linear import LinearFactory, linear_rows
    from pendulum_lqg.scoreboard.sb3 import SB3Factory

    def rows_of(s: Suite) -> list[dict[str, Any]]:
        if isinstance(factory, LinearFactory):
            return linear_rows(s, factory.doc, name=factory.name, nthread=nthread)
        if isinstance(factory, SB3Factory):
            from pendulum_lqg.scoreboard.sb3_batch import batched_rows

            return batched_rows(s, factory, normalize_action=normalized)
        return ep.agent_rows(s, factory, name=agent, normalize_action=normalized)
    return rows_of


def _finite(value: float) -> float | None:
    return None if not math.isfinite(value) else float(value)
