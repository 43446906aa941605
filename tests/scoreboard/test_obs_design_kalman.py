"""The observation design ``estimator = "kalman"`` (PPO on x̂): the frames are the reference
steady-state Kalman filter's estimates, checked against the reference's own estimator on the
same episodes, and a stand-in model that is the LQR on those frames scores as the LQG reference."""

from __future__ import annotations

import dataclasses
import json

import gymnasium as gym
import numpy as np
import pytest

import pendulum_lqg
from pendulum_lqg.core.rules import saturate
from pendulum_lqg.envs.agent import LQGAgent
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.policies.loading import build_policy
from pendulum_lqg.scoreboard.obs_design import ObservationDesign, ObservationHistory

#: lossy: lost samples (nan) take the filter's prediction step; a short episode
LOSSY = {"dropout": 0.3, "duration": 1.0, "x0_std": [0.0, 0.05, 0.0, 0.0]}


@pytest.mark.parametrize("normalize", [False, True], ids=["newtons", "normalized"])
def test_the_frames_are_the_reference_kalman_filters_estimates_on_the_same_episode(normalize):
    env = gym.make(pendulum_lqg.ENV_ID, normalize_action=normalize, **LOSSY)
    reference = LQGAgent(env, observer="kalman")         # the reference's estimator, driving
    design = ObservationDesign(3, past_actions=True, estimator="kalman")
    space = env.action_space
    history = ObservationHistory(design, 1, 2, space.low, space.high,
                                 config=env.unwrapped.config, normalize_action=normalize)
    y, _ = env.reset(seed=5)
    reference.reset()
    stack = history.reset(y[None, :])
    seen, lost = [], 0
    for _ in range(100):
        action = reference.act(y)
        seen.append((stack[0, -5:-1].copy(), reference.policy.x_hat[0].copy()))
        lost += int(not np.isfinite(y).all())
        y, _, terminated, truncated, _ = env.step(action)
        stack = history.step(y[None, :], action[None, :])
        if terminated or truncated:
            break
    assert len(seen) == 100 and lost > 10               # a whole episode, with lost samples
    ours, theirs = map(np.array, zip(*seen, strict=True))
    if normalize:      # the env's map back to newtons rounds a + 1: a few ulps of 10 N
        np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-12)
    else:              # the same floats: the same estimator fed the same y and forces
        np.testing.assert_array_equal(ours, theirs)
    assert np.abs(theirs[:, 2:]).max() > 0.05           # velocities estimated, not zeros
    assert stack.shape == (1, 3 * (4 + 1))


def test_a_lost_first_sample_and_the_design_errors():
    config = gym.make(pendulum_lqg.ENV_ID).unwrapped.config
    h = ObservationHistory(ObservationDesign(1, estimator="kalman"), 2, 2, [-10.0], [10.0],
                           config=config, normalize_action=False)
    first = h.reset(np.array([[np.nan, np.nan], [0.1, 0.2]]))
    np.testing.assert_array_equal(first[0], np.zeros(4))   # no sample: the prior x̂₀ = 0
    assert np.all(first[1] != 0.0)                        # a sample: x̂ = L y
    with pytest.raises(ConfigError, match=r"^estimator: expected one of kalman \(or none\), "):
        ObservationDesign(estimator="luenberger")
    with pytest.raises(ConfigError, match=r"^estimator: 'kalman' needs the env's config"):
        ObservationHistory(ObservationDesign(estimator="kalman"), 1, 2, [-1.0], [1.0])
    state = gym.make(pendulum_lqg.ENV_ID, observation_mode="state").unwrapped.config
    with pytest.raises(ConfigError, match=r"^estimator: 'kalman' estimates x from y"):
        ObservationHistory(ObservationDesign(estimator="kalman"), 1, 4, [-1.0], [1.0],
                           config=state, normalize_action=False)


class _LQROnEstimate:
    """stable-baselines3's predict: the DLQR ``u = sat(−K x̂)`` on the frames it is shown (the
    design's x̂), as a normalised action; counts its calls and the rows of each."""

    def __init__(self, K, u_max):
        self.K, self.u_max, self.calls = K, u_max, []

    def predict(self, observation, state=None, episode_start=None, deterministic=False):
        self.calls.append(observation.shape[0])
        u = saturate(-observation @ self.K.T, self.u_max)
        return u / self.u_max, state


def test_a_model_that_is_the_lqr_on_the_frames_scores_as_the_lqg_reference(tmp_path):
    from pendulum_lqg.scoreboard import episodes as ep
    from pendulum_lqg.scoreboard.sb3 import SB3Factory
    from pendulum_lqg.scoreboard.sb3_batch import batched_rows
    from pendulum_lqg.scoreboard.suites import load_suite

    suite = load_suite("lossy").with_episodes(4)
    suite = dataclasses.replace(suite, env={**suite.env, "duration": 2.0})
    policy = build_policy(suite.reference, plant=suite.plants()[1],
                             scenario=suite.config.scenario)
    design = ObservationDesign(1, estimator="kalman")
    (tmp_path / "m.zip").write_bytes(b"stand-in")
    meta = {"algo": "PPO", "normalize_action": True, "env": {}, "obs_norm": None,
            **design.record()}
    factory = SB3Factory(str(tmp_path / "m.zip"), meta, _LQROnEstimate(policy.K, policy.u_max))
    reference = ep.policy_rows(suite, suite.reference, nthread=1)
    for rows in (batched_rows(suite, factory), ep.agent_rows(suite, factory,
                                                             normalize_action=True)):
        assert [(r["success"], r["failure_reason"]) for r in rows] == \
            [(r["success"], r["failure_reason"]) for r in reference]
        np.testing.assert_allclose([r["cost"] for r in rows], [r["cost"] for r in reference],
                                   rtol=1e-9)
    assert json.loads(json.dumps(meta))["estimator"] == "kalman"
