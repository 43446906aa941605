"""The RL baselines' training script, a few hundred steps (only where the rl extra is installed)."""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import pytest

pytest.importorskip("stable_baselines3", reason="the rl extra (stable-baselines3, torch) is absent")

ROOT = Path(__file__).resolve().parents[2]


def test_a_short_training_saves_a_model_its_record_and_scores_through_the_adapter(tmp_path):
    spec = importlib.util.spec_from_file_location("train_agents", ROOT / "benchmarks" / "train_agents.py")
    train_agents = importlib.util.module_from_spec(spec)
    sys.modules["train_agents"] = train_agents
    spec.loader.exec_module(train_agents)
    path = train_agents.train("ppo-lecture", tmp_path, steps=512)
    record = json.loads(path.with_suffix(".json").read_text())
    assert record["algo"] == "PPO" and record["frame_stack"] == 8
    assert len(record["obs_norm"]["mean"]) == 2 * 8 and record["budget"]["steps"] == 512
    from pendulum_lqg.scoreboard import episodes as ep
    from pendulum_lqg.scoreboard.suites import load_suite

    factory = ep.load_agent(f"sb3:{path}")
    rows = ep.agent_rows(load_suite("lecture").with_episodes(2), factory,
                         normalize_action=factory.normalize_action)
    assert [r["episode"] for r in rows] == [0, 1] and all(r["cost"] > 0 for r in rows)
