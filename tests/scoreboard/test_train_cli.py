"""benchmarks/train_agents.py's command line without the rl extra: the methods list, the run's
file names and the refusal of bad numbers (nothing is trained here)."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import load_benchmark_script

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def train_agents():
    return load_benchmark_script("train_agents", "train_agents_cli")


def test_list_names_every_method_with_its_budget(train_agents, capsys):
    assert train_agents.main(["--list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in lines] == list(train_agents.METHODS)
    assert any(line.startswith("ppo-history") and "1,000,000 steps" in line for line in lines)
    assert train_agents.run_name("sac-history", 4) == "sac-history-seed4"


def test_the_methods_declare_designs_the_scorer_can_rebuild(train_agents):
    from pendulum_lqg.boundary.schemas import ALGORITHMS
    from pendulum_lqg.scoreboard.obs_design import ObservationDesign
    from pendulum_lqg.scoreboard.suites import load_suite

    for m in train_agents.METHODS.values():
        assert m.algo in ALGORITHMS and load_suite(m.suite).name == m.suite
        assert m.design() == ObservationDesign(m.frame_stack, m.past_actions, m.estimator)
    suite = train_agents.eval_suite(load_suite("lecture"))
    assert (suite.seed, suite.episodes) == (train_agents.EVAL_SEED, 20)
    assert suite.seed != load_suite("lecture").seed                # never a suite's episodes


@pytest.mark.parametrize(("args", "message"), [
    (["ppo-history", "--seed", "-1"], "--seed: expected a non-negative integer, got -1"),
    (["ppo-history", "--steps", "0"], "--steps: expected a positive integer, got 0"),
    (["ppo-history", "--eval-every", "0"], "--eval-every: expected a positive integer, got 0"),
])
def test_bad_numbers_exit_2_with_one_line(train_agents, capsys, args, message):
    with pytest.raises(SystemExit) as exc:
        train_agents.main(args)
    assert exc.value.code == 2 and message in capsys.readouterr().err


def test_ppo_kalman_is_ppo_history_on_the_kalman_estimate(train_agents):
    kalman, history = train_agents.METHODS["ppo-kalman"], train_agents.METHODS["ppo-history"]
    assert kalman.design().record() == {"frame_stack": 1, "past_actions": False,
                                        "estimator": "kalman"}
    assert (kalman.algo, kalman.suite, kalman.steps, kalman.envs, kalman.kwargs) == \
        (history.algo, history.suite, history.steps, history.envs, history.kwargs)
    assert "estimator" not in history.design().record()      # today's records keep their keys


def test_the_noise_ladder_names_its_runs_and_trains_at_the_scale(train_agents):
    assert train_agents.method_name("ppo-history", None) == "ppo-history"
    assert train_agents.method_name("ppo-history", 0.25) == "ppo-history-noise0.25"
    assert train_agents.method_name("ppo-history", 1.0) == "ppo-history-noise1"
    m = train_agents.METHODS["ppo-history"]
    assert train_agents.training_suite(m, 0.5).env["noise_scale"] == 0.5
    assert "noise_scale" not in train_agents.training_suite(m).env


def test_a_negative_noise_scale_exits_2_with_one_line(train_agents, capsys):
    with pytest.raises(SystemExit) as exc:
        train_agents.main(["ppo-history", "--noise-scale", "-0.5"])
    assert exc.value.code == 2
    assert "--noise-scale: expected a finite number ≥ 0, got -0.5" in capsys.readouterr().err
