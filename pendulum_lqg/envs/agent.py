"""The LQG policy as a Gymnasium agent: ``reset()`` and ``act(observation) -> action``.

:class:`LQGAgent` designs from the environment's own model and control period with
:func:`~pendulum_lqg.policies.lqg.design_policy` — the very policy ``pendulum-lqg bench`` runs — and sees
nothing but the observations the env hands out. Over the same episode seeds
(``env.reset(seed=episode_seed(s, k))``) it reproduces ``bench``'s episodes bit for bit (to rounding
error with ``normalize_action=True``), so its success rate and mean J equal the benchmark's.

Example::

    env = gymnasium.make("pendulum_lqg/CartPoleLQG-v0")
    agent = LQGAgent(env, observer="kalman")
    obs, info = env.reset(seed=0)
    agent.reset()
    while True:
        obs, reward, terminated, truncated, info = env.step(agent.act(obs))
        if terminated or truncated:
            break
"""

from __future__ import annotations

import dataclasses
from typing import Literal

import gymnasium as gym
import numpy as np

from pendulum_lqg.envs.single import CartPoleLQGEnv
from pendulum_lqg.envs.vector import CartPoleLQGVectorEnv
from pendulum_lqg.errors import ConfigError, ShapeError
from pendulum_lqg.model.plant import load_plant
from pendulum_lqg.policies.lqg import DesignSpec, Policy, delay_periods, design_policy


class LQGAgent:
    """An LQG policy (controller + observer) acting through the Gymnasium API.

    Parameters
    ----------
    env : a ``pendulum_lqg/CartPoleLQG-v0`` env (wrapped or not) or its native vector env
    spec : the design (controller, observer, weights); default :class:`~pendulum_lqg.policies.lqg.DesignSpec`
    controller, observer : shortcuts that replace ``spec``'s controller / observer
    design_model : ``"nominal"`` (default, as ``bench``) designs on the XML model without the env's
        ``model_overrides`` — a mismatch study; ``"simulated"`` designs on the simulated plant

    The observer ``"none"`` (full-state feedback) needs the true state: the env must have
    ``observation_mode="state"``; every other observer needs ``"measurement"``. A mismatch is a
    :class:`~pendulum_lqg.errors.ConfigError`.

    With a single env, ``act`` takes an observation (2,) or (4,) and returns a float64 action (1,);
    with the vector env, observations (num_envs, ·) and actions (num_envs, 1). The actions are
    float64 on purpose: the env applies them at that precision, so the forces equal ``bench``'s.

    With ``normalize_action=True`` the actions are the env's own: each force mapped into
    ``[−1, 1]`` by the inverse of the env's map. The forces then agree with ``bench``'s to a few
    ulps of the force limit rather than bit for bit (the env's map rounds ``a + 1``), so the
    episodes' outcomes are the same and their J agree to rounding error.
    """

    def __init__(self, env: gym.Env | CartPoleLQGVectorEnv, spec: DesignSpec | None = None, *,
                 controller: str | None = None, observer: str | None = None,
                 design_model: Literal["nominal", "simulated"] = "nominal") -> None:
        base = env.unwrapped
        if not isinstance(base, CartPoleLQGEnv | CartPoleLQGVectorEnv):
            raise ConfigError(f"env: expected a pendulum_lqg CartPoleLQG env, got {base!r}")
        spec = spec or DesignSpec()
        if controller is not None:
            spec = dataclasses.replace(spec, controller=controller)
        if observer is not None:
            spec = dataclasses.replace(spec, observer=observer)
        if design_model not in ("nominal", "simulated"):
            raise ConfigError(f"design_model: expected 'nominal' or 'simulated', got "
                              f"{design_model!r}")
        scenario = base.scenario
        self.spec = spec
        self.policy: Policy
        if base.config.plant_file is not None:       # a plant file: its own weights and noise
            from pendulum_lqg.policies.lti import design_lti_policy

            self.policy = design_lti_policy(base.config.plant_file,
                                            f"{spec.controller}+{spec.observer}",
                                            u_max=base.action_map.hi)
        else:
            plant = base.plant
            if design_model == "nominal" and not plant.overrides.is_empty():
                plant = load_plant(plant.path)
            self.policy = design_policy(plant, scenario.control_period, scenario.noise, spec,
                                        delays=delay_periods(scenario))
        wants = "state" if self.policy.needs_state else "measurement"
        if base.observation_mode != wants:
            raise ConfigError(f"observer: {spec.observer!r} needs observation_mode={wants!r}, "
                              f"the env has {base.observation_mode!r}")
        #: the env's map between actions and newtons (identity unless normalize_action)
        self._actions = base.action_map
        self.vector = isinstance(base, CartPoleLQGVectorEnv)
        self.num_envs = base.num_envs if isinstance(base, CartPoleLQGVectorEnv) else 1
        space = (base.single_observation_space if isinstance(base, CartPoleLQGVectorEnv)
                 else base.observation_space)
        assert space.shape is not None
        self._obs_dim = int(space.shape[0])
        #: the estimate's size (the plant's states)
        self._n = int(np.shape(self.policy.K)[-1])

    @property
    def name(self) -> str:
        """``"<controller>+<observer>"``."""
        return self.policy.name

    def reset(self, rows: np.ndarray | None = None, *, x_hat0: np.ndarray | None = None) -> None:
        """Start new episode(s): the estimate goes back to ``x_hat0`` (default 0, as ``bench``).

        Parameters
        ----------
        rows : vector env only: restart just these sub-envs (those that ended in the last step)
        x_hat0 : initial estimate (4,) or (len(rows), 4), e.g. ``info["state"]`` for a known x₀
        """
        if rows is None:
            x0 = np.zeros((self.num_envs, self._n)) if x_hat0 is None else \
                np.broadcast_to(np.asarray(x_hat0, dtype=float), (self.num_envs, self._n)).copy()
            self.policy.reset(self.num_envs, x0)
            return
        rows = np.asarray(rows, dtype=np.int64).reshape(-1)
        if rows.size == 0:
            return
        x0 = np.zeros((rows.size, self._n)) if x_hat0 is None else \
            np.broadcast_to(np.asarray(x_hat0, dtype=float), (rows.size, self._n)).copy()
        self.policy.estimator.reset(x0, rows=rows)

    def act(self, observation: np.ndarray) -> np.ndarray:
        """Force(s) for the current observation(s): (1,) for one env, (num_envs, 1) for a batch."""
        obs = np.asarray(observation, dtype=np.float64)
        if obs.shape[-1:] != (self._obs_dim,) or obs.size != self.num_envs * self._obs_dim:
            want = (self._obs_dim,) if not self.vector else (self.num_envs, self._obs_dim)
            raise ShapeError(f"observation: expected shape {want}, found {obs.shape}")
        u = self._actions.from_newtons(self.policy.act(obs.reshape(self.num_envs, self._obs_dim)))
        return u.reshape(self.num_envs, 1) if self.vector else u.reshape(1)
