"""The scoreboard: suites, the two paths of scoring, the score's figures, the board."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from pendulum_lqg.cli import main
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.scoreboard import episodes as ep
from pendulum_lqg.scoreboard.board import make_board
from pendulum_lqg.scoreboard.sb3 import SB3Agent
from pendulum_lqg.scoreboard.score import optimality_gap, success_figures
from pendulum_lqg.scoreboard.suites import SUITE_ORDER, load_suite, parse_suite, suite_names

ROOT = Path(__file__).resolve().parents[2]
PLUGIN = str(ROOT / "experiments" / "plugin_lqg.py") + ":make"
OUTSIDE_AGENT = str(ROOT / "experiments" / "agents" / "python_control_lqg.py") + ":make"


def test_seven_suites_ship_and_each_reference_follows_the_one_rule():
    assert suite_names() == list(SUITE_ORDER)
    for name in suite_names():
        s = load_suite(name)
        assert s.name == name and s.episodes >= 100 and s.version >= 1
        assert s.reference == ep.reference_design(s.config.observation_mode, s.config.scenario)
        assert len(s.fingerprint()) == 64 and s.fingerprint() == load_suite(name).fingerprint()
    assert load_suite("lecture").with_episodes(10).fingerprint() != load_suite("lecture").fingerprint()


def test_a_bad_suite_file_is_a_one_line_error_naming_the_key():
    base = {"name": "x", "version": 1, "purpose": "p", "reference": "dlqr+kalman",
            "episodes": 5, "seed": 0}
    with pytest.raises(ConfigError, match=r"unknown key 'colour'"):
        parse_suite({**base, "colour": 1})
    with pytest.raises(ConfigError, match=r"\[env\] noise_sclae: not a keyword"):
        parse_suite({**base, "env": {"noise_sclae": 2}})
    with pytest.raises(ConfigError, match=r"episodes: expected a positive integer"):
        parse_suite({**base, "episodes": 0})
    with pytest.raises(ConfigError, match=r"suite: no suite 'nope'"):
        load_suite("nope")


def test_the_gap_is_the_ratio_of_mean_costs_on_common_survivors():
    rows = [{"episode": k, "success": ok, "cost": c} for k, (ok, c) in
            enumerate([(True, 2.0), (True, 4.0), (False, 0.5), (True, 9.0)])]
    ref = [{"episode": k, "success": ok, "cost": c} for k, (ok, c) in
           enumerate([(True, 1.0), (True, 3.0), (True, 1.0), (False, 1.0)])]
    g = optimality_gap(rows, ref)
    assert g["gap_episodes"] == 2                         # episodes 0 and 1 only
    assert g["optimality_gap"] == pytest.approx((2.0 + 4.0) / (1.0 + 3.0) - 1.0)
    lo, hi = g["gap_ci"]
    assert 1.0 / 3.0 - 1 <= lo <= g["optimality_gap"] <= hi <= 2.0 - 1     # within the pair range
    assert optimality_gap(rows, rows)["optimality_gap"] == 0.0
    assert optimality_gap(rows, rows)["gap_ci"] == [0.0, 0.0]
    none = optimality_gap([{**r, "success": False} for r in rows], ref)
    assert none["optimality_gap"] is None and none["gap_episodes"] == 0
    fig = success_figures(rows)
    assert fig["success_rate"] == 0.75 and fig["cost_mean"] == pytest.approx(5.0)
    assert fig["success_ci"][0] < 0.75 < fig["success_ci"][1]


def test_a_plugin_and_its_gymnasium_twin_give_identical_rows():
    for name in ("lecture", "lossy"):
        suite = load_suite(name).with_episodes(6)
        batch = ep.policy_rows(suite, PLUGIN)
        gym_rows = ep.agent_rows(suite, ep.plugin_agent(PLUGIN))
        assert batch == gym_rows                                       # bit for bit


def test_the_lqg_agent_through_the_env_equals_the_reference_through_the_batch():
    for name in ("lecture", "delayed", "full-state"):
        suite = load_suite(name).with_episodes(4)
        assert ep.agent_rows(suite, ep.reference_agent) == ep.policy_rows(suite, suite.reference)


def test_score_of_the_reference_has_gap_zero_and_the_documented_success(capsys, tmp_path):
    out = tmp_path / "ref.json"
    assert main(["score", "dlqr+kalman", "--suite", "lecture", "--episodes", "12", "--json",
                 "--out", str(out)]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert doc == json.loads(out.read_text())
    e = doc["suites"]["lecture"]
    assert e["optimality_gap"] == 0.0 and e["gap_ci"] == [0.0, 0.0]
    assert e["success_rate"] == 1.0 == e["reference"]["success_rate"]
    assert e["reference"]["policy"] == "dlqr+kalman" and e["episodes"] == 12
    assert e["full_state_bound"]["cost_mean"] < e["cost_mean"] / 5     # observation costs a lot
    assert set(doc["versions"]) >= {"pendulum_lqg", "mujoco", "numpy"}
    assert e["fingerprint"] == load_suite("lecture").with_episodes(12).fingerprint()


def test_an_agent_written_outside_the_package_scores_near_the_reference(capsys):
    assert main(["score", "--agent", OUTSIDE_AGENT, "--suite", "lecture", "--episodes", "20",
                 "--json"]) == 0
    e = json.loads(capsys.readouterr().out)["suites"]["lecture"]
    assert e["success_rate"] == 1.0
    assert abs(e["optimality_gap"]) < 0.05                     # its own LQR + Kalman filter


def test_a_zero_force_agent_scores_success_zero_with_a_clear_row(capsys, tmp_path):
    agent = tmp_path / "zero.py"
    agent.write_text("import numpy as np\n"
                     "class Zero:\n"
                     "    def reset(self): pass\n"
                     "    def act(self, obs): return np.zeros(1)\n"
                     "def make(env): return Zero()\n")
    assert main(["score", "--agent", f"{agent}:make", "--suite", "lecture", "--episodes",
                 "5"]) == 0
    out = capsys.readouterr().out
    assert "| lecture | 5 | 0 % [0, 43] | – | – |" in out


def test_bad_score_arguments_are_one_line_errors(capsys):
    assert main(["score", "--suite", "lecture"]) == 2
    assert capsys.readouterr().err.strip() == "error: score: give one POLICY or one --agent REF"
    assert main(["score", "--agent", "no_such_module:make", "--suite", "lecture"]) == 2
    assert capsys.readouterr().err.startswith("error: ")
    assert main(["score", "--agent", "sb3:/nonexistent.zip", "--suite", "lecture"]) == 2
    assert "no such model file" in capsys.readouterr().err


def test_suite_all_gives_a_row_per_suite_and_says_where_a_policy_does_not_apply(capsys):
    assert main(["score", "dlqr+kalman", "--suite", "all", "--episodes", "2", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    assert list(doc["suites"]) == list(SUITE_ORDER)                     # seven rows
    full = doc["suites"]["full-state"]
    assert full["applicable"] is False and "gives the true state" in full["reason"]
    assert all(doc["suites"][s]["applicable"] for s in SUITE_ORDER[1:])
    assert main(["score", "dlqr+none", "--suite", "lecture", "--suite", "full-state",
                 "--episodes", "2"]) == 0
    out = capsys.readouterr().out
    assert "| lecture | 2 | not applicable: policy 'dlqr+none' needs the true state" in out
    assert "| full-state | 2 | 100 % [" in out


class _StandIn:
    """stable-baselines3's predict signature: a linear policy of the stacked observation."""

    def __init__(self, gain: np.ndarray) -> None:
        self.gain, self.calls = gain, []

    def predict(self, observation, state=None, episode_start=None, deterministic=False):
        self.calls.append((observation.copy(), state, episode_start.copy(), deterministic))
        return observation @ self.gain, ("lstm", len(self.calls))


