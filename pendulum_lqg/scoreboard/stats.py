"""Statistics that compare agents across training runs: the failure-aware score and its aggregates.

The survivor gap of :mod:`pendulum_lqg.scoreboard.score` is conditional on survival: an agent that
keeps only its easiest 10 % of episodes alive can show a small gap. Comparing agents whose success
rates differ needs a per-episode score that counts a failure.

**Failure-aware score.** On episode ``i`` of a suite, with ``J_i`` the entry's cost and
``J_ref,i`` the suite reference's cost on the same seed::

    s_i = J_ref,i / J_i   if the entry survived episode i,      s_i = 0   if it failed.

1 is "as good as the reference on this episode", above 1 better, 0 a failure; a run's score on a
suite is the mean of ``s_i`` over the suite's episodes. Where the reference itself failed on episode
``i`` (it has no ``J_ref,i``), the reference's mean J over the episodes it survived stands in; where
the reference survived no episode the score is undefined (``nan``).

**Aggregates over runs** (training seeds), as recommended by Agarwal et al., *Deep RL at the edge of
the statistical precipice* (NeurIPS 2021) and implemented in their library rliable:

* the interquartile mean (IQM): the mean of the middle 50 % of all run × suite scores;
* stratified bootstrap confidence intervals: runs are resampled with replacement *within each suite*
  and the statistic recomputed; the percentile interval of the resampled statistics;
* the performance profile: the share of run × suite scores above each threshold ``τ``;
* the probability of improvement ``P(X > Y)``: per suite, the Mann–Whitney probability that a run of
  X scores above a run of Y (ties count one half), averaged over the suites.

Arrays of scores are ``(runs, suites)``: one row per training run, one column per suite.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

#: Bootstrap resamples and seed of :func:`stratified_bootstrap_ci` (a fixed seed: reproducible).
BOOTSTRAP_RESAMPLES, BOOTSTRAP_SEED = 2000, 0


def failure_aware_scores(rows: Sequence[dict[str, Any]],
                         reference: Sequence[dict[str, Any]]) -> np.ndarray:
    """The per-episode failure-aware scores ``s_i`` of ``rows`` against ``reference`` (see the
    module docstring). Rows are matched by ``episode``; every episode of ``rows`` must be in
    ``reference``."""
    ref = {r["episode"]: r for r in reference}
    missing = [r["episode"] for r in rows if r["episode"] not in ref]
    if missing:
        raise ValueError(f"reference: no row for episode {missing[0]}")
    survived = [float(r["cost"]) for r in reference if r["success"]]
    fallback = float(np.mean(survived)) if survived else math.nan
    out = np.zeros(len(rows))
    for i, r in enumerate(rows):
        if not r["success"]:
            continue                    # a failed episode scores 0
        mate = ref[r["episode"]]
        j_ref = float(mate["cost"]) if mate["success"] else fallback
        out[i] = j_ref / float(r["cost"])
    return out


def failure_aware_figures(rows: Sequence[dict[str, Any]],
                          reference: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """A suite entry's ``score_mean`` — the mean of :func:`failure_aware_scores` over its episodes —
    and ``score_ci``, its 95 % percentile bootstrap interval over the episodes
    (:data:`BOOTSTRAP_RESAMPLES` resamples, :data:`BOOTSTRAP_SEED`: reproducible). Both are
    ``None`` where the score is undefined (the reference survived no episode, or no rows)."""
    if not rows or not any(r["success"] for r in reference):
        return {"score_mean": None, "score_ci": [None, None]}
    s = failure_aware_scores(rows, reference)
    rng = np.random.default_rng(BOOTSTRAP_SEED)
    means = s[rng.integers(0, s.size, size=(BOOTSTRAP_RESAMPLES, s.size))].mean(axis=1)
    lo, hi = np.percentile(means, [2.5, 97.5])
    return {"score_mean": float(s.mean()), "score_ci": [float(lo), float(hi)]}


def as_runs_by_suites(scores: Any) -> np.ndarray:
    """``scores`` as a float ``(runs, suites)`` array; a 1-D array is one suite's runs."""
    x = np.asarray(scores, dtype=float)
    if x.ndim == 1:
        return x[:, None]
    if x.ndim != 2:
        raise ValueError(f"scores: expected a (runs, suites) array, got shape {x.shape}")
    return x


def interquartile_means(rows: np.ndarray) -> np.ndarray:
    """The interquartile mean of each row of a ``(k, n)`` array: the mean of its middle 50 %
    (25 % trimmed from each end, as rliable's IQM and :func:`scipy.stats.trim_mean` with
    ``proportiontocut=0.25``). Rows at once, for the bootstrap's resamples."""
    flat = np.sort(np.asarray(rows, dtype=float), axis=1)
    n = flat.shape[1]
    if n == 0:
        return np.full(flat.shape[0], math.nan)
    cut = int(0.25 * n)
    return flat[:, cut:n - cut].mean(axis=1)


