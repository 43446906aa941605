"""Observation designs of the RL agents: what the network sees, the same in training and scoring.

A design is declared in the training record (:func:`~pendulum_lqg.boundary.schemas.training_record`)
and rebuilt from it by ``score --agent sb3:MODEL.zip``, so a model is always scored on the very
observation it was trained on:

* ``frame_stack = K`` — the last ``K`` frames, newest last, zeros before the first (as SB3's
  ``VecFrameStack``);
* ``past_actions = true`` — each frame is ``[y_t, a_{t−1}]``: the observation and the action
  applied before it (0 before the first), so a history of length ``K`` holds ``K`` (y, u) pairs.
  The action is the one the env was given, clipped to its action space (the actuator's command;
  a scenario's smaller ``force_limit`` saturates it further inside the env, unseen);
* ``obs_norm`` — ``(stack − mean) / sqrt(var + ε)`` clipped to ``±clip``, the frozen statistics
  of SB3's ``VecNormalize`` (applied to the stack, after it).

A sample lost or not yet delivered (``nan``: ``dropout``, a measurement delay) is replaced by the
last one received, zeros before the first: the networks never see a nan.

:class:`ObservationHistory` keeps the frames of ``n`` rows at once: one row for one scored episode,
``num_envs`` rows in training (:func:`history_vec_env`, an SB3 ``VecEnvWrapper``, which also turns
each ``terminal_observation`` into the history the ended episode's last step would have shown).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pendulum_lqg.errors import ConfigError

__all__ = ["ObservationDesign", "ObservationHistory", "history_vec_env", "normalise"]


@dataclass(frozen=True)
class ObservationDesign:
    """The declared design (see the module docstring): ``frame_stack`` frames of the observation,
    each with the previous action if ``past_actions``."""

    frame_stack: int = 1
    past_actions: bool = False

    def __post_init__(self) -> None:
        if isinstance(self.frame_stack, bool) or not isinstance(self.frame_stack, int) \
                or self.frame_stack < 1:
            raise ConfigError(f"frame_stack: expected a positive integer, got {self.frame_stack!r}")

    def frame_size(self, obs_dim: int, action_dim: int) -> int:
        return obs_dim + (action_dim if self.past_actions else 0)

    def record(self) -> dict[str, Any]:
        """The training record's keys of this design."""
        return {"frame_stack": self.frame_stack, "past_actions": self.past_actions}


def normalise(stack: np.ndarray, obs_norm: dict[str, Any] | None) -> np.ndarray:
    """``stack`` normalised with frozen ``VecNormalize`` statistics (``None``: unchanged)."""
    if obs_norm is None:
        return stack
    std = np.sqrt(np.asarray(obs_norm["var"], dtype=float) + float(obs_norm.get("epsilon", 1e-8)))
    clip = float(obs_norm.get("clip", 10.0))
    return np.clip((stack - np.asarray(obs_norm["mean"], dtype=float)) / std, -clip, clip)


