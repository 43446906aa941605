"""``perf``: the baseline is the faster bare physics, the ratio the median of the pair ratios."""

from __future__ import annotations

import statistics
import time

import pytest

from pendulum_lqg.bench.perf import raw_batch_rate, run_perf, shard_idle


def test_perf_baseline_is_the_faster_bare_physics_and_the_ratio_the_median_of_pairs():
    """The faster call is chosen by its median, then used pair by pair (a per-pair maximum of two
    equally fast calls would bias the baseline upwards by the noise)."""
    out = run_perf(episodes=16, duration=0.1, nthread=1, repeats=3)
    assert len(out["raw_steps_per_s"]) == len(out["closed_loop_steps_per_s"]) == 3
    # the baseline is one call's runs throughout: the call with the higher median
    series = {"rollout": out["bare_rollout_steps_per_s"], "batch": out["bare_batch_steps_per_s"]}
    faster = max(series, key=lambda name: statistics.median(series[name]))
    assert out["bare_baseline"] == faster
    assert out["raw_steps_per_s"] == series[faster] and min(series[faster]) > 0
    assert statistics.median(series[faster]) >= max(statistics.median(v) for v in series.values())
    pairs = [c / r for c, r in zip(out["closed_loop_steps_per_s"], out["raw_steps_per_s"],
                                   strict=True)]
    assert out["pair_ratios"] == pairs
    assert out["ratio"] == statistics.median(pairs)
    assert out["episodes"] == 16 and out["steps_per_period"] == 10 and out["repeats"] == 3
    assert any("target ≥ 0.90" in line for line in out["report"])
    assert out["shards"] == 1 and out["shard_idle_fraction"] == [0.0, 0.0, 0.0]


def test_shard_idle_is_the_thread_time_spent_waiting_for_the_last_shard():
    """Two shards ending at 9 s and 10 s: one thread waits 1 s of the 2 × 10 s → 5 %."""
    assert shard_idle([(0.0, 9.0), (0.5, 10.0)]) == pytest.approx(0.05)
    assert shard_idle([(0.0, 4.0), (0.0, 4.0), (0.0, 2.0)]) == pytest.approx(2 / 12)
    assert shard_idle([(0.0, 3.0)]) == 0.0 and shard_idle([]) == 0.0



def test_raw_batch_rate_times_the_physics_only_not_the_python_gaps(plant):
    """With 20 ms of Python spun before each of 3 calls, the run lasts over 60 ms, but the rate
    counts only the calls' own time (4 simulations × 10 steps take well under 60 ms)."""
    t = time.perf_counter()
    rate = raw_batch_rate(plant, 4, 10, 1, calls=3, gap=0.02)
    assert time.perf_counter() - t >= 0.06
    assert 0 < 3 * 4 * 10 / rate < 0.02