def interquartile_mean(scores: np.ndarray) -> float:
    """The mean of the middle 50 % of all scores (:func:`interquartile_means` of one row)."""
    return float(interquartile_means(np.asarray(scores, dtype=float).reshape(1, -1))[0])


def stratified_bootstrap_ci(scores: np.ndarray, statistic: Callable[[np.ndarray], Any],
                            *, resamples: int = BOOTSTRAP_RESAMPLES, seed: int = BOOTSTRAP_SEED,
                            level: float = 0.95, vectorized: bool = False) -> tuple[float, float]:
    """The percentile interval of ``statistic`` over stratified bootstrap resamples of the
    ``(runs, suites)`` array ``scores``: in each resample, every suite's column gets its own draw of
    runs with replacement (the suites are the strata).

    ``statistic`` maps one ``(runs, suites)`` resample to a number; with ``vectorized=True`` it is
    called once, on all resamples stacked as ``(resamples, runs, suites)``, and returns one number
    per resample (as :func:`scipy.stats.bootstrap`'s ``vectorized``) — the same draws either way.
    """
    x = as_runs_by_suites(scores)
    runs, suites = x.shape
    if runs == 0:
        return math.nan, math.nan
    rng = np.random.default_rng(seed)
    idx = rng.integers(0, runs, size=(resamples, runs, suites))
    samples = x[idx, np.arange(suites)]
    if vectorized:
        stats = np.asarray(statistic(samples), dtype=float)
        if stats.shape != (resamples,):
            raise ValueError(f"statistic: expected one value per resample, shape ({resamples},), "
                             f"got {stats.shape}")
    else:
        stats = np.array([statistic(sample) for sample in samples])
    tail = 100 * (1 - level) / 2
    lo, hi = np.percentile(stats, [tail, 100 - tail])
    return float(lo), float(hi)


def performance_profile(scores: np.ndarray, taus: np.ndarray) -> np.ndarray:
    """The share of run × suite scores strictly above each threshold in ``taus``."""
    flat = np.asarray(scores, dtype=float).ravel()
    return (flat[None, :] > np.asarray(taus, dtype=float)[:, None]).mean(axis=1)


def probability_of_improvement(x: np.ndarray, y: np.ndarray) -> float:
    """``P(X > Y)``: per suite, the probability that a random run of ``x`` scores above a random
    run of ``y`` (ties count ½; the Mann–Whitney U statistic over ``n·m``), averaged over the suites.
    ``x`` and ``y`` are ``(runs, suites)`` arrays with the same suites (their run counts may
    differ)."""
    a, b = as_runs_by_suites(x), as_runs_by_suites(y)
    if a.shape[1] != b.shape[1]:
        raise ValueError(f"y: expected {a.shape[1]} suites like x, got {b.shape[1]}")
    per_suite = [float(np.mean((a[:, k, None] > b[None, :, k]) + 0.5 * (a[:, k, None] == b[None, :, k])))
                 for k in range(a.shape[1])]
    return float(np.mean(per_suite))


def probability_of_improvement_ci(x: np.ndarray, y: np.ndarray, *,
                                  resamples: int = BOOTSTRAP_RESAMPLES, seed: int = BOOTSTRAP_SEED,
                                  level: float = 0.95) -> tuple[float, float]:
    """The percentile interval of :func:`probability_of_improvement` over stratified bootstrap
    resamples: in each, the runs of ``x`` and of ``y`` are drawn with replacement within each
    suite, independently (rliable's two-sample stratified bootstrap)."""
    a, b = as_runs_by_suites(x), as_runs_by_suites(y)
    rng = np.random.default_rng(seed)
    cols_a, cols_b = np.arange(a.shape[1]), np.arange(b.shape[1])
    stats = [probability_of_improvement(
                 a[rng.integers(0, a.shape[0], size=a.shape), cols_a],
                 b[rng.integers(0, b.shape[0], size=b.shape), cols_b])
             for _ in range(resamples)]
    tail = 100 * (1 - level) / 2
    lo, hi = np.percentile(stats, [tail, 100 - tail])
    return float(lo), float(hi)


def aggregate(scores: np.ndarray) -> dict[str, Any]:
    """IQM and mean of a ``(runs, suites)`` array with their stratified bootstrap 95 % intervals:
    the figures a board row shows for one method."""
    x = as_runs_by_suites(scores)
    return {"runs": x.shape[0],
            "iqm": interquartile_mean(x),
            "iqm_ci": list(stratified_bootstrap_ci(x, lambda s: interquartile_means(_rows(s)),
                                                   vectorized=True)),
            "mean": float(np.mean(x)),
            "mean_ci": list(stratified_bootstrap_ci(x, lambda s: _rows(s).mean(axis=1),
                                                    vectorized=True))}


def _rows(samples: np.ndarray) -> np.ndarray:
    """Stacked ``(k, runs, suites)`` resamples as ``(k, runs · suites)`` rows."""
    return samples.reshape(samples.shape[0], -1)