def test_the_sb3_adapter_stacks_normalises_and_carries_the_recurrent_state():
    """VecNormalize(VecFrameStack(env)): stack the raw observations (zeros before the first),
    then normalise the stack with the frozen statistics and clip."""
    model = _StandIn(np.arange(6.0)[:, None])
    mean, var = np.array([0.0, 0.0, 1.0, 0.0, 1.0, 0.0]), np.array([1, 1, 4, 1, 4, 1.0])
    agent = SB3Agent(model, frame_stack=3, obs_norm={"mean": mean, "var": var, "epsilon": 0.0,
                                                     "clip": 5.0})
    agent.reset()
    a1 = agent.act(np.array([3.0, 1.0]))
    a2 = agent.act(np.array([1.0, 100.0]))             # 100 is clipped to 5
    np.testing.assert_array_equal(model.calls[0][0], [[0, 0, -0.5, 0, 1, 1]])
    np.testing.assert_array_equal(model.calls[1][0], [[0, 0, 1, 1, 0, 5]])
    assert a1.shape == (1,) and a1[0] == -1 + 4 + 5 and a2[0] == 2 + 3 + 25
    assert model.calls[0][1] is None and model.calls[1][1] == ("lstm", 1)    # state carried
    assert model.calls[0][2].tolist() == [True] and model.calls[1][2].tolist() == [False]
    assert all(c[3] is True for c in model.calls)                            # deterministic
    agent.reset()
    agent.act(np.array([1.0, 0.0]))
    np.testing.assert_array_equal(model.calls[2][0], [[0, 0, -0.5, 0, 0, 0]])
    assert model.calls[2][1] is None and model.calls[2][2].tolist() == [True]
    agent.act(np.array([np.nan, np.nan]))           # a lost sample: the last one is held
    np.testing.assert_array_equal(model.calls[3][0], [[0, 0, 0, 0, 0, 0]])
    agent.reset()
    agent.act(np.array([np.nan, np.nan]))           # nothing received yet: zeros
    np.testing.assert_array_equal(model.calls[4][0], [[0, 0, -0.5, 0, -0.5, 0]])


