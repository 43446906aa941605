"""Issue 55 item 13: a plain ``model.save()`` zip scores once one documented command has written
its training record (no torch here: the model is a stand-in with SB3's ``predict``)."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from pendulum_lqg.scoreboard.sb3_record import main


class _LQROnState:
    """A stand-in SB3 model: ``predict`` is the full-state DLQR ``u = −K x`` of the suite."""

    def __init__(self, K):
        self.K = np.asarray(K, dtype=float)

    def predict(self, observation, state=None, episode_start=None, deterministic=False):
        return -(np.asarray(observation) @ self.K.T), None


def test_item13_a_plain_model_save_zip_scores_with_the_record_the_command_writes(tmp_path,
                                                                                capsys):
    from pendulum_lqg.policies.loading import build_policy
    from pendulum_lqg.scoreboard.episodes import agent_rows
    from pendulum_lqg.scoreboard.sb3 import SB3Factory, read_metadata
    from pendulum_lqg.scoreboard.suites import load_suite

    model = tmp_path / "my_ppo.zip"
    model.write_bytes(b"a stand-in for model.save('my_ppo')")
    assert main([str(model), "--algo", "PPO", "--observation-mode", "state"]) == 0
    assert capsys.readouterr().out == (f"wrote {tmp_path / 'my_ppo.json'}; score it with: "
                                       f"pendulum-lqg score --agent sb3:{model}\n")
    meta = read_metadata(model)                    # what score --agent sb3:my_ppo.zip reads
    assert meta["algo"] == "PPO" and meta["frame_stack"] == 1 and meta["obs_norm"] is None
    assert meta["env"] == {"observation_mode": "state"} and meta["normalize_action"] is False
    suite = load_suite("full-state").with_episodes(3)
    K = build_policy("dlqr+none", plant=suite.plants()[1], scenario=suite.config.scenario).K
    rows = agent_rows(suite, SB3Factory(str(model), meta, _LQROnState(K)))
    assert [r["success"] for r in rows] == [True, True, True]
    # the design flags reach the agent: a history of 8 [y, previous action] frames
    assert main([str(model), "--algo", "RecurrentPPO", "--frame-stack", "8", "--past-actions",
                 "--normalize-action", "--method", "mine", "--seed", "2", "--force"]) == 0
    meta = read_metadata(model)
    assert (meta["algo"], meta["frame_stack"], meta["past_actions"], meta["normalize_action"],
            meta["method"], meta["seed"]) == ("RecurrentPPO", 8, True, True, "mine", 2)


def test_item13_record_command_refuses_in_one_line(tmp_path):
    model = tmp_path / "m.zip"
    (tmp_path / "m.json").write_text(json.dumps({"algo": "PPO"}), encoding="utf-8")

    def run(*args):
        p = subprocess.run([sys.executable, "-m", "pendulum_lqg.scoreboard.sb3_record", *args],
                           capture_output=True, text=True, check=False)
        return p.returncode, p.stderr.strip()

    assert run(str(model), "--algo", "PPO") == (
        2, f"error: record: {tmp_path / 'm.json'} exists; give --force to replace it")
    assert json.loads((tmp_path / "m.json").read_text()) == {"algo": "PPO"}     # left as it was
    code, err = run(str(model), "--algo", "PPO", "--frame-stack", "1e12")
    assert (code, err) == (2, "error: --frame-stack: expected an integer from 1 to 10,000, "
                              "got '1e12'")
    code, err = run(str(tmp_path / "m.pkl"), "--algo", "PPO")
    assert code == 2 and err.startswith("error: model: expected the path of a stable-baselines3 zip")
    code, err = run(str(model), "--algo", "ppo")
    assert code == 2 and err.startswith("error: --algo: invalid choice: 'ppo'")


@pytest.mark.parametrize("flags", [[], ["--estimator", "kalman"]])
def test_item13_every_record_the_command_writes_passes_the_scorers_schema(tmp_path, flags):
    from pendulum_lqg.boundary.schemas import training_record

    model = tmp_path / "m.zip"
    assert main([str(model), "--algo", "SAC", *flags]) == 0
    doc = training_record(tmp_path / "m.json", where_text="agent")
    assert doc["estimator"] == (flags[1] if flags else None)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.json"]          # nothing else left