class ObservationHistory:
    """The frames of ``n`` rows under ``design`` (see the module docstring); ``low``/``high``:
    the action space's bounds (the previous action is clipped to them)."""

    def __init__(self, design: ObservationDesign, n: int, obs_dim: int, low: Any, high: Any,
                 ) -> None:
        self.design, self.n, self.obs_dim = design, n, obs_dim
        self.low = np.asarray(low, dtype=float).ravel()
        self.high = np.asarray(high, dtype=float).ravel()
        self.frame = design.frame_size(obs_dim, self.low.size)
        self.stack = np.zeros((n, design.frame_stack * self.frame))
        self.held = np.zeros((n, obs_dim))

    @property
    def size(self) -> int:
        """The length of one row's stacked observation."""
        return self.stack.shape[1]

    def _frame(self, rows: np.ndarray, obs: np.ndarray, actions: np.ndarray | None) -> np.ndarray:
        obs = np.asarray(obs, dtype=float).reshape(rows.size, self.obs_dim)
        fresh = np.isfinite(obs).all(axis=1)         # a lost or late sample: hold the last one
        self.held[rows[fresh]] = obs[fresh]
        parts = [self.held[rows]]
        if self.design.past_actions:
            a = (np.zeros((rows.size, self.low.size)) if actions is None else
                 np.clip(np.asarray(actions, dtype=float).reshape(rows.size, -1), self.low,
                         self.high))
            parts.append(a)
        return np.concatenate(parts, axis=1)

    def reset(self, obs: np.ndarray, rows: np.ndarray | None = None) -> np.ndarray:
        """Start ``rows`` (default: all) on their first observations ``obs``; their stacks."""
        rows = np.arange(self.n) if rows is None else np.asarray(rows, dtype=int)
        self.stack[rows] = 0.0
        self.held[rows] = 0.0
        return self.push(rows, obs, None)

    def step(self, obs: np.ndarray, actions: np.ndarray) -> np.ndarray:
        """Every row's next observation ``obs`` after ``actions``; the stacks (a copy)."""
        return self.push(np.arange(self.n), obs, actions)

    def peek(self, rows: np.ndarray, obs: np.ndarray, actions: np.ndarray) -> np.ndarray:
        """The stacks ``rows`` would have after ``obs`` and ``actions``, without keeping them
        (an ended episode's terminal observation)."""
        stack, held = self.stack[rows].copy(), self.held[rows].copy()
        out = self.push(rows, obs, actions)
        self.stack[rows], self.held[rows] = stack, held
        return out

    def select(self, rows: np.ndarray) -> None:
        """Keep only ``rows`` (ended episodes leave the batch: the policy protocol's ``select``)."""
        self.stack, self.held = self.stack[rows], self.held[rows]
        self.n = self.stack.shape[0]

    def push(self, rows: np.ndarray, obs: np.ndarray, actions: np.ndarray | None) -> np.ndarray:
        """Append the frame of ``obs`` (and ``actions``) to ``rows``; their stacks (a copy)."""
        frame = self._frame(rows, obs, actions)
        self.stack[rows] = np.concatenate([self.stack[rows][:, self.frame:], frame], axis=1)
        return self.stack[rows].copy()


class HistoryVecEnvLogic:
    """An SB3 ``VecEnvWrapper`` that shows the design's stacks instead of the raw observations;
    mixed with SB3's ``VecEnvWrapper`` (or a stand-in) by :func:`history_vec_env`."""

    venv: Any
    num_envs: int

    def __init__(self, venv: Any, design: ObservationDesign) -> None:
        from gymnasium import spaces

        space = venv.action_space
        self.history = ObservationHistory(design, venv.num_envs, venv.observation_space.shape[0],
                                          space.low, space.high)
        self._actions = np.zeros((venv.num_envs, space.shape[0]))
        observation_space = spaces.Box(-np.inf, np.inf, shape=(self.history.size,),
                                       dtype=np.float64)
        super().__init__(venv, observation_space=observation_space)  # type: ignore[call-arg]

    def reset(self) -> np.ndarray:
        return self.history.reset(self.venv.reset())

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions, dtype=float).reshape(self.num_envs, -1)
        self.venv.step_async(actions)

    def step_wait(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        obs, reward, dones, infos = self.venv.step_wait()
        ended = np.nonzero(dones)[0]
        for row in ended:             # the ended episode's last stack, then the new episode's
            terminal = infos[row]["terminal_observation"]
            infos[row]["terminal_observation"] = self.history.peek(
                np.array([row]), terminal, self._actions[row])[0]
        running = np.nonzero(~np.asarray(dones, dtype=bool))[0]
        out = np.empty((self.num_envs, self.history.size))
        if running.size:
            out[running] = self.history.push(running, obs[running], self._actions[running])
        if ended.size:
            out[ended] = self.history.reset(obs[ended], ended)
        return out, reward, dones, infos


def history_vec_env(venv: Any, design: ObservationDesign, *, base: type | None = None) -> Any:
    """``venv`` (an SB3 ``VecEnv``) seen through ``design``'s stacks. ``base``: the
    ``VecEnvWrapper`` class to mix in (default: stable-baselines3's, the ``rl`` extra)."""
    if base is None:
        from pendulum_lqg.scoreboard.sb3_vec import sb3_vec_env_class

        base = sb3_vec_env_class("VecEnvWrapper", "history_vec_env")
    cls = type("HistoryVecEnv", (HistoryVecEnvLogic, base), {"__module__": __name__})
    return cls(venv, design)
