"""The SB3 VecEnv adapter over the native vector env, checked step for step against single
Gymnasium envs driven as SB3's DummyVecEnv drives them: with a stand-in for SB3's VecEnv base
(always, no torch needed) and with stable-baselines3's own VecEnv where the rl extra is installed."""

from __future__ import annotations

import importlib.util

import gymnasium as gym
import numpy as np
import pytest

import pendulum_lqg
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.scoreboard.sb3_vec import native_vec_env

N, SEED, STEPS = 3, 11, 120
#: short episodes that both fail (|θ| > 0.15 under random forces) and run out of time (25 steps)
ENV = {"max_episode_steps": 25, "normalize_action": True, "theta_max": 0.15,
       "x0_std": [0.0, 0.05, 0.0, 0.0]}


class StandInVecEnv:
    """The part of SB3's ``VecEnv`` base the adapter relies on (SB3 2.x): its ``__init__``
    (per-env reset infos, seeds and options used at the next reset, ``render_mode`` read with
    ``get_attr``), ``seed(s)`` → ``s + i`` and ``step`` = ``step_async`` + ``step_wait``."""

    def __init__(self, num_envs, observation_space, action_space):
        self.num_envs = num_envs
        self.observation_space, self.action_space = observation_space, action_space
        self.reset_infos = [{} for _ in range(num_envs)]
        self._seeds = [None] * num_envs
        self._options = [{} for _ in range(num_envs)]
        self.render_mode = self.get_attr("render_mode")[0]

    def seed(self, seed=None):
        self._seeds = [seed + i for i in range(self.num_envs)]
        return self._seeds

    def step(self, actions):
        self.step_async(actions)
        return self.step_wait()


def _bases():
    bases = [pytest.param(StandInVecEnv, id="stand-in")]
    if importlib.util.find_spec("stable_baselines3") is not None:
        bases.append(pytest.param(None, id="stable-baselines3"))
    return bases


def _dummy_steps(actions):
    """SB3's DummyVecEnv semantics over N single envs (sub-env i reset with seed SEED + i): the
    observations, rewards, dones and terminal observations, step by step."""
    kw = {k: v for k, v in ENV.items() if k != "max_episode_steps"}
    envs = [gym.make(pendulum_lqg.ENV_ID, max_episode_steps=ENV["max_episode_steps"], **kw)
            for _ in range(N)]
    first = np.array([env.reset(seed=SEED + i)[0] for i, env in enumerate(envs)])
    out = []
    for a in actions:
        step = []
        for i, env in enumerate(envs):
            obs, reward, terminated, truncated, info = env.step(a[i])
            terminal = None
            if terminated or truncated:
                terminal, (obs, _) = obs, env.reset()
            step.append((obs, reward, terminated or truncated, terminal,
                         truncated and not terminated, info["cost"]))
        out.append(step)
    return first, out


@pytest.mark.parametrize("base", _bases())
def test_the_adapter_steps_as_dummyvecenv_over_single_envs(base):
    rng = np.random.default_rng(0)
    actions = rng.uniform(-1.0, 1.0, size=(STEPS, N, 1))
    first, expected = _dummy_steps(actions)
    env = native_vec_env(N, base=base, seed=SEED, **ENV)
    np.testing.assert_array_equal(env.reset(), first)
    ends = {"terminated": 0, "truncated": 0}
    for a, want in zip(actions, expected, strict=True):
        obs, reward, done, infos = env.step(a)
        assert reward.dtype == np.float32 and done.dtype == np.bool_ and len(infos) == N
        for i, (w_obs, w_reward, w_done, w_terminal, w_trunc, w_cost) in enumerate(want):
            np.testing.assert_array_equal(obs[i], w_obs)
            assert reward[i] == np.float32(w_reward) and done[i] == w_done
            assert infos[i]["TimeLimit.truncated"] == w_trunc and infos[i]["cost"] == w_cost
            if w_done:
                np.testing.assert_array_equal(infos[i]["terminal_observation"], w_terminal)
                ends["truncated" if w_trunc else "terminated"] += 1
                assert env.reset_infos[i]["running_cost"] == 0.0     # the new episode's info
            else:
                assert "terminal_observation" not in infos[i]
    assert ends["terminated"] > 0 and ends["truncated"] > 0        # both kinds of end were met
    env.close()


@pytest.mark.parametrize("base", _bases())
def test_seeds_are_used_once_and_attributes_are_the_batched_envs(base):
    env = native_vec_env(N, base=base, **ENV)
    single = gym.make(pendulum_lqg.ENV_ID, **{k: v for k, v in ENV.items()
                                              if k != "max_episode_steps"})
    assert env.seed(5) == [5, 6, 7]
    first = env.reset()
    np.testing.assert_array_equal(first[2], single.reset(seed=7)[0])
    again = env.reset()                     # no new seed: the generators continue
    np.testing.assert_array_equal(again[2], single.reset()[0])
    assert not np.array_equal(first, again)
    assert env.get_attr("dt") == [0.01] * N and env.get_attr("dt", indices=1) == [0.01]
    env.set_attr("note", "x")
    assert env.get_attr("note", indices=[0, 2]) == ["x", "x"]
    called = env.env_method("reset", seed=3)     # one call on the batched env, its result per row
    assert len(called) == N and called[0] is called[2]
    np.testing.assert_array_equal(called[0][0][1], single.reset(seed=4)[0])
    assert env.env_is_wrapped(gym.Wrapper) == [False] * N
    with pytest.raises(ConfigError, match=r"^indices: set_attr\('note'\) acts on the whole"):
        env.set_attr("note", "y", indices=[1])
    with pytest.raises(ConfigError, match=r"^indices: expected sub-envs 0 … 2, got 3"):
        env.get_attr("dt", indices=[3])
    with pytest.raises(ConfigError, match=r"^autoreset_mode: SB3's VecEnv resets in the same step"):
        native_vec_env(N, base=base, autoreset_mode="next_step")
    env.close()


def test_without_stable_baselines3_the_adapter_is_one_line(monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "stable_baselines3", None)     # import fails
    monkeypatch.setitem(sys.modules, "stable_baselines3.common", None)  # also once imported
    monkeypatch.setitem(sys.modules, "stable_baselines3.common.vec_env", None)
    with pytest.raises(ConfigError, match=r"^native_vec_env needs stable-baselines3 \(install"):
        native_vec_env(N)
