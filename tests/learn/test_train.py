"""``pendulum-lqg train``: the methods listed, every bad input one line and exit 2 before any
training, outputs never written over without --force (and a run without --out never touching the
committed models), Ctrl-C as exit 130 with whole files, the extra named where it is missing, and a
``linear:`` file written by ``train`` scoring exactly as the controller did in memory."""

from __future__ import annotations

import hashlib
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import interruptible_cli, run_cli

from pendulum_lqg.cli import main
from pendulum_lqg.learn.methods import METHODS

ROOT = Path(__file__).resolve().parents[2]
MODELS = ROOT / "experiments" / "agents" / "models"


def _one_line(status, err, needle):
    assert status == 2, err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    assert err.startswith("error: ") and needle in err, err


def test_train_list_names_every_method(capsys):
    assert main(["train", "--list"]) == 0
    *lines, plants = capsys.readouterr().out.splitlines()
    names = [line.split()[0] for line in lines]
    assert names == list(METHODS)
    # the last line: the methods train --plant takes (the ARS ones read the plant's sizes)
    assert plants == "--plant NAME|FILE (any plant of one input): ars-history, ars-history-clone"
    for name in ("ppo-history", "recurrentppo-actions", "sac-history", "ppo-kalman",
                 "ppo-full-state", "ars-history", "ars-history-clone", "ls-clone", "sysid-lqg",
                 "sysid-openloop"):
        assert name in names
    assert any(line.startswith("ppo-history ") and "1,000,000 steps" in line and "[rl]" in line
               for line in lines)


def test_the_sb3_methods_declare_designs_the_scorer_can_rebuild():
    from pendulum_lqg.boundary.schemas import ALGORITHMS
    from pendulum_lqg.learn.deep import METHODS as SB3
    from pendulum_lqg.learn.deep import method_name, training_suite
    from pendulum_lqg.learn.runs import EVAL_SEED, eval_suite, run_name
    from pendulum_lqg.scoreboard.obs_design import ObservationDesign
    from pendulum_lqg.scoreboard.suites import load_suite

    for m in SB3.values():
        assert m.algo in ALGORITHMS and load_suite(m.suite).name == m.suite
        assert m.design() == ObservationDesign(m.frame_stack, m.past_actions, m.estimator)
    suite = eval_suite(load_suite("lecture"))
    assert (suite.seed, suite.episodes) == (EVAL_SEED, 20)
    assert suite.seed != load_suite("lecture").seed                # never a suite's episodes
    assert run_name("sac-history", 4) == "sac-history-seed4"
    kalman, history = SB3["ppo-kalman"], SB3["ppo-history"]
    assert kalman.design().record() == {"frame_stack": 1, "past_actions": False,
                                        "estimator": "kalman"}
    assert (kalman.algo, kalman.suite, kalman.steps, kalman.envs, kalman.kwargs) == \
        (history.algo, history.suite, history.steps, history.envs, history.kwargs)
    assert method_name("ppo-history", 0.25) == "ppo-history-noise0.25"
    assert method_name("ppo-history", 1.0) == "ppo-history-noise1"
    assert training_suite(history, 0.5).env["noise_scale"] == 0.5
    assert "noise_scale" not in training_suite(history).env


@pytest.mark.parametrize(("args", "needle"), [
    (["ars-history", "--steps", "0"], "--steps: expected an integer from 1 to"),
    (["ars-history", "--seed", "-1"], "--seed: expected an integer from 0 to"),
    (["ars-history", "--frames", "1e12"], "--frames: expected an integer from 1 to 1,024"),
    (["ars-history", "--frames", "1000000000000"], "--frames: expected an integer from 1 to"),
    (["ars-history", "--alpha", "nan"], "--alpha: expected a finite number > 0"),
    (["ars-history", "--eval-every", "0"], "--eval-every: expected an integer from 1 to"),
    (["ppo-history", "--noise-scale", "-0.5"], "--noise-scale: expected a finite number ≥ 0"),
    (["ppo-history", "--frames", "8"], "--frames: does not apply to ppo-history"),
    (["sysid-lqg", "--alpha", "0.1"], "--alpha: does not apply to sysid-lqg"),
    (["no-such-method"], "method: expected one of ppo-history"),
    (["ars-history", "--suite", "no-such-suite"], "no-such-suite"),
    (["ars-history", "--resume"], "--resume: needs the --out DIR"),
])
def test_bad_input_is_one_line_and_exit_2_before_any_training(capsys, tmp_path, args, needle):
    status, err = run_cli(capsys, ["train", *args, "--out", str(tmp_path / "o")]
                          if "--resume" not in args else ["train", *args])
    _one_line(status, err, needle)
    assert not (tmp_path / "o").exists()                      # nothing trained, nothing written