def test_the_board_tabulates_comparable_scores_and_lists_the_rest(capsys, tmp_path):
    for args in (["dlqr+kalman"], ["dlqr+luenberger"]):
        assert main(["score", *args, "--suite", "lecture", "--episodes", "4",
                     "--out", str(tmp_path / f"{args[0]}.json")]) == 0
    assert main(["score", "dlqr+kalman-tv", "--suite", "lecture", "--episodes", "3",
                 "--out", str(tmp_path / "short.json")]) == 0
    capsys.readouterr()
    table = make_board(tmp_path)
    lines = table.splitlines()
    assert lines[0].startswith("| entry | kind | lecture: success | lecture: J | lecture: gap |")
    kalman = next(line for line in lines if line.startswith("| `dlqr+kalman` |"))
    assert "| 100 % |" in kalman and "+0.00 [+0.00, +0.00]" in kalman
    assert any(line.startswith("| `dlqr+luenberger` |") for line in lines)
    assert "Not comparable" in table and "`dlqr+kalman-tv` on `lecture`" in table
    assert main(["board", str(tmp_path), "--out", str(tmp_path / "board.md")]) == 0
    assert capsys.readouterr().out == table == (tmp_path / "board.md").read_text()


def test_the_committed_leaderboard_is_what_board_makes_of_the_committed_scores():
    """docs/leaderboard/board.md is regenerated by `pendulum-lqg board docs/leaderboard/scores`,
    and it has the rows the Leaderboard page promises."""
    folder = ROOT / "docs" / "leaderboard"
    table = make_board(folder / "scores")
    assert table == (folder / "board.md").read_text()
    entries = [line.split(" | ")[0].removeprefix("| ") for line in table.splitlines()[2:]
               if line.startswith("| `")]
    rl = [e for e in entries if e.startswith("`sb3:")]
    assert len(rl) >= 4 and "`dlqr+kalman`" in entries and "`dlqr+luenberger`" in entries
    assert "`experiments/plugin_lqg.py:make`" in entries
    assert "`pendulum_lqg.scoreboard.episodes:reference_agent`" in entries
