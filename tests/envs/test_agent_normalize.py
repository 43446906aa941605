"""``LQGAgent`` honours the env's ``normalize_action``: the same seeds give the same episodes."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import pendulum_lqg
from pendulum_lqg.core.seeding import episode_seed
from pendulum_lqg.envs.agent import LQGAgent

ID = pendulum_lqg.ENV_ID


def _episodes(observer: str, n: int, **kwargs) -> list[tuple[bool, str, float, float]]:
    env = gym.make(ID, **kwargs)
    agent = LQGAgent(env, observer=observer)
    out = []
    for k in range(n):
        obs, _ = env.reset(seed=episode_seed(11, k))
        agent.reset()
        term = trunc = False
        while not (term or trunc):
            action = agent.act(obs)
            assert env.action_space.contains(action.astype(np.float32))
            obs, _, term, trunc, info = env.step(action)
        out.append((not term, info["failure_reason"], info["time"], info["running_cost"]))
    return out


@pytest.mark.parametrize(("observer", "n"), [
    ("kalman", 6), pytest.param("kalman", 20, marks=pytest.mark.slow), ("luenberger", 6)])
def test_normalized_actions_play_the_same_episodes(observer, n):
    newtons = _episodes(observer, n)
    normalized = _episodes(observer, n, normalize_action=True)
    # outcomes exactly: success, failure reason, the time the episode ended
    assert [r[:3] for r in normalized] == [r[:3] for r in newtons]
    if observer == "luenberger":
        assert not all(r[0] for r in newtons)          # failures are compared too
    else:
        assert all(r[0] for r in newtons)              # every one, as bench
    # J to a few ulps of the force per step, not bit for bit: the env's map rounds a + 1
    np.testing.assert_allclose([r[3] for r in normalized], [r[3] for r in newtons], rtol=1e-12)


def test_vector_env_agent_returns_actions_in_the_normalized_box():
    envs = gym.make_vec(ID, num_envs=4, normalize_action=True)
    agent = LQGAgent(envs)
    plain = gym.make_vec(ID, num_envs=4)
    ref = LQGAgent(plain)
    obs, _ = envs.reset(seed=3)
    obs_ref, _ = plain.reset(seed=3)
    agent.reset()
    ref.reset()
    for _ in range(50):
        a, u = agent.act(obs), ref.act(obs_ref)
        assert a.shape == (4, 1) and np.all(np.abs(a) <= 1.0)
        np.testing.assert_allclose(a * 10.0, u, rtol=0, atol=1e-12)   # ±1 ↔ ±10 N
        obs, *_ = envs.step(a)
        obs_ref, *_ = plain.step(u)