@pytest.mark.parametrize("kind", ["file", "fifo", "device"])
def test_an_out_that_is_not_a_folder_is_refused_before_training(capsys, tmp_path, kind):
    """The old ARS script trained for its whole budget, then failed to write."""
    out = {"file": tmp_path / "f", "fifo": tmp_path / "p", "device": Path("/dev/null")}[kind]
    if kind == "file":
        out.write_text("mine")
    elif kind == "fifo":
        os.mkfifo(out)
    status, err = run_cli(capsys, ["train", "ars-history", "--out", str(out)])
    _one_line(status, err, f"--out: {out} is ")
    assert "progress" not in err and "steps" not in err
    if kind == "file":
        assert out.read_text() == "mine"


def test_run_files_that_are_fifos_are_refused(capsys, tmp_path):
    os.mkfifo(tmp_path / "ars-history-seed0-curve.csv")
    status, err = run_cli(capsys, ["train", "ars-history", "--out", str(tmp_path), "--force"])
    _one_line(status, err, "is a FIFO")


def test_an_existing_run_is_refused_without_force(capsys, tmp_path):
    (tmp_path / "ars-history-seed0.json").write_text("mine")
    status, err = run_cli(capsys, ["train", "ars-history", "--out", str(tmp_path)])
    _one_line(status, err, "already holds ars-history-seed0.json; give --force")
    assert (tmp_path / "ars-history-seed0.json").read_text() == "mine"
    status, err = run_cli(capsys, ["train", "ars-history", "--out", str(tmp_path), "--resume"])
    _one_line(status, err, "--resume: ")                              # no checkpoint to continue


def _tree_digest(folder):
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.iterdir())
            if p.is_file()}


def test_smoke_run_without_out_leaves_committed_models_untouched(tmp_path, monkeypatch, capsys,
                                                                 few_curve_episodes):
    """The documented smoke run used to write into experiments/agents/models (seed 3's committed
    files replaced); without --out a run goes to a new folder under runs/."""
    before = _tree_digest(MODELS)
    monkeypatch.chdir(ROOT)
    made = []
    monkeypatch.setattr("pendulum_lqg.learn.runs.RUNS_FOLDER", tmp_path / "runs")
    assert main(["train", "ars-history", "--seed", "3", "--steps", "500"]) == 0
    made = list((tmp_path / "runs").iterdir())
    assert len(made) == 1 and made[0].name.startswith("ars-history-seed3-")
    assert sorted(p.name for p in made[0].iterdir()) == ["ars-history-seed3-curve.csv",
                                                         "ars-history-seed3.json"]
    assert _tree_digest(MODELS) == before
    assert str(made[0]) in capsys.readouterr().err


def test_default_run_folder_is_under_runs_and_ignored_by_git():
    from pendulum_lqg.learn.runs import default_out

    out = default_out("ppo-history", 3)
    assert out.parts[0] == "runs" and out.name.startswith("ppo-history-seed3-")
    assert "/runs/" in (ROOT / ".gitignore").read_text().splitlines()


def test_train_without_torch_names_the_extra(capsys, monkeypatch, tmp_path):
    import importlib.util

    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name in ("torch", "stable_baselines3")
                        else real(name, *a))
    status, err = run_cli(capsys, ["train", "ppo-history", "--out", str(tmp_path / "o")])
    _one_line(status, err, "ppo-history: needs the rl extra (torch, stable_baselines3 not "
                           "installed): uv sync --extra rl, or pip install 'pendulum-lqg[rl]'")


def test_progress_is_rounded():
    from pendulum_lqg.learn.runs import progress_line

    line = progress_line("ppo-history-seed3", {"env_steps": 100000, "success_rate": 0.85,
                                               "score_mean": 0.10815189878983791})
    assert line == "ppo-history-seed3: 100,000 steps, success 0.85, score 0.108"
    assert progress_line("x", {"env_steps": 1, "success_rate": 0.0,
                               "score_mean": None}).endswith("score –")


