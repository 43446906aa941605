"""The LQG agent at its 0.3 import path (the module is :mod:`pendulum_lqg.envs.agent`)."""

from pendulum_lqg.envs.agent import LQGAgent

__all__ = ["LQGAgent"]
