"""The envs refuse, in one line, what they used to cut or crash on: complex actions, a vector env
too large to allocate."""

from __future__ import annotations

import time

import gymnasium as gym
import numpy as np
import pytest

import pendulum_lqg
from pendulum_lqg.errors import ConfigError, PendulumLQGError
from pendulum_lqg.util.limits import MAX_NUM_ENVS

ID = pendulum_lqg.ENV_ID


@pytest.mark.parametrize("action", [np.array([1.0 + 2.0j]), np.array([0.5 + 0.0j]), [1 + 1j],
                                    1 + 1j, np.array([[2.0 + 0.0j]])])
def test_a_complex_action_is_refused_not_cut_to_its_real_part(action):
    env = gym.make(ID)
    env.reset(seed=0)
    with pytest.raises(PendulumLQGError, match=r"^action: expected real forces in newtons, got "
                                               r"complex "):
        env.step(action)
    envs = gym.make_vec(ID, num_envs=2)
    envs.reset(seed=0)
    with pytest.raises(PendulumLQGError, match=r"^action: expected real forces in newtons"):
        envs.step(np.full((2, 1), 1.0 + 1.0j))
    # a real action still steps (and a float64 one is used as given)
    _, _, _, _, info = env.step(np.array([0.5]))
    assert info["force"] == 0.5


def test_a_vector_env_too_large_to_allocate_is_one_line():
    t = time.perf_counter()
    with pytest.raises(ConfigError) as err:
        gym.make_vec(ID, num_envs=10**12)
    assert str(err.value) == (f"num_envs: at most {MAX_NUM_ENVS:,} (each sub-env is a row of "
                              "every array of the batched simulation core), got "
                              "1,000,000,000,000")
    assert time.perf_counter() - t < 5.0
