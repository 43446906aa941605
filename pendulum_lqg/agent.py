"""Deprecated: the 0.3 import path of the LQG agent, kept for the 0.6 series only
(``from pendulum_lqg import LQGAgent``; the module is :mod:`pendulum_lqg.envs.agent`)."""

import warnings

from pendulum_lqg.envs.agent import LQGAgent

__all__ = ["LQGAgent"]

warnings.warn("pendulum_lqg.agent is deprecated and goes in 0.7: from pendulum_lqg import LQGAgent",
              DeprecationWarning, stacklevel=2)
