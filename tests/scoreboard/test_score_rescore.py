"""``score --agent sb3:MODEL.zip`` is reproducible and batched: the same command writes the same
score file byte for byte (the file holds no time or host), and a recurrent model is asked once per
control period for all episodes of a suite, its state kept per row.

Without torch a stand-in model is loaded in place of stable-baselines3's ``load``; where the rl
extra is installed, tiny untrained PPO and RecurrentPPO models are saved and scored for real."""

from __future__ import annotations

import importlib.util
import json

import numpy as np
import pytest

from pendulum_lqg.cli import main
from pendulum_lqg.scoreboard import sb3
from pendulum_lqg.scoreboard.obs_design import ObservationDesign

DESIGN = ObservationDesign(4, past_actions=True)


class _RecurrentStandIn:
    """A recurrent policy: per row an LSTM-like state (a running mean of what it saw), reset at
    each row's episode start; records the rows of each call."""

    def __init__(self, size):
        self.gain = np.linspace(-0.4, 0.4, size)
        self.calls = []

    def predict(self, observation, state=None, episode_start=None, deterministic=False):
        n = observation.shape[0]
        self.calls.append((n, np.array(episode_start, dtype=bool)))
        h = np.zeros(n) if state is None else np.where(episode_start, 0.0, state[0])
        h = 0.9 * h + 0.1 * (observation @ self.gain)
        return np.tanh(h + observation @ self.gain)[:, None], (h,)


def _record(tmp_path, name="m", **extra):
    meta = {"algo": "RecurrentPPO", "method": "stand-in", "seed": 4, "normalize_action": True,
            "env": {}, "obs_norm": None, **DESIGN.record(), **extra}
    (tmp_path / f"{name}.zip").write_bytes(b"stand-in weights")
    (tmp_path / f"{name}.json").write_text(json.dumps(meta), encoding="utf-8")
    return tmp_path / f"{name}.zip"


def test_rescoring_a_model_writes_the_same_score_file_byte_for_byte(tmp_path, monkeypatch):
    model = _RecurrentStandIn(4 * 3)
    monkeypatch.setattr(sb3, "load_model", lambda path, algo: model)
    path = _record(tmp_path)
    outs = [tmp_path / "a.json", tmp_path / "b.json"]
    for out in outs:
        assert main(["score", "--agent", f"sb3:{path}", "--suite", "lecture", "--suite", "lossy",
                     "--episodes", "6", "--out", str(out), "--json"]) == 0
    first = outs[0].read_bytes()
    assert first == outs[1].read_bytes()
    doc = json.loads(first)
    assert (doc["method"], doc["seed"]) == ("stand-in", 4)
    assert doc["model_sha256"] == sb3.file_sha256(path)
    assert [e["episodes"] for e in doc["suites"].values()] == [6, 6]


def test_a_recurrent_model_is_asked_once_per_period_for_all_rows_with_their_states(
        tmp_path, monkeypatch):
    from pendulum_lqg.scoreboard import episodes as ep
    from pendulum_lqg.scoreboard.sb3_batch import batched_rows
    from pendulum_lqg.scoreboard.suites import load_suite

    model = _RecurrentStandIn(4 * 3)
    monkeypatch.setattr(sb3, "load_model", lambda path, algo: model)
    factory = ep.load_agent(f"sb3:{_record(tmp_path)}")
    suite = load_suite("lecture").with_episodes(7)
    rows = batched_rows(suite, factory)
    batched, model.calls = model.calls, []
    one = ep.agent_rows(suite, factory, normalize_action=True)   # one episode at a time
    assert {n for n, _ in model.calls} == {1}
    lengths = np.diff(np.flatnonzero([s[0] for _, s in model.calls] + [True]))
    assert len(lengths) == 7 and len(set(lengths)) > 1           # episodes of several lengths
    assert {n for n, _ in batched} == {7}            # every call: all 7 episodes' rows …
    assert len(batched) == lengths.max()             # … once per period of the longest
    assert batched[0][1].all() and not any(s.any() for _, s in batched[1:])
    assert [(r["success"], r["failure_reason"]) for r in rows] == \
        [(r["success"], r["failure_reason"]) for r in one]
    np.testing.assert_allclose([r["cost"] for r in rows], [r["cost"] for r in one], rtol=1e-9)


