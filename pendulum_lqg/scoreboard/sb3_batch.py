"""Scoring a stable-baselines3 model batched: all of a suite's episodes at once in the native vector env.

:func:`~pendulum_lqg.scoreboard.episodes.agent_rows` plays one episode after another and asks the
model once per step per episode; a recurrent model took minutes per suite that way. Here the
suite's episodes are rows of one :class:`~pendulum_lqg.envs.vector.CartPoleLQGVectorEnv` (at most
:data:`CHUNK` at a time), sub-env ``i`` reset with episode ``i``'s seed — the very episode a single
env reset with that seed plays — and the model's ``predict`` is called once per control period for
all rows, with the observation design of its training record
(:class:`~pendulum_lqg.scoreboard.obs_design.ObservationHistory`, one row per episode) and a
recurrent policy's state kept per row. A row's episode ends at its first ``terminated`` or
``truncated``; its later steps (the vector env's next-step reset) are not counted.

The rows are those of the one-episode path up to floating-point rounding: a network evaluated on a
batch may round differently from the same network on one row.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from pendulum_lqg.core.seeding import episode_seeds
from pendulum_lqg.errors import NotApplicable, PluginError
from pendulum_lqg.scoreboard.obs_design import ObservationDesign, ObservationHistory, normalise
from pendulum_lqg.scoreboard.suites import Suite

#: Episodes stepped together (rows of one batched simulator).
CHUNK = 256

__all__ = ["CHUNK", "batched_rows"]


def batched_rows(suite: Suite, factory: Any, *, normalize_action: bool | None = None,
                 ) -> list[dict[str, Any]]:
    """The rows of the SB3 model of ``factory`` (:class:`~pendulum_lqg.scoreboard.sb3.SB3Factory`)
    on ``suite``, batched (see the module docstring); ``normalize_action`` (default: the
    record's) is the env's action space."""
    normalized = factory.normalize_action if normalize_action is None else normalize_action
    trained_on = factory.env.get("observation_mode", "measurement")
    mode = suite.env.get("observation_mode", "measurement")
    if mode != trained_on:
        raise NotApplicable(f"agent sb3:{factory.path_text} was trained on observation_mode = "
                            f"{trained_on!r}; this suite's env has {mode!r}")
    from pendulum_lqg.scoreboard.sb3 import one_torch_thread

    seeds = list(episode_seeds(suite.seed, range(suite.episodes)))
    rows: list[dict[str, Any]] = []
    with one_torch_thread():
        for start in range(0, len(seeds), CHUNK):
            rows += _chunk(suite, factory, seeds[start:start + CHUNK], start, normalized)
    return rows


def _chunk(suite: Suite, factory: Any, seeds: list[int], first: int, normalized: bool,
           ) -> list[dict[str, Any]]:
    """Episodes ``first …`` (their ``seeds``) stepped together until every one has ended."""
    from pendulum_lqg.envs.vector import CartPoleLQGVectorEnv

    n = len(seeds)
    env = CartPoleLQGVectorEnv(n, normalize_action=normalized, nthread=1, **suite.env)
    meta = factory.meta
    space: Any = env.single_action_space
    obs_dim = int(np.prod(env.single_observation_space.shape or (1,)))
    history = ObservationHistory(ObservationDesign.of(meta), n, obs_dim, space.low, space.high,
                                 config=suite.config, normalize_action=normalized)
    obs, _ = env.reset(seed=seeds)
    stack = history.reset(obs)
    state: Any = None
    starts = np.ones(n, dtype=bool)
    out: list[dict[str, Any] | None] = [None] * n
    running = np.ones(n, dtype=bool)             # rows whose episode has not ended yet
    try:
        while running.any():
            actions, state = _predict(factory, normalise(stack, meta["obs_norm"]), state, starts)
            obs, _, terminated, truncated, info = env.step(actions)
            starts[:] = False
            ended = (terminated | truncated) & running
            running &= ~ended
            for i in np.nonzero(ended)[0]:
                out[i] = {"episode": first + int(i), "seed": seeds[i],
                          "success": not bool(terminated[i]),
                          "failure_reason": str(info["failure_reason"][i]),
                          "cost": float(info["running_cost"][i])}
            stack = history.step(obs, actions)
    finally:
        env.close()
    return [r for r in out if r is not None]


def _predict(factory: Any, seen: np.ndarray, state: Any, starts: np.ndarray,
             ) -> tuple[np.ndarray, Any]:
    """One ``predict`` for every row; an error of the model is one line naming it."""
    try:
        action, state = factory.model.predict(seen, state=state, episode_start=starts.copy(),
                                              deterministic=True)
    except Exception as exc:
        raise PluginError(f"agent sb3:{factory.path_text}: predict raised {type(exc).__name__}: "
                          f"{' '.join(str(exc).split())[:200]}") from exc
    return np.asarray(action, dtype=float).reshape(seen.shape[0], -1), state
