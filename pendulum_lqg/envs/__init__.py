"""Gymnasium environments over the simulation core, and the LQG baseline agent.

=================  ===============================================================
module             concept
=================  ===============================================================
``config``         the keywords both envs take, the action map and the reward
``single``         :class:`~pendulum_lqg.envs.single.CartPoleLQGEnv` (one episode)
``vector``         :class:`~pendulum_lqg.envs.vector.CartPoleLQGVectorEnv` (a batch)
``render``         offscreen frames for ``render()``
``agent``          :class:`~pendulum_lqg.envs.agent.LQGAgent`, the LQG policy as an agent
=================  ===============================================================

Nothing here steps MuJoCo, draws noise, saturates, integrates a cost or decides a failure: the
envs are adapters over :class:`~pendulum_lqg.core.loop.Simulator` and its rules. The ids are
registered in ``pendulum_lqg/__init__.py`` (:data:`pendulum_lqg.ENV_ID`).
"""

from pendulum_lqg.envs.config import DEFAULT_REWARD_SCALE, REWARD_FLOOR, EnvConfig, step_reward
from pendulum_lqg.envs.single import CartPoleLQGEnv, make_env
from pendulum_lqg.envs.vector import CartPoleLQGVectorEnv

__all__ = ["DEFAULT_REWARD_SCALE", "REWARD_FLOOR", "CartPoleLQGEnv", "CartPoleLQGVectorEnv",
           "EnvConfig", "make_env", "step_reward"]
