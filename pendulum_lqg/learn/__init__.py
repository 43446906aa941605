"""Learning controllers from data: identification, random search and deep RL, behind
``pendulum-lqg train METHOD``.

The deep-RL methods need the ``rl`` extra (stable-baselines3, sb3-contrib, torch), imported only
inside the functions that train them; identification and random search need nothing beyond the
package's own dependencies.
"""
