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
* ``estimator = "kalman"`` — each frame holds, instead of ``y_t``, the estimate ``x̂_t`` (4 numbers,
  ``[p, θ, ṗ, θ̇]``) of the reference steady-state Kalman filter (``dlqr+kalman``'s estimator,
  :func:`~pendulum_lqg.policies.loading.build_policy` on the env's design plant
  (:func:`~pendulum_lqg.scoreboard.suites.design_plant`: its model with the fixed
  ``model_overrides``, without the ``randomize`` draws), control period and nominal noise, as the
  suites' reference designs it) fed with ``y_t`` and the force applied before it:
  the action mapped to newtons as the env maps it and saturated by the core's rule
  (:func:`~pendulum_lqg.core.rules.saturate`), so it is the force the reference's own estimator
  would be told of. ``x̂₀`` starts at 0 as the reference's; a lost sample is the estimator's own
  prediction step. The filter is designed for the env being played (a model trained on ``lecture``
  and scored on ``delayed`` sees the plain Kalman filter of ``delayed``'s env, not the delay-aware
  one); it observes ``y``, so it needs ``observation_mode = "measurement"``. Absent from a record
  (records before this design): ``y`` itself;
* ``obs_norm`` — ``(stack − mean) / sqrt(var + ε)`` clipped to ``±clip``, the frozen statistics
  of SB3's ``VecNormalize`` (applied to the stack, after it).

A sample lost or not yet delivered (``nan``: ``dropout``, a measurement delay) is replaced by the
last one received, zeros before the first (with the Kalman design: the filter's prediction): the
networks never see a nan.

:class:`ObservationHistory` keeps the frames of ``n`` rows at once: one row for one scored episode,
``num_envs`` rows in training (:func:`history_vec_env`, an SB3 ``VecEnvWrapper``, which also turns
each ``terminal_observation`` into the history the ended episode's last step would have shown).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from pendulum_lqg.boundary.schemas import ESTIMATORS
from pendulum_lqg.errors import ConfigError

if TYPE_CHECKING:
    from pendulum_lqg.envs.config import EnvConfig

__all__ = ["ESTIMATORS", "KalmanEstimates", "ObservationDesign", "ObservationHistory",
           "history_vec_env", "normalise"]


@dataclass(frozen=True)
class ObservationDesign:
    """The declared design (see the module docstring): ``frame_stack`` frames of the observation
    (or, with ``estimator = "kalman"``, of the reference Kalman filter's ``x̂``), each with the
    previous action if ``past_actions``."""

    frame_stack: int = 1
    past_actions: bool = False
    estimator: str | None = None

    def __post_init__(self) -> None:
        if isinstance(self.frame_stack, bool) or not isinstance(self.frame_stack, int) \
                or self.frame_stack < 1:
            raise ConfigError(f"frame_stack: expected a positive integer, got {self.frame_stack!r}")
        if self.estimator is not None and self.estimator not in ESTIMATORS:
            raise ConfigError(f"estimator: expected one of {', '.join(ESTIMATORS)} (or none), got "
                              f"{self.estimator!r}")

    @classmethod
    def of(cls, record: dict[str, Any]) -> ObservationDesign:
        """The design a training record declares (a record without ``estimator``: ``y``)."""
        return cls(record["frame_stack"], record["past_actions"], record.get("estimator"))

    def frame_size(self, obs_dim: int, action_dim: int) -> int:
        seen = KalmanEstimates.SIZE if self.estimator else obs_dim
        return seen + (action_dim if self.past_actions else 0)

    def record(self) -> dict[str, Any]:
        """The training record's keys of this design (``estimator`` only where one is shown, so
        the records of the designs without one keep their keys)."""
        out: dict[str, Any] = {"frame_stack": self.frame_stack, "past_actions": self.past_actions}
        if self.estimator is not None:
            out["estimator"] = self.estimator
        return out


class KalmanEstimates:
    """The reference steady-state Kalman filter's ``x̂`` for ``n`` rows of an env (``config``, its
    actions in ``[−1, 1]`` if ``normalize_action``), each row on its own (the module docstring).

    The filter is the estimator of ``dlqr+kalman`` as the suites build it (on
    :func:`~pendulum_lqg.scoreboard.suites.design_plant`); its current-form
    recursion ``x̄ = Φx̂ + Γu``, ``x̂ = x̄ + L(y − Cx̄)`` is run by the estimator's own ``reset``,
    ``update`` and ``estimate`` on the rows asked for: ``reset(x̂_prev)`` then ``update(u)`` is
    the time update from the row's last estimate, so any subset of rows can step at a time."""

    #: Numbers of the estimate ``x̂ = [p, θ, ṗ, θ̇]``.
    SIZE = 4

    def __init__(self, config: EnvConfig, normalize_action: bool, n: int) -> None:
        from pendulum_lqg.envs.config import Actions
        from pendulum_lqg.policies.loading import build_policy
        from pendulum_lqg.scoreboard.suites import design_plant

        if config.observation_mode != "measurement":
            raise ConfigError("estimator: 'kalman' estimates x from y = [p, θ]; this env observes "
                              "the state (observation_mode = 'state')")
        policy = build_policy("dlqr+kalman", plant=design_plant(config), scenario=config.scenario)
        self.estimator, self.u_max = policy.estimator, policy.u_max
        self.actions = Actions(self.u_max, normalize_action)
        self.x_hat = np.zeros((n, self.SIZE))

    def applied(self, actions: np.ndarray) -> np.ndarray:
        """The forces (rows, 1) [N] the env applies for ``actions`` (the env's map, saturated)."""
        from pendulum_lqg.core.rules import saturate

        a = np.asarray(actions, dtype=float).reshape(-1)
        return saturate(self.actions.forces(a, a.size), self.u_max)[:, None]

    def first(self, rows: np.ndarray, y: np.ndarray) -> np.ndarray:
        """The first estimates of ``rows`` (new episodes, prior 0) from their ``y``."""
        self.estimator.reset(np.zeros((rows.size, self.SIZE)))
        self.x_hat[rows] = self.estimator.estimate(y)
        return self.x_hat[rows]

    def next(self, rows: np.ndarray, y: np.ndarray, actions: np.ndarray) -> np.ndarray:
        """The estimates of ``rows`` after ``actions`` were applied and ``y`` measured."""
        self.estimator.reset(self.x_hat[rows])
        self.estimator.update(self.applied(actions))
        self.x_hat[rows] = self.estimator.estimate(y)
        return self.x_hat[rows]


def normalise(stack: np.ndarray, obs_norm: dict[str, Any] | None) -> np.ndarray:
    """``stack`` normalised with frozen ``VecNormalize`` statistics (``None``: unchanged)."""
    if obs_norm is None:
        return stack
    std = np.sqrt(np.asarray(obs_norm["var"], dtype=float) + float(obs_norm.get("epsilon", 1e-8)))
    clip = float(obs_norm.get("clip", 10.0))
    return np.clip((stack - np.asarray(obs_norm["mean"], dtype=float)) / std, -clip, clip)


class ObservationHistory:
    """The frames of ``n`` rows under ``design`` (see the module docstring); ``low``/``high``:
    the action space's bounds (the previous action is clipped to them). A design with an
    ``estimator`` needs the env's ``config`` and whether its actions are ``normalize_action``
    (the map from actions to newtons the filter is told of)."""

    def __init__(self, design: ObservationDesign, n: int, obs_dim: int, low: Any, high: Any, *,
                 config: EnvConfig | None = None, normalize_action: bool | None = None) -> None:
        self.design, self.n, self.obs_dim = design, n, obs_dim
        self.low = np.asarray(low, dtype=float).ravel()
        self.high = np.asarray(high, dtype=float).ravel()
        self.frame = design.frame_size(obs_dim, self.low.size)
        self.stack = np.zeros((n, design.frame_stack * self.frame))
        self.held = np.zeros((n, obs_dim))
        self.kalman: KalmanEstimates | None = None
        if design.estimator is not None:
            if config is None or normalize_action is None:
                raise ConfigError(f"estimator: {design.estimator!r} needs the env's config and "
                                  "its normalize_action (the filter is designed for the env)")
            self.kalman = KalmanEstimates(config, normalize_action, n)

    @property
    def size(self) -> int:
        """The length of one row's stacked observation."""
        return self.stack.shape[1]

    def _frame(self, rows: np.ndarray, obs: np.ndarray, actions: np.ndarray | None) -> np.ndarray:
        obs = np.asarray(obs, dtype=float).reshape(rows.size, self.obs_dim)
        fresh = np.isfinite(obs).all(axis=1)         # a lost or late sample: hold the last one
        self.held[rows[fresh]] = obs[fresh]
        if self.kalman is None:
            parts = [self.held[rows]]
        elif actions is None:                        # a new episode: the filter's first estimate
            parts = [self.kalman.first(rows, obs)]
        else:
            parts = [self.kalman.next(rows, obs, np.clip(
                np.asarray(actions, dtype=float).reshape(rows.size, -1), self.low, self.high))]
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
        x_hat = None if self.kalman is None else self.kalman.x_hat[rows].copy()
        out = self.push(rows, obs, actions)
        self.stack[rows], self.held[rows] = stack, held
        if self.kalman is not None:
            self.kalman.x_hat[rows] = x_hat
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

    def __init__(self, venv: Any, design: ObservationDesign, normalize_action: bool | None,
                 ) -> None:
        from gymnasium import spaces

        space = venv.action_space
        config = venv.get_attr("config")[0] if design.estimator is not None else None
        self.history = ObservationHistory(design, venv.num_envs, venv.observation_space.shape[0],
                                          space.low, space.high, config=config,
                                          normalize_action=normalize_action)
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


def history_vec_env(venv: Any, design: ObservationDesign, *, base: type | None = None,
                    normalize_action: bool | None = None) -> Any:
    """``venv`` (an SB3 ``VecEnv``) seen through ``design``'s stacks. ``base``: the
    ``VecEnvWrapper`` class to mix in (default: stable-baselines3's, the ``rl`` extra). A design
    with an ``estimator`` reads the env's ``config`` (``get_attr``: the native vector env's) and
    needs ``normalize_action``, the env's action map."""
    if base is None:
        from pendulum_lqg.scoreboard.sb3_vec import sb3_vec_env_class

        base = sb3_vec_env_class("VecEnvWrapper", "history_vec_env")
    cls = type("HistoryVecEnv", (HistoryVecEnvLogic, base), {"__module__": __name__})
    return cls(venv, design, normalize_action)
