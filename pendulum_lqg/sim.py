"""Deprecated: the 0.3 import path of the simulation core's names, kept for the 0.6 series only.

Import them from the package (``from pendulum_lqg import Scenario, run_episodes``) or from their
modules in :mod:`pendulum_lqg.core`.
"""

import warnings

from pendulum_lqg.core.loop import Simulator, StepResult
from pendulum_lqg.core.runner import BatchResult, run_episodes
from pendulum_lqg.core.scenario import Scenario
from pendulum_lqg.core.seeding import child_generator, episode_generators, episode_seed, episode_seeds
from pendulum_lqg.core.trajectory import Trajectory

__all__ = ["BatchResult", "Scenario", "Simulator", "StepResult", "Trajectory", "child_generator",
           "episode_generators", "episode_seed", "episode_seeds", "run_episodes"]

warnings.warn("pendulum_lqg.sim is deprecated and goes in 0.7: import from pendulum_lqg "
              "(Scenario, run_episodes, episode_seed, …) or pendulum_lqg.core",
              DeprecationWarning, stacklevel=2)
