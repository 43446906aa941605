"""One set of episodes through the three paths of the core — a batch (``run_episodes``), the single
env (a one-row simulator) and the native vector env — gives the same rows, bit for bit."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import pendulum_lqg
from pendulum_lqg.core.runner import run_episodes
from pendulum_lqg.core.seeding import episode_seed
from pendulum_lqg.envs.agent import LQGAgent
from pendulum_lqg.policies.lqg import DesignSpec, design_policy
from pendulum_lqg.policies.lti import design_lti_policy

SEED, EPISODES = 5, 6


def _single(kwargs: dict) -> list[tuple[bool, float, str, float]]:
    env = gym.make(pendulum_lqg.ENV_ID, **kwargs)
    agent = LQGAgent(env)
    out = []
    for k in range(EPISODES):
        obs, _ = env.reset(seed=episode_seed(SEED, k))
        agent.reset()
        term = trunc = False
        while not (term or trunc):
            obs, _, term, trunc, info = env.step(agent.act(obs))
        out.append((not term, info["running_cost"], info["failure_reason"], info["time"]))
    return out


def _vector(kwargs: dict) -> list[tuple[bool, float, str, float]]:
    """Each sub-env's first episode; a sub-env that ends is reset (its later episode is ignored)."""
    envs = gym.make_vec(pendulum_lqg.ENV_ID, num_envs=EPISODES,
                        autoreset_mode=gym.vector.AutoresetMode.DISABLED, **kwargs)
    agent = LQGAgent(envs)
    obs, _ = envs.reset(seed=[episode_seed(SEED, k) for k in range(EPISODES)])
    agent.reset()
    rows: dict[int, tuple[bool, float, str, float]] = {}
    while len(rows) < EPISODES:
        obs, _, term, trunc, info = envs.step(agent.act(obs))
        ended = np.nonzero(term | trunc)[0]
        for r in ended.tolist():
            rows.setdefault(r, (not bool(term[r]), float(info["running_cost"][r]),
                                str(info["failure_reason"][r]), float(info["time"][r])))
        if ended.size and len(rows) < EPISODES:
            obs, _ = envs.reset(options={"reset_mask": np.isin(np.arange(EPISODES), ended)})
            agent.reset(ended)
    return [rows[k] for k in range(EPISODES)]


@pytest.mark.parametrize("kwargs", [
    {"duration": 3.0},
    {"duration": 2.0, "noise_scale": 6.0, "x0_std": (0.2, 0.1, 0.0, 0.0)},     # some fail
    {"plant": "double-cartpole", "duration": 2.0},                   # a plant file's plant
    {"plant": "double-cartpole", "duration": 2.0, "noise_scale": 8.0},          # some fail
])
def test_batch_single_env_and_vector_env_give_the_same_rows(kwargs):
    env = gym.make(pendulum_lqg.ENV_ID, **kwargs).unwrapped
    if env.config.plant_file is not None:
        policy = design_lti_policy(env.config.plant_file, "dlqr+kalman",
                                   u_max=env.action_map.hi)
    else:
        policy = design_policy(env.plant, env.scenario.control_period, env.scenario.noise,
                               DesignSpec("dlqr", "kalman"))
    batch = [(r["success"], r["cost"], r["failure_reason"],
              r["duration"] if r["success"] else r["time_to_failure"])
             for r in run_episodes(env.plant, env.scenario, policy, seed=SEED,
                                   episodes=range(EPISODES)).rows]
    single = _single(kwargs)
    vector = _vector(kwargs)
    assert [b[:3] for b in batch] == [s[:3] for s in single] == [v[:3] for v in vector]
    assert [s[3] for s in single] == [v[3] for v in vector]
    if "noise_scale" in kwargs:
        assert not all(b[0] for b in batch), "the noisy case should include failures"
