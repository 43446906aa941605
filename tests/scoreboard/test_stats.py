"""The failure-aware score and the across-run aggregates, checked against SciPy and closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats as sps

from pendulum_lqg.scoreboard import stats


def _rows(costs, success):
    return [{"episode": i, "cost": c, "success": s}
            for i, (c, s) in enumerate(zip(costs, success, strict=True))]


def test_failure_aware_score_is_the_cost_ratio_and_zero_on_failure():
    ref = _rows([10.0, 20.0, 30.0, 40.0], [True, True, False, True])
    entry = _rows([20.0, 10.0, 35.0, 80.0], [True, True, True, False])
    s = stats.failure_aware_scores(entry, ref)
    # episode 2: the reference failed, its mean surviving J (10+20+40)/3 stands in
    np.testing.assert_allclose(s, [0.5, 2.0, (70.0 / 3) / 35.0, 0.0])


def test_the_reference_scores_one_on_every_episode_it_survives():
    ref = _rows([12.5, 7.0, 3.3], [True, True, True])
    np.testing.assert_array_equal(stats.failure_aware_scores(ref, ref), [1.0, 1.0, 1.0])


def test_failure_aware_score_needs_the_reference_rows():
    with pytest.raises(ValueError, match="reference: no row for episode 1"):
        stats.failure_aware_scores(_rows([1.0, 2.0], [True, True]), _rows([1.0], [True]))


def test_failure_aware_score_is_nan_when_the_reference_never_survives():
    s = stats.failure_aware_scores(_rows([1.0], [True]), _rows([1.0], [False]))
    assert math.isnan(s[0])


@pytest.mark.parametrize("n", [4, 7, 20, 101])
def test_iqm_equals_scipy_trim_mean(n):
    x = np.random.default_rng(n).gamma(2.0, size=(n, 3))
    assert stats.interquartile_mean(x) == pytest.approx(sps.trim_mean(x.ravel(), 0.25), rel=1e-12)


def test_probability_of_improvement_equals_mann_whitney():
    rng = np.random.default_rng(1)
    x, y = rng.normal(0.3, 1.0, size=(9, 2)), rng.normal(0.0, 1.0, size=(6, 2))
    x[0, 0] = y[0, 0]                                            # one tie counts one half
    expected = np.mean([sps.mannwhitneyu(x[:, k], y[:, k]).statistic / (9 * 6) for k in range(2)])
    assert stats.probability_of_improvement(x, y) == pytest.approx(expected, rel=1e-12)
    assert stats.probability_of_improvement(x, x) == pytest.approx(0.5)


def test_bootstrap_interval_of_a_mean_matches_the_normal_interval():
    # many runs of one suite: the percentile bootstrap of the mean ≈ mean ± 1.96 s/√n
    x = np.random.default_rng(2).normal(1.0, 0.5, size=400)
    lo, hi = stats.stratified_bootstrap_ci(x, lambda s: float(np.mean(s)))
    half = 1.96 * x.std(ddof=1) / math.sqrt(x.size)
    assert lo == pytest.approx(x.mean() - half, abs=0.15 * half)
    assert hi == pytest.approx(x.mean() + half, abs=0.15 * half)


def test_bootstrap_resamples_within_each_suite():
    # suite 0 is constant, suite 1 varies: a stratified draw never moves suite 0's column mean
    x = np.column_stack([np.full(10, 3.0), np.arange(10.0)])
    lo, hi = stats.stratified_bootstrap_ci(x, lambda s: float(s[:, 0].mean()))
    assert (lo, hi) == (3.0, 3.0)
    lo, hi = stats.stratified_bootstrap_ci(x, lambda s: float(s[:, 1].mean()))
    assert lo < 4.5 < hi


def test_performance_profile_counts_scores_above_each_threshold():
    x = np.array([[0.0, 0.5], [1.0, 1.5]])
    np.testing.assert_array_equal(stats.performance_profile(x, [-1.0, 0.0, 0.75, 1.5]),
                                  [1.0, 0.75, 0.5, 0.0])


def test_aggregate_reports_iqm_and_mean_with_intervals():
    x = np.random.default_rng(3).uniform(size=(5, 7))
    agg = stats.aggregate(x)
    assert agg["runs"] == 5
    assert agg["iqm_ci"][0] <= agg["iqm"] <= agg["iqm_ci"][1]
    assert agg["mean"] == pytest.approx(x.mean())


def test_probability_of_improvement_interval_brackets_it_and_is_sure_of_a_clear_winner():
    rng = np.random.default_rng(4)
    x, y = rng.normal(0.5, 1.0, size=(5, 3)), rng.normal(0.0, 1.0, size=(5, 3))
    lo, hi = stats.probability_of_improvement_ci(x, y)
    assert lo <= stats.probability_of_improvement(x, y) <= hi and hi - lo > 0.1
    assert stats.probability_of_improvement_ci(x + 10.0, y) == (1.0, 1.0)
    assert stats.probability_of_improvement_ci(y, x + 10.0) == (0.0, 0.0)


@pytest.mark.parametrize("runs", [10, 40])
def test_the_iqm_interval_of_one_suite_matches_scipy_bootstrap(runs):
    # one suite: the stratified bootstrap is the plain one; scipy's percentile bootstrap of
    # trim_mean over the same runs gives the same interval up to resampling noise
    x = np.random.default_rng(runs).gamma(2.0, size=runs)
    ours = stats.stratified_bootstrap_ci(x, stats.interquartile_mean, resamples=4000)
    res = sps.bootstrap((x,), lambda v, axis=-1: sps.trim_mean(v, 0.25, axis=axis),
                        n_resamples=4000, method="percentile", random_state=1)
    scale = x.std() / np.sqrt(runs)
    assert ours[0] == pytest.approx(res.confidence_interval.low, abs=0.25 * scale)
    assert ours[1] == pytest.approx(res.confidence_interval.high, abs=0.25 * scale)


def test_a_vectorized_statistic_sees_the_same_resamples_as_the_per_resample_one():
    # aggregate() bootstraps with vectorized statistics; called one resample at a time, the same
    # rule over the same draws gives the same interval to the last bit
    x = np.random.default_rng(5).gamma(2.0, size=(7, 3)) * [1.0, 0.0, 2.0]
    one_by_one = (stats.stratified_bootstrap_ci(x, stats.interquartile_mean),
                  stats.stratified_bootstrap_ci(x, lambda s: float(np.mean(s))))
    agg = stats.aggregate(x)
    assert (tuple(agg["iqm_ci"]), tuple(agg["mean_ci"])) == one_by_one
    rows = np.array([[4.0, 1.0, 3.0, 2.0], [0.0, 0.0, 9.0, 1.0]])
    assert stats.interquartile_means(rows).tolist() == [2.5, 0.5]     # middle two of each row
    with pytest.raises(ValueError, match=r"statistic: expected one value per resample, shape \(2000,\)"):
        stats.stratified_bootstrap_ci(x, lambda s: s.mean(), vectorized=True)
