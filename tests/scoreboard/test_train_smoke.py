"""The RL baselines' training script, a few thousand steps (only where the rl extra is installed):
one run writes its model, its training record and its learning curve, and the scorer rebuilds the
run's observation design from the record."""

from __future__ import annotations

import csv
import importlib.util
import json
import sys
from pathlib import Path

import pytest

pytest.importorskip("stable_baselines3", reason="the rl extra (stable-baselines3, torch) is absent")

ROOT = Path(__file__).resolve().parents[2]


def test_a_short_run_saves_its_model_record_and_curve_and_scores_with_its_design(tmp_path):
    spec = importlib.util.spec_from_file_location("train_agents", ROOT / "benchmarks" / "train_agents.py")
    train_agents = importlib.util.module_from_spec(spec)
    sys.modules["train_agents"] = train_agents
    spec.loader.exec_module(train_agents)
    model, venv, _ = train_agents.build(train_agents.METHODS["sac-history"], 2)
    native = venv.unwrapped                       # below VecNormalize and the history wrapper
    n_envs = train_agents.METHODS["sac-history"].envs
    assert native._seeds == [train_agents.TRAIN_SEED_BASE + 2000 + i for i in range(n_envs)]
    assert model.seed == 2
    path = train_agents.train("ppo-history", tmp_path, seed=1, steps=512, eval_every=512)
    assert path.name == "ppo-history-seed1.zip"
    record = json.loads(path.with_suffix(".json").read_text())
    assert record["method"] == "ppo-history" and record["seed"] == 1 and record["algo"] == "PPO"
    assert record["frame_stack"] == 32 and record["past_actions"] is True
    assert len(record["obs_norm"]["mean"]) == 32 * 3 and record["budget"]["steps"] == 16 * 256
    assert record["budget"]["steps_requested"] == 512
    with (tmp_path / "ppo-history-seed1-curve.csv").open() as f:
        curve = list(csv.DictReader(f))
    assert [int(r["env_steps"]) for r in curve] == [16 * 256]      # one PPO rollout of 16 envs
    assert 0.0 <= float(curve[0]["success_rate"]) <= 1.0
    from pendulum_lqg.scoreboard import episodes as ep
    from pendulum_lqg.scoreboard.suites import load_suite

    factory = ep.load_agent(f"sb3:{path}")
    assert factory.run["method"] == "ppo-history" and factory.run["seed"] == 1
    rows = ep.agent_rows(load_suite("lecture").with_episodes(2), factory,
                         normalize_action=factory.normalize_action)
    assert [r["episode"] for r in rows] == [0, 1] and all(r["cost"] > 0 for r in rows)
