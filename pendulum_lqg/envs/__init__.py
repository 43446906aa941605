"""Gymnasium environments over the simulation core, and the LQG baseline agent.

=================  ===============================================================
module             concept
=================  ===============================================================
``registration``   :data:`~pendulum_lqg.envs.registration.ENV_ID` and its registration
``config``         the keywords both envs take, the action map and the reward
``keywords``       the ``EnvKeywords`` TypedDict (generated from ``problem``'s declarations)
``single``         :class:`~pendulum_lqg.envs.single.CartPoleLQGEnv` (one episode)
``vector``         :class:`~pendulum_lqg.envs.vector.CartPoleLQGVectorEnv` (a batch)
``render``         offscreen frames for ``render()``
``agent``          :class:`~pendulum_lqg.envs.agent.LQGAgent`, the LQG policy as an agent
=================  ===============================================================

Nothing here steps MuJoCo, draws noise, saturates, integrates a cost or decides a failure: the
envs are adapters over :class:`~pendulum_lqg.core.loop.Simulator` and its rules. The names below
load their module on first use, so that importing :mod:`pendulum_lqg.envs.registration` (which
the package root does) loads neither Gymnasium nor MuJoCo.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from pendulum_lqg.envs.config import DEFAULT_REWARD_SCALE, REWARD_FLOOR, EnvConfig, step_reward
    from pendulum_lqg.envs.single import CartPoleLQGEnv, make_env
    from pendulum_lqg.envs.vector import CartPoleLQGVectorEnv

#: Each public name and the module that defines it.
_HOMES = {"DEFAULT_REWARD_SCALE": "config", "REWARD_FLOOR": "config", "EnvConfig": "config",
          "step_reward": "config", "CartPoleLQGEnv": "single", "make_env": "single",
          "CartPoleLQGVectorEnv": "vector"}

__all__ = ["DEFAULT_REWARD_SCALE", "REWARD_FLOOR", "CartPoleLQGEnv", "CartPoleLQGVectorEnv",
           "EnvConfig", "make_env", "step_reward"]


def __getattr__(name: str) -> Any:
    if name not in _HOMES:
        raise AttributeError(f"module 'pendulum_lqg.envs' has no attribute {name!r}")
    return getattr(importlib.import_module(f"pendulum_lqg.envs.{_HOMES[name]}"), name)