def test_train_sigint_exits_130_with_whole_curve(tmp_path):
    """A real Ctrl-C (SIGINT) once the first curve point is out: exit 130, one line naming the
    files and the command that continues, a curve CSV of whole rows, a checkpoint."""
    import signal

    cmd = interruptible_cli("train", "ars-history", "--seed", "101", "--steps", "10000000",
                            "--eval-every", "1000", "--out", tmp_path)
    proc = subprocess.Popen(cmd, stderr=subprocess.PIPE, text=True, cwd=tmp_path)
    lines = []
    for line in proc.stderr:                      # wait for a curve point, then Ctrl-C
        lines.append(line)
        if ", success " in line and not line.startswith("ars-history-seed101: 0 steps"):
            proc.send_signal(signal.SIGINT)
            break
    rest = proc.stderr.read()
    assert proc.wait() == 130, rest
    tail = [x for x in rest.splitlines() if not x.startswith("ars-history-seed101: ")]
    assert len(tail) == 1 and tail[0].startswith("stopped at ") and "Traceback" not in rest
    assert tail[0].endswith("--resume") and "ars-history-seed101-checkpoint.json" in tail[0]
    rows = (tmp_path / "ars-history-seed101-curve.csv").read_text().splitlines()
    assert len(rows) >= 3 and all(len(r.split(",")) == 8 for r in rows)
    saved = json.loads((tmp_path / "ars-history-seed101-checkpoint.json").read_text())
    assert saved["points"] == len(rows) - 1 and saved["state"]["steps"] >= 1000
    assert f"stopped at {saved['state']['steps']} steps" in tail[0]


# ---- sysid-lqg and ls-clone over the closed-loop identification (a stand-in of its API) --------
@pytest.fixture
def identification(monkeypatch):
    from stand_ins import closed_loop_module

    calls: list[dict] = []
    monkeypatch.setitem(sys.modules, "pendulum_lqg.learn.closed_loop", closed_loop_module(calls))
    return calls


def test_linear_file_written_by_train_scores_exactly_as_the_in_memory_controller(
        tmp_path, capsys, identification, few_curve_episodes):
    """sysid-lqg's curve point is the controller in memory through the scorer's batch; the file
    it writes, scored by ``score --agent linear:FILE`` on the same episodes, gives the same rows —
    and, the stand-in's rounds being the true-model LQG, the reference's own score."""
    import numpy as np

    from pendulum_lqg.learn.runs import eval_suite, run_root
    from pendulum_lqg.scoreboard.score import score_entry
    from pendulum_lqg.scoreboard.suites import load_suite

    assert main(["train", "sysid-lqg", "--seed", "4", "--steps", "50000", "--out",
                 str(tmp_path)]) == 0
    assert identification == [{"suite": "lecture", "root": run_root(4), "steps": 50000}]
    path = tmp_path / "sysid-lqg-seed4.json"
    doc = json.loads(path.read_text())
    t = doc["training"]
    assert (doc["method"], doc["seed"], doc["form"], doc["action_scale"]) == \
        ("sysid-lqg", 4, "state_space", 1.0)
    assert t["budget"]["logged_steps"] == 40_000 and t["budget"]["stepped_steps"] == 41_000
    assert t["model"] == {"round": 2} and t["rounds"] == 2 and "versions" in t
    curve = (tmp_path / "sysid-lqg-seed4-curve.csv").read_text().splitlines()
    assert [int(r.split(",")[0]) for r in curve[1:]] == [10_000, 40_000]
    last = dict(zip(curve[0].split(","), curve[-1].split(","), strict=True))
    scored = score_entry([eval_suite(load_suite("lecture"))], agent=f"linear:{path}")
    e = next(iter(scored["suites"].values()))
    assert e["success_rate"] == float(last["success_rate"]) == 1.0
    assert e["score_mean"] == float(last["score_mean"])
    np.testing.assert_allclose(e["score_mean"], 1.0, rtol=1e-9)    # the reference itself
    assert scored["method"] == "sysid-lqg" and scored["seed"] == 4


def test_ls_clone_is_not_resumed(tmp_path, capsys, identification):
    """ls-clone keeps no checkpoint (sysid-lqg does: test_train_reliability.py, item 12)."""
    (tmp_path / "ls-clone-seed0-checkpoint.json").write_text("{}")
    status, err = run_cli(capsys, ["train", "ls-clone", "--out", str(tmp_path), "--resume"])
    _one_line(status, err, "--resume: ls-clone is not resumed")
