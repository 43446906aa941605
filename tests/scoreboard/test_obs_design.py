"""Observation designs: the history of (y, previous action), the frame stack and the normalisation,
by hand and as a cross-check: the training wrapper's observations are exactly what the scoring
agent rebuilds from the training record on the same episode."""

from __future__ import annotations

import dataclasses
import importlib.util

import gymnasium as gym
import numpy as np
import pytest

import pendulum_lqg
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.scoreboard.obs_design import (
    ObservationDesign,
    ObservationHistory,
    history_vec_env,
    normalise,
)
from pendulum_lqg.scoreboard.sb3 import SB3Agent
from pendulum_lqg.scoreboard.sb3_vec import native_vec_env
from tests.scoreboard.test_sb3_vec import StandInVecEnv

ENV = {"normalize_action": True, "theta_max": 0.3, "x0_std": [0.0, 0.05, 0.0, 0.0],
       "duration": 1.0}


class StandInWrapper(StandInVecEnv):
    """The part of SB3's ``VecEnvWrapper`` the design wrapper relies on."""

    def __init__(self, venv, observation_space=None, action_space=None):
        self.venv = venv
        super().__init__(venv.num_envs, observation_space or venv.observation_space,
                         action_space or venv.action_space)

    def get_attr(self, attr_name, indices=None):
        return self.venv.get_attr(attr_name, indices)

    def close(self):
        self.venv.close()


def _bases():
    out = [pytest.param((StandInVecEnv, StandInWrapper), id="stand-in")]
    if importlib.util.find_spec("stable_baselines3") is not None:
        out.append(pytest.param((None, None), id="stable-baselines3"))
    return out


def test_the_history_holds_y_and_the_previous_clipped_action_newest_last():
    h = ObservationHistory(ObservationDesign(3, past_actions=True), 1, 2, [-1.0], [1.0])
    np.testing.assert_array_equal(h.reset(np.array([[1.0, 2.0]])), [[0, 0, 0, 0, 0, 0, 1, 2, 0]])
    np.testing.assert_array_equal(h.step(np.array([[3.0, 4.0]]), np.array([[5.0]])),
                                  [[0, 0, 0, 1, 2, 0, 3, 4, 1]])             # 5 clipped to 1
    np.testing.assert_array_equal(h.peek(np.array([0]), np.array([[7.0, 8.0]]), np.array([[0.5]])),
                                  [[1, 2, 0, 3, 4, 1, 7, 8, 0.5]])           # not kept:
    np.testing.assert_array_equal(h.step(np.array([[np.nan, np.nan]]), np.array([[-0.5]])),
                                  [[1, 2, 0, 3, 4, 1, 3, 4, -0.5]])          # a lost y is held
    frames = ObservationHistory(ObservationDesign(2), 1, 2, [-1.0], [1.0])
    np.testing.assert_array_equal(frames.reset(np.array([[np.nan, np.nan]])), [[0, 0, 0, 0]])
    norm = {"mean": [1.0, 0.0], "var": [4.0, 1.0], "epsilon": 0.0, "clip": 2.0}
    np.testing.assert_array_equal(normalise(np.array([[3.0, -9.0]]), norm), [[1.0, -2.0]])
    with pytest.raises(ConfigError, match=r"^frame_stack: expected a positive integer, got 0"):
        ObservationDesign(0)


class _Linear:
    """stable-baselines3's predict: a fixed linear policy of what it sees; records its inputs."""

    def __init__(self, size):
        self.gain = np.linspace(-1.0, 1.0, size)[:, None] * 0.3
        self.seen = []

    def predict(self, observation, state=None, episode_start=None, deterministic=False):
        self.seen.append(np.array(observation, dtype=float))
        return np.tanh(observation @ self.gain), state


@pytest.mark.parametrize("bases", _bases())
@pytest.mark.parametrize("design", [ObservationDesign(4, past_actions=True), ObservationDesign(3),
                                    ObservationDesign(2, past_actions=True, estimator="kalman")],
                         ids=["history", "frames", "kalman"])
