"""Episode seeds and generators: where every random number of a run comes from.

Episode ``e`` of a run seeded ``s`` draws everything from ``numpy.random.default_rng(
episode_seed(s, e))``: the initial state, then the noise blocks (:mod:`pendulum_lqg.core.noise`),
and — only when a scenario randomises parameters or drops samples — a child stream
(:func:`child_generator`). So one episode can be replayed alone, in a batch of any size, or through
the Gymnasium environment (``env.reset(seed=episode_seed(s, e))`` makes the same generator).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from pendulum_lqg.errors import ConfigError


def _check_seed(seed: object) -> int:
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ConfigError(f"seed: expected a non-negative integer, got {seed!r}")
    return int(seed)


def episode_seed(seed: int, episode: int) -> int:
    """The integer seed of episode ``episode`` of a run seeded with ``seed``.

    Derived with ``SeedSequence(seed).spawn``: equal to ``SeedSequence(seed).spawn(N)[episode]``'s
    first word, for any N. ``numpy.random.default_rng(episode_seed(s, k))`` is the generator of that
    episode — and also what ``gymnasium.Env.reset(seed=episode_seed(s, k))`` makes, so the same
    episode can be replayed alone, in a batch, or through the gymnasium environment.
    """
    seq = np.random.SeedSequence(_check_seed(seed), spawn_key=(int(episode),))
    return int(seq.generate_state(1, dtype=np.uint32)[0])


def child_generator(generator: np.random.Generator) -> np.random.Generator:
    """The episode's child stream: ``generator.spawn(1)[0]``.

    Drawn from only when a scenario randomises parameters or drops samples, so the episode's own
    generator — the initial state, then the noise blocks — draws exactly what it draws without
    those features. The child is made at the episode's reset and draws, in order: the three
    uniforms of :class:`~pendulum_lqg.model.overrides.Randomization` (if any range is given), then one
    uniform per control period for the dropouts (if ``dropout > 0``), in blocks. Spawning does not
    advance the parent; it depends only on the parent's seed sequence and on how many children it
    spawned before, so ``default_rng(s)`` and ``gymnasium``'s ``reset(seed=s)`` give the same child.
    """
    try:
        return generator.spawn(1)[0]
    except (AttributeError, TypeError, ValueError) as exc:
        raise ConfigError("generators: randomize/dropout need generators made from a seed "
                          "(numpy.random.default_rng(seed)), which can spawn a child stream"
                          ) from exc


def episode_seeds(seed: int, episodes: Sequence[int] | np.ndarray) -> list[int]:
    """``[episode_seed(seed, e) for e in episodes]``."""
    seed = _check_seed(seed)
    eps = [int(e) for e in episodes]
    if eps and min(eps) < 0:
        raise ConfigError(f"episodes: expected non-negative integers, got {min(eps)}")
    return [episode_seed(seed, e) for e in eps]


def episode_generators(seeds: Sequence[int]) -> list[np.random.Generator]:
    """``[numpy.random.default_rng(s) for s in seeds]``: each episode's own generator."""
    return [np.random.default_rng(_check_seed(s)) for s in seeds]
