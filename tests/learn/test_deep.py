"""The SB3 methods of ``pendulum-lqg train`` (only where the rl extra is installed): a short run
writes its model, record and curve and the scorer rebuilds the run's observation design from the
record; a run stopped by Ctrl-C leaves a checkpoint (model, VecNormalize statistics) and
``--resume`` completes it, its curve identical to an uninterrupted run's up to the checkpoint."""

from __future__ import annotations

import csv
import json
import os
import signal

import pytest

pytest.importorskip("stable_baselines3", reason="the rl extra (stable-baselines3, torch) is absent")

from pendulum_lqg.cli import main


def _curve(path):
    with path.open() as f:
        return list(csv.DictReader(f))


def test_a_short_run_saves_its_model_record_and_curve_and_scores_with_its_design(
        tmp_path, few_curve_episodes):
    from pendulum_lqg.learn.deep import METHODS, TRAIN_SEED_BASE, build, training_suite

    m = METHODS["sac-history"]
    model, venv = build(m, 2, training_suite(m))
    native = venv.unwrapped                       # below VecNormalize and the history wrapper
    assert native._seeds == [TRAIN_SEED_BASE + 2000 + i for i in range(m.envs)]
    assert model.seed == 2
    assert main(["train", "ppo-history", "--seed", "1", "--steps", "512", "--eval-every", "512",
                 "--out", str(tmp_path)]) == 0
    path = tmp_path / "ppo-history-seed1.zip"
    record = json.loads(path.with_suffix(".json").read_text())
    assert record["method"] == "ppo-history" and record["seed"] == 1 and record["algo"] == "PPO"
    assert record["frame_stack"] == 32 and record["past_actions"] is True
    assert len(record["obs_norm"]["mean"]) == 32 * 3 and record["budget"]["steps"] == 16 * 256
    assert record["budget"]["steps_requested"] == 512
    curve = _curve(tmp_path / "ppo-history-seed1-curve.csv")
    assert [int(r["env_steps"]) for r in curve] == [16 * 256]      # one PPO rollout of 16 envs
    assert 0.0 <= float(curve[0]["success_rate"]) <= 1.0
    assert float(curve[0]["train_length"]) > 0                       # training episodes logged
    assert not list(tmp_path.glob("*checkpoint*"))
    from pendulum_lqg.scoreboard import episodes as ep
    from pendulum_lqg.scoreboard.suites import load_suite

    factory = ep.load_agent(f"sb3:{path}")
    assert factory.run["method"] == "ppo-history" and factory.run["seed"] == 1
    rows = ep.agent_rows(load_suite("lecture").with_episodes(2), factory,
                         normalize_action=factory.normalize_action)
    assert [r["episode"] for r in rows] == [0, 1] and all(r["cost"] > 0 for r in rows)


def test_sb3_run_stopped_by_ctrl_c_resumes_from_its_checkpoint(tmp_path, monkeypatch, capsys,
                                                              few_curve_episodes):
    from pendulum_lqg.learn.curve import Curve

    args = ["train", "ppo-history", "--seed", "5", "--steps", "8192", "--eval-every", "4096"]
    assert main([*args, "--out", str(tmp_path / "whole")]) == 0
    add = Curve.add

    def add_then_stop(self, env_steps, rows, **kw):
        point = add(self, env_steps, rows, **kw)
        os.kill(os.getpid(), signal.SIGINT)
        return point

    monkeypatch.setattr(Curve, "add", add_then_stop)
    cut = tmp_path / "cut"
    assert main([*args, "--out", str(cut)]) == 130
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err.startswith("stopped at 4112 steps") and err.endswith("--resume")
    assert sorted(p.name for p in cut.iterdir()) == [
        "ppo-history-seed5-checkpoint-vecnormalize.pkl", "ppo-history-seed5-checkpoint.json",
        "ppo-history-seed5-checkpoint.zip", "ppo-history-seed5-curve.csv"]
    monkeypatch.setattr(Curve, "add", add)
    assert main([*args, "--out", str(cut), "--resume"]) == 0
    record = json.loads((cut / "ppo-history-seed5.json").read_text())
    assert record["budget"]["steps"] >= 8192 and "resume_env_seeds" in record["budget"]
    whole, resumed = _curve(tmp_path / "whole" / "ppo-history-seed5-curve.csv"), _curve(
        cut / "ppo-history-seed5-curve.csv")
    assert len(resumed) == 2 and not list(cut.glob("*checkpoint*"))
    for row in (whole[0], resumed[0]):                # up to the checkpoint: the same run
        row.pop("wall_seconds")
    assert resumed[0] == whole[0]
