"""The environments on any plant (issue 52): the ``plant`` keyword takes a shipped NAME or a plant
FILE, the spaces take the plant's sizes, and what the plant file holds is refused by name."""

from __future__ import annotations

import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import pendulum_lqg
from pendulum_lqg.envs.agent import LQGAgent
from pendulum_lqg.envs.single import CartPoleLQGEnv
from pendulum_lqg.envs.vector import CartPoleLQGVectorEnv
from pendulum_lqg.errors import ConfigError
from tests.envs.test_envs import CHECK_ENV_ALLOWED, _warn_text

DI = "experiments/lti/double_integrator.toml"


def test_the_double_pendulums_env_passes_gymnasiums_checker_without_warnings():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(gym.make(pendulum_lqg.ENV_ID, plant="double-cartpole").unwrapped,
                  skip_render_check=True)
    # the cart-pole's by-design warnings (unbounded noisy observations, actions in newtons), no
    # other
    assert {_warn_text(w) for w in caught} == CHECK_ENV_ALLOWED
    env = gym.make(pendulum_lqg.ENV_ID, plant="double-cartpole")
    assert env.observation_space.shape == (3,)                      # y = [p, θ₁, θ₂]
    assert env.action_space.low.tolist() == [-10.0] and env.action_space.high.tolist() == [10.0]
    state = CartPoleLQGEnv(plant="double-cartpole", observation_mode="state")
    obs, info = state.reset(seed=3)
    assert obs.shape == (6,) and info["y_true"].shape == (3,)
    np.testing.assert_array_equal(info["y_true"], obs[:3])        # C picks the joint angles


def test_the_matrix_plants_env_measures_through_c_and_cannot_render():
    env = CartPoleLQGEnv(plant=DI, observation_mode="state")
    obs, info = env.reset(seed=0)
    assert obs.shape == (2,) and info["y_true"].tolist() == [obs[0]]     # y = x₁
    with pytest.raises(ConfigError, match="render_mode: the plant 'double_integrator' is given "
                                          "as matrices"):
        CartPoleLQGEnv(plant=DI, render_mode="rgb_array")


def test_the_lqg_agent_balances_the_double_pendulum_in_the_vector_env():
    envs = CartPoleLQGVectorEnv(num_envs=8, plant="double-cartpole", duration=3.0)
    agent = LQGAgent(envs)
    obs, _ = envs.reset(seed=1)
    agent.reset()
    ended = np.zeros(8, dtype=bool)
    failed = np.zeros(8, dtype=bool)
    for _ in range(envs.max_episode_steps):
        obs, _, term, trunc, _ = envs.step(agent.act(obs))
        failed |= term & ~ended
        ended |= term | trunc
        if ended.all():
            break
    assert ended.all() and not failed.any()


def test_a_frame_of_the_double_pendulum_shows_its_state():
    env = CartPoleLQGEnv(plant="double-cartpole", render_mode="rgb_array", width=160, height=120)
    env.reset(seed=0)
    upright = env.render()
    env._sim.x[0, 1] = 0.4                   # tilt the first pole (the drawn state only)
    tilted = env.render()
    assert upright.shape == (120, 160, 3) and upright.std() > 0
    assert np.abs(upright.astype(int) - tilted.astype(int)).sum() > 0
    env.close()


@pytest.mark.parametrize("keyword, value", [("x0", (0, 0.1, 0, 0)), ("theta_max", 0.5),
                                            ("measurement_variance", 0.1),
                                            ("model_path", "models/cartpole.xml"),
                                            ("control_period", 0.02)])
def test_what_the_plant_file_holds_is_refused_by_name(keyword, value):
    with pytest.raises(ConfigError) as exc:
        CartPoleLQGEnv(plant="double-cartpole", **{keyword: value})
    assert str(exc.value).startswith(f"{keyword}: not with plant='double-cartpole' (its plant "
                                     f"file holds it)")


def test_the_plant_keyword_still_takes_the_simulator_words_for_one_release():
    old = CartPoleLQGEnv(plant="linear-zoh")
    new = CartPoleLQGEnv(simulator="linear-zoh")
    assert old.scenario == new.scenario and old.scenario.plant == "linear-zoh"
    with pytest.raises(ConfigError, match="plant: 'linear-zoh' names the simulator"):
        CartPoleLQGEnv(plant="linear-zoh", simulator="linear-euler")
    with pytest.raises(ConfigError, match=f"simulator: the plant '{DI}' is simulated by linear-zoh"):
        CartPoleLQGEnv(plant=DI, simulator="mujoco")
