"""seeding at its 0.3 import path (the module is :mod:`pendulum_lqg.core.seeding`)."""

from pendulum_lqg.core.seeding import child_generator, episode_generators, episode_seed, episode_seeds

__all__ = ['child_generator', 'episode_generators', 'episode_seed', 'episode_seeds']
