"""Batch seeding (pendulum_lqg.core.seeding) against NumPy's own SeedSequence, value for value."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from pendulum_lqg.core.seeding import (
    child_generator,
    episode_generators,
    episode_seed,
    episode_seeds,
)
from pendulum_lqg.errors import ConfigError

# one-, two- and five-word run seeds (a spawn key pads the run entropy to four words first)
SEEDS = [0, 1, 7, 2**31, 2**32 - 1, 2**32, 2**40 + 3, 2**130 + 5]


@pytest.mark.parametrize("seed", SEEDS)
def test_episode_seeds_equal_numpy_spawn(seed):
    episodes = [*range(200), 2**31, 2**32 - 1]
    expected = [int(np.random.SeedSequence(seed).spawn(e + 1)[e].generate_state(1)[0])
                for e in (0, 1, 199)]
    got = episode_seeds(seed, episodes)
    assert got == [episode_seed(seed, e) for e in episodes]
    assert [got[0], got[1], got[199]] == expected
    assert len(set(got)) == len(got)


def test_episode_seeds_two_word_episode_and_empty():
    assert episode_seeds(3, [5, 2**33]) == [episode_seed(3, 5), episode_seed(3, 2**33)]
    assert episode_seeds(3, []) == []
    assert episode_seeds(3, np.arange(4)) == [episode_seed(3, e) for e in range(4)]


def test_episode_generators_equal_default_rng():
    seeds = [0, 1, 2**32 - 1, *episode_seeds(11, range(300))]
    for s, g in zip(seeds, episode_generators(seeds), strict=True):
        ref = np.random.default_rng(s)
        assert g.bit_generator.state == ref.bit_generator.state
        assert np.array_equal(g.standard_normal(7), ref.standard_normal(7))
        assert np.array_equal(g.random(3), ref.random(3))


def test_generators_spawn_pickle_and_attributes_as_numpy():
    s = episode_seed(4, 2)
    (g,) = episode_generators([s])
    ref = np.random.default_rng(s)
    g.standard_normal(5), ref.standard_normal(5)
    # the child stream of randomisation and dropouts, twice (the second child differs)
    for _ in range(2):
        assert np.array_equal(child_generator(g).random(4), child_generator(ref).random(4))
    seq, ref_seq = g.bit_generator.seed_seq, ref.bit_generator.seed_seq
    assert seq.entropy == ref_seq.entropy == s
    assert seq.n_children_spawned == ref_seq.n_children_spawned == 2
    assert np.array_equal(seq.generate_state(4), ref_seq.generate_state(4))
    g2 = pickle.loads(pickle.dumps(g))
    assert isinstance(g2.bit_generator.seed_seq, np.random.SeedSequence)
    assert np.array_equal(g2.random(4), ref.random(4))
    assert np.array_equal(child_generator(g2).random(2), child_generator(ref).random(2))


def test_large_seeds_take_numpy_path():
    seeds = [2**32, 2**40 + 1]
    for s, g in zip(seeds, episode_generators(seeds), strict=True):
        assert np.array_equal(g.random(3), np.random.default_rng(s).random(3))


@pytest.mark.parametrize("bad", [-1, True, 1.5, "3"])
def test_bad_seed_one_line_error(bad):
    with pytest.raises(ConfigError, match="seed: expected a non-negative integer"):
        episode_seeds(bad, [0])
    with pytest.raises(ConfigError, match="seed: expected a non-negative integer"):
        episode_generators([bad])


def test_negative_episode_rejected():
    with pytest.raises(ConfigError, match="episodes: expected non-negative integers"):
        episode_seeds(0, [3, -1])
