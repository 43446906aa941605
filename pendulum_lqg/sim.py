"""The names of the simulation core at their 0.3 import path (the core is :mod:`pendulum_lqg.core`).

``from pendulum_lqg.sim import Scenario, run_episodes`` keeps working; new code may import from the
core's modules directly.
"""

from pendulum_lqg.core.loop import Simulator, StepResult
from pendulum_lqg.core.physics import BatchPhysics, thread_count
from pendulum_lqg.core.rules import RUNAWAY
from pendulum_lqg.core.runner import MIN_SHARD_ROWS, BatchResult, run_episodes, shard_count
from pendulum_lqg.core.scenario import Scenario
from pendulum_lqg.core.seeding import child_generator, episode_generators, episode_seed, episode_seeds
from pendulum_lqg.core.trajectory import Trajectory

__all__ = ["MIN_SHARD_ROWS", "RUNAWAY", "BatchPhysics", "BatchResult", "Scenario", "Simulator",
           "StepResult", "Trajectory", "child_generator", "episode_generators", "episode_seed",
           "episode_seeds", "run_episodes", "shard_count", "thread_count"]
