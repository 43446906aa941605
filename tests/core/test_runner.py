"""run_episodes' own checks (issue 45): the number of episodes is bounded before anything is
allocated, and an empty or non-integer list of episodes is named as such — the Python API is
protected as the CLI is."""

from __future__ import annotations

import tracemalloc

import pytest

from pendulum_lqg.core.runner import run_episodes
from pendulum_lqg.core.scenario import Scenario
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.policies.loading import build_policy
from pendulum_lqg.util.limits import MAX_BATCH_EPISODES, MAX_RECORDED_EPISODES


@pytest.fixture(scope="module")
def setup(plant):
    scenario = Scenario(duration=0.2)
    return plant, scenario, build_policy("dlqr+kalman", plant=plant, scenario=scenario)


@pytest.fixture(scope="module")
def plant():
    from pendulum_lqg.model.plant import load_plant

    return load_plant()


class Huge:
    """A sequence of ``n`` episode numbers that fails the test if more than ``allowed`` of them
    are ever read (``range(10**9)`` as a caller would pass it, made safe to run against code that
    materialises it)."""

    def __init__(self, n: int, allowed: int) -> None:
        self.n, self.allowed, self.read = n, allowed, 0

    def __len__(self) -> int:
        return self.n

    def __iter__(self):
        for i in range(self.n):
            self.read += 1
            if self.read > self.allowed:
                raise AssertionError(f"read {self.read:,} episode numbers of {self.n:,}")
            yield i


def test_run_episodes_refuses_a_billion_episodes_before_allocating(setup):
    plant, scenario, policy = setup
    tracemalloc.start()
    try:
        with pytest.raises(ConfigError, match=r"^episodes: at most 100,000 \(.*\), got "
                                              r"1,000,000,000$"):
            run_episodes(plant, scenario, policy, seed=0, episodes=Huge(10**9, allowed=0))
        with pytest.raises(ConfigError, match=r"^episodes: at most 100,000 .*got 1,000,000,000$"):
            run_episodes(plant, scenario, policy, seed=0, episodes=range(10**9))
        # an iterable without a length is read one past the ceiling, no further
        source = iter(Huge(10**9, allowed=MAX_BATCH_EPISODES + 1))
        with pytest.raises(ConfigError, match=r"^episodes: at most 100,000 .*got more$"):
            run_episodes(plant, scenario, policy, seed=0, episodes=(e for e in source))
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 64 * 2**20, peak       # the ceiling's worth of ints at most, not 10⁹ rows
    # trajectories keep every period: the ceiling of run --record
    with pytest.raises(ConfigError, match=r"^episodes: at most 1,000 \(trajectory=True"):
        run_episodes(plant, scenario, policy, seed=0, episodes=range(MAX_RECORDED_EPISODES + 1),
                     trajectory=True)


def test_run_episodes_at_the_ceiling_is_allowed(setup):
    from pendulum_lqg.util.limits import check_episodes

    assert check_episodes(range(MAX_BATCH_EPISODES)) == list(range(MAX_BATCH_EPISODES))
    assert check_episodes(range(3, MAX_RECORDED_EPISODES + 3), trajectory=True)[-1] == 1002


@pytest.mark.parametrize("empty", [[], range(0), (), iter([])], ids=["list", "range", "tuple",
                                                                     "iterator"])
def test_run_episodes_empty_range_says_so(setup, empty):
    plant, scenario, policy = setup
    with pytest.raises(ConfigError) as err:
        run_episodes(plant, scenario, policy, seed=0, episodes=empty)
    assert str(err.value) == ("episodes: expected at least one episode number, got an empty "
                              "collection")


@pytest.mark.parametrize("bad", [[0, 1.5], ["3"], [None]])
def test_run_episodes_refuses_episode_numbers_that_are_not_integers(setup, bad):
    plant, scenario, policy = setup
    with pytest.raises(ConfigError, match=r"^episodes: expected integer episode numbers, got "):
        run_episodes(plant, scenario, policy, seed=0, episodes=bad)


def test_run_episodes_still_runs_the_episodes_it_is_given(setup):
    """The check changes nothing for a valid list: the same rows as episode by episode."""
    import numpy as np

    plant, scenario, policy = setup
    batch = run_episodes(plant, scenario, policy, seed=3, episodes=np.array([4, 0, 2]))
    one = [run_episodes(plant, scenario, policy, seed=3, episodes=[e]).rows[0] for e in (4, 0, 2)]
    assert [r["episode"] for r in batch.rows] == [4, 0, 2]
    assert [r["cost"] for r in batch.rows] == [r["cost"] for r in one]


def test_experiment_chunk_above_the_batch_ceiling_is_refused():
    """A work unit is one run_episodes batch: a chunk the runner would refuse mid-sweep is
    refused when the experiment is read."""
    from pendulum_lqg.bench.experiments import parse_spec

    with pytest.raises(ConfigError, match=r"^chunk: at most 100,000 \(episodes per work unit"):
        parse_spec({"episodes": 10, "chunk": MAX_BATCH_EPISODES + 1})
    assert parse_spec({"episodes": 10, "chunk": MAX_BATCH_EPISODES}).chunk == MAX_BATCH_EPISODES
