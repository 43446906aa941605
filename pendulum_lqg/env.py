"""The Gymnasium environments at their 0.3 import path (the package is :mod:`pendulum_lqg.envs`)."""

from pendulum_lqg.envs.config import DEFAULT_REWARD_SCALE, REWARD_FLOOR, EnvConfig, step_reward
from pendulum_lqg.envs.render import CAMERA_DISTANCE_POLE_LENGTHS
from pendulum_lqg.envs.single import CartPoleLQGEnv, make_env
from pendulum_lqg.envs.vector import CartPoleLQGVectorEnv

__all__ = ["CAMERA_DISTANCE_POLE_LENGTHS", "DEFAULT_REWARD_SCALE", "REWARD_FLOOR", "CartPoleLQGEnv",
           "CartPoleLQGVectorEnv", "EnvConfig", "make_env", "step_reward"]