def test_training_observations_are_what_the_scorer_rebuilds_from_the_record(bases, design):
    vec_base, wrapper_base = bases
    n, seed = 2, 21
    venv = history_vec_env(native_vec_env(n, base=vec_base, seed=seed, **ENV), design,
                           base=wrapper_base, normalize_action=True)
    norm = {"mean": np.full(venv.observation_space.shape[0], 0.1).tolist(),
            "var": np.full(venv.observation_space.shape[0], 2.0).tolist(), "clip": 5.0,
            "epsilon": 1e-8}
    policy = _Linear(venv.observation_space.shape[0])
    trained_on, obs, row0_done = [], venv.reset(), False
    while not row0_done:                           # row 0's first episode, as training sees it
        seen = normalise(obs, norm)
        trained_on.append(seen[0])
        actions = policy.predict(seen)[0]
        obs, _, dones, infos = venv.step(actions)
        row0_done = bool(dones[0])
    assert len(trained_on) > 10                    # an episode of some length, not one step
    terminal = infos[0]["terminal_observation"]
    assert terminal.shape == (venv.observation_space.shape[0],)
    record = design.record()
    assert record == {"frame_stack": design.frame_stack, "past_actions": design.past_actions,
                      **({"estimator": "kalman"} if design.estimator else {})}
    env = gym.make(pendulum_lqg.ENV_ID, **ENV)
    agent = SB3Agent(_Linear(terminal.size), obs_norm=norm, low=env.action_space.low,
                     high=env.action_space.high, config=env.unwrapped.config,
                     normalize_action=True, **record)
    y, _ = env.reset(seed=seed)                   # row 0 = a single env reset with the seed
    agent.reset()
    for _ in trained_on:
        y, *_ = env.step(agent.act(y))
    np.testing.assert_allclose(np.concatenate(agent.model.seen), np.array(trained_on),
                               rtol=0, atol=1e-12)
    if design.past_actions:                        # the ended step's action is in its last frame
        last = np.tanh(trained_on[-1] @ policy.gain)
        assert terminal[-1] == pytest.approx(float(np.clip(last, -1, 1)[0]))
    venv.close()


class _Recurrent(_Linear):
    """A stand-in recurrent policy: its state (one number per row) counts the row's steps since
    its episode start, and the action depends on it (so a state mixed between rows shows)."""

    def predict(self, observation, state=None, episode_start=None, deterministic=False):
        n = observation.shape[0]
        count = np.zeros(n) if state is None else np.where(episode_start, 0.0, state[0])
        count = count + 1.0
        action = np.tanh(observation @ self.gain) * (1.0 - 0.5 * np.exp(-count[:, None] / 10))
        return action, (count,)


@pytest.mark.parametrize("model_class", [_Linear, _Recurrent], ids=["mlp", "recurrent"])
def test_batched_scoring_gives_the_rows_of_the_one_episode_path(tmp_path, model_class,
                                                                monkeypatch):
    from pendulum_lqg.scoreboard import episodes as ep
    from pendulum_lqg.scoreboard import sb3_batch
    from pendulum_lqg.scoreboard.sb3 import SB3Factory
    from pendulum_lqg.scoreboard.sb3_batch import batched_rows
    from pendulum_lqg.scoreboard.suites import load_suite

    suite = load_suite("lossy").with_episodes(5)          # dropout: the held samples too
    suite = dataclasses.replace(suite, env={**suite.env, "duration": 0.3, "theta_max": 0.3,
                                            "x0_std": [0.0, 0.15, 0.0, 0.0]})
    design = ObservationDesign(4, past_actions=True)
    size = 4 * 3
    norm = {"mean": [0.0] * size, "var": [0.5] * size, "clip": 10.0, "epsilon": 1e-8}
    (tmp_path / "m.zip").write_bytes(b"stand-in")
    meta = {"algo": "PPO", "normalize_action": True, "env": {}, "obs_norm": norm,
            **design.record()}
    factory = SB3Factory(str(tmp_path / "m.zip"), meta, model_class(size))
    one = ep.agent_rows(suite, factory, normalize_action=True)
    monkeypatch.setattr(sb3_batch, "CHUNK", 2)            # 5 episodes in chunks of 2, 2, 1
    batched = batched_rows(suite, factory)
    assert [(r["episode"], r["seed"], r["success"], r["failure_reason"]) for r in batched] == \
        [(r["episode"], r["seed"], r["success"], r["failure_reason"]) for r in one]
    np.testing.assert_allclose([r["cost"] for r in batched], [r["cost"] for r in one],
                               rtol=1e-9)
    assert {r["success"] for r in one} == {True, False}     # both ends were played
