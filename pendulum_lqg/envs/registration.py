"""The Gymnasium id of the cart-pole environment and its registration.

Kept apart from the envs themselves so that naming the id, or registering it, loads Gymnasium at
most — never MuJoCo, numpy's heavier users or the simulation core (those load when an env is made).
"""

from __future__ import annotations

#: The Gymnasium id of the cart-pole LQG environment (:class:`pendulum_lqg.envs.single.CartPoleLQGEnv`).
ENV_ID = "pendulum_lqg/CartPoleLQG-v0"


def register_envs() -> None:
    """Register :data:`ENV_ID` (single and vector entry points) with Gymnasium, once.

    A behaviour change of the environment gets a new version here (``-v1``), never an edit of v0.
    No keyword is registered: the entry point :func:`pendulum_lqg.envs.single.make_env` takes the
    env's own defaults (:class:`~pendulum_lqg.envs.config.EnvConfig`, from
    :class:`~pendulum_lqg.core.scenario.Scenario`) and wraps the env in its own ``TimeLimit`` of
    ``duration / control_period`` steps, so ``max_episode_steps`` follows the keywords a caller
    gives (a fixed registered value would cut a longer episode short).
    """
    import gymnasium

    if ENV_ID in gymnasium.registry:
        return
    gymnasium.register(
        id=ENV_ID,
        entry_point="pendulum_lqg.envs.single:make_env",
        vector_entry_point="pendulum_lqg.envs.vector:CartPoleLQGVectorEnv",
    )
