"""Episode seeds and generators: where every random number of a run comes from.

Episode ``e`` of a run seeded ``s`` draws everything from ``numpy.random.default_rng(
episode_seed(s, e))``: the initial state, then the noise blocks (:mod:`pendulum_lqg.noise`), and
— only when a scenario randomises parameters or drops samples — a child stream
(:func:`child_generator`). So one episode can be replayed alone, in a batch of any size, or through
the gymnasium environment (``env.reset(seed=episode_seed(s, e))`` makes the same generator).

A batch of 512 episodes made one at a time costs about 7 ms of Python — ``SeedSequence`` hashes
its entropy in a Python-level loop, twice per episode (the episode's seed, then its generator's
state) — and the threads of a sharded run do it at once, serialised by the GIL, before any physics
starts. :func:`episode_seeds` and :func:`episode_generators` give the same seeds and generators
with the hashing done once for the whole batch, as numpy ``uint32`` arithmetic: NumPy's
``SeedSequence`` algorithm (O'Neill's ``seed_seq`` alternative, which NumPy's stream-compatibility
policy keeps fixed), checked value for value against NumPy's own by the tests.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.random.bit_generator import ISpawnableSeedSequence

from pendulum_lqg.errors import ConfigError

# NumPy's SeedSequence constants (numpy/random/bit_generator.pyx)
_POOL = 4
_INIT_A, _MULT_A = 0x43B0D7E5, 0x931E8875
_INIT_B, _MULT_B = 0x8B51F9DD, 0x58F38DED
_MIX_L, _MIX_R = np.uint32(0xCA01F9DD), np.uint32(0x4973F715)
_MASK32 = 0xFFFFFFFF


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
    uniforms of :class:`~pendulum_lqg.plant.Randomization` (if any range is given), then one
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


def _words(n: int) -> list[int]:
    """``n`` ≥ 0 as little-endian 32-bit words (NumPy's ``_int_to_uint32_array``; 0 is ``[0]``)."""
    out = [n & _MASK32]
    n >>= 32
    while n:
        out.append(n & _MASK32)
        n >>= 32
    return out


class _HashConst:
    """The running hash constant of NumPy's ``hashmix``: the same sequence for every row, so a
    scalar serves the whole batch."""

    def __init__(self, init: int, mult: int) -> None:
        self.value, self.mult = init, mult

    def hashmix(self, v: np.ndarray) -> np.ndarray:
        v = v ^ np.uint32(self.value)
        self.value = (self.value * self.mult) & _MASK32
        v = v * np.uint32(self.value)
        return v ^ (v >> np.uint32(16))


def _mix(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    r: np.ndarray = np.subtract(_MIX_L * x, _MIX_R * y, dtype=np.uint32)
    return r ^ (r >> np.uint32(16))


def _pools(entropy: np.ndarray) -> np.ndarray:
    """The 4-word pools of ``SeedSequence`` for each row of ``entropy`` (rows, words) ``uint32``
    (the assembled entropy: run entropy, zero-padded to 4 words when a spawn key follows, then the
    spawn key)."""
    rows, length = entropy.shape
    h = _HashConst(_INIT_A, _MULT_A)
    zero = np.zeros(rows, dtype=np.uint32)
    mixer = [h.hashmix(entropy[:, i] if i < length else zero) for i in range(_POOL)]
    for src in range(_POOL):
        for dst in range(_POOL):
            if src != dst:
                mixer[dst] = _mix(mixer[dst], h.hashmix(mixer[src]))
    for src in range(_POOL, length):
        for dst in range(_POOL):
            mixer[dst] = _mix(mixer[dst], h.hashmix(entropy[:, src]))
    return np.stack(mixer, axis=1)


def _generate_state(pools: np.ndarray, n_words: int) -> np.ndarray:
    """``SeedSequence.generate_state(n_words, uint32)`` of each pool row → (rows, n_words)."""
    h = _HashConst(_INIT_B, _MULT_B)
    out = np.empty((pools.shape[0], n_words), dtype=np.uint32)
    for i in range(n_words):
        out[:, i] = h.hashmix(pools[:, i % _POOL])
    return out


def episode_seeds(seed: int, episodes: Sequence[int] | np.ndarray) -> list[int]:
    """``[episode_seed(seed, e) for e in episodes]``, hashed for the whole batch at once."""
    seed = _check_seed(seed)
    eps = [int(e) for e in episodes]
    if not eps:
        return []
    if min(eps) < 0:
        raise ConfigError(f"episodes: expected non-negative integers, got {min(eps)}")
    if max(eps) > _MASK32:                          # a two-word spawn key: NumPy's own path
        return [episode_seed(seed, e) for e in eps]
    run = _words(seed)
    run += [0] * (_POOL - len(run))                 # padded: a spawn key follows
    entropy = np.empty((len(eps), len(run) + 1), dtype=np.uint32)
    entropy[:, :-1] = run
    entropy[:, -1] = eps
    return _generate_state(_pools(entropy), 1)[:, 0].tolist()


class _PrecomputedSeedSequence(ISpawnableSeedSequence):
    """``SeedSequence(entropy)`` whose first ``generate_state(4, uint64)`` (what ``PCG64`` asks for
    when it is made) was computed with a batch; the real ``SeedSequence`` is made only if asked for
    anything else (``spawn`` for a child stream, its attributes, pickling)."""

    def __init__(self, entropy: int, pcg64_words: np.ndarray) -> None:
        self.entropy = entropy
        self._words: np.ndarray | None = pcg64_words
        self._seq: np.random.SeedSequence | None = None

    def _real(self) -> np.random.SeedSequence:
        if self._seq is None:
            self._seq = np.random.SeedSequence(self.entropy)
        return self._seq

    def generate_state(self, n_words: int, dtype: Any = np.uint32) -> np.ndarray:
        words, self._words = self._words, None
        if words is not None and n_words == 4 and np.dtype(dtype) == np.uint64:
            return words
        return self._real().generate_state(n_words, dtype)

    def spawn(self, n_children: int) -> list[np.random.SeedSequence]:  # type: ignore[override]
        # NumPy's own children, as SeedSequence(entropy).spawn gives them
        return self._real().spawn(n_children)

    def __getattr__(self, name: str) -> Any:          # spawn_key, pool, n_children_spawned, …
        if name.startswith("_"):
            raise AttributeError(name)
        return getattr(self._real(), name)

    def __reduce__(self) -> Any:                        # pickles as the SeedSequence it stands for
        return self._real().__reduce__()

    def __repr__(self) -> str:
        return repr(self._real())


def episode_generators(seeds: Sequence[int]) -> list[np.random.Generator]:
    """``[numpy.random.default_rng(s) for s in seeds]`` — the same ``PCG64`` generators, streams and
    child streams — with their seed sequences hashed for the whole batch at once (seeds are
    ``uint32`` words, as :func:`episode_seed` gives; larger ones take NumPy's own path)."""
    seeds = [_check_seed(s) for s in seeds]
    if not seeds or max(seeds) > _MASK32:
        return [np.random.default_rng(s) for s in seeds]
    entropy = np.asarray(seeds, dtype=np.uint32)[:, None]
    # PCG64 seeds itself with generate_state(4, uint64): 8 words, read as little-endian pairs
    state = _generate_state(_pools(entropy), 8).astype("<u4").view("<u8").astype(np.uint64)
    return [np.random.Generator(np.random.PCG64(_PrecomputedSeedSequence(s, w)))
            for s, w in zip(seeds, state, strict=True)]