@pytest.mark.skipif(importlib.util.find_spec("sb3_contrib") is None,
                    reason="the rl extra (sb3-contrib, torch) is absent")
@pytest.mark.parametrize("algo", ["PPO", "RecurrentPPO"])
def test_real_models_rescore_byte_for_byte_and_batch_as_one_episode_at_a_time(tmp_path, algo):
    import torch

    from pendulum_lqg.scoreboard import episodes as ep
    from pendulum_lqg.scoreboard.obs_design import history_vec_env
    from pendulum_lqg.scoreboard.sb3_batch import batched_rows
    from pendulum_lqg.scoreboard.sb3_vec import native_vec_env
    from pendulum_lqg.scoreboard.suites import load_suite

    torch.set_num_threads(1)
    module = importlib.import_module("sb3_contrib" if algo == "RecurrentPPO" else
                                     "stable_baselines3")
    venv = history_vec_env(native_vec_env(2, normalize_action=True), DESIGN,
                           normalize_action=True)
    policy = "MlpLstmPolicy" if algo == "RecurrentPPO" else "MlpPolicy"
    model = getattr(module, algo)(policy, venv, seed=0, device="cpu", n_steps=16, batch_size=32,
                                  policy_kwargs={"log_std_init": -1.0})
    path = _record(tmp_path, algo, algo=algo)
    model.save(str(path))                       # untrained weights: a deterministic policy
    outs = [tmp_path / "a.json", tmp_path / "b.json"]
    for out in outs:
        assert main(["score", "--agent", f"sb3:{path}", "--suite", "lecture", "--episodes", "3",
                     "--out", str(out), "--json"]) == 0
    assert outs[0].read_bytes() == outs[1].read_bytes()
    factory = ep.load_agent(f"sb3:{path}")
    suite = load_suite("lecture").with_episodes(3)
    rows, one = batched_rows(suite, factory), ep.agent_rows(suite, factory,
                                                            normalize_action=True)
    assert [r["success"] for r in rows] == [r["success"] for r in one]
    np.testing.assert_allclose([r["cost"] for r in rows], [r["cost"] for r in one], rtol=1e-6)


def test_the_noise_ladder_plays_the_suites_at_the_scale_it_names(tmp_path, capsys):
    from pendulum_lqg.scoreboard.suites import load_suite

    out = tmp_path / "quiet.json"
    assert main(["score", "dlqr+kalman", "--suite", "lecture", "--episodes", "4",
                 "--noise-scale", "0", "--out", str(out)]) == 0
    doc = json.loads(out.read_text())
    lecture = load_suite("lecture").with_episodes(4)
    assert doc["noise_scale"] == 0.0
    assert doc["suites"]["lecture"]["fingerprint"] == lecture.with_noise_scale(0.0).fingerprint()
    assert doc["suites"]["lecture"]["fingerprint"] != lecture.fingerprint()
    assert lecture.with_noise_scale(1.0).fingerprint() == lecture.fingerprint()
    # without noise the LQG loop's cost is the deterministic transient from θ₀ = 0.1 rad alone:
    # every episode the same J, below every episode's J at the lecture's noise
    from pendulum_lqg.scoreboard.episodes import policy_rows

    rows = doc["suites"]["lecture"]["rows"]
    assert len({round(r["cost"], 9) for r in rows}) == 1
    assert rows[0]["cost"] < min(r["cost"] for r in policy_rows(lecture, "dlqr+kalman"))
    capsys.readouterr()
    with pytest.raises(SystemExit) as exc:          # argparse refuses it: usage, one line, 2
        main(["score", "dlqr+kalman", "--suite", "lecture", "--noise-scale", "-1"])
    assert exc.value.code == 2
    assert "--noise-scale: expected a finite number ≥ 0, got '-1'" in capsys.readouterr().err
