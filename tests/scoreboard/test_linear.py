"""Linear controllers as files (``score --agent linear:FILE.json``): the file round-trips,
dlqr+kalman written as a state-space controller scores as the built-in, the two forms agree, the
batch and the Gymnasium path agree, bad files are one line (ARS: tests/learn/test_ars.py)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from pendulum_lqg.boundary.schemas import linear_controller
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.scoreboard.linear import (
    controller_file,
    linear_agent,
    linear_rows,
    lqg_state_space,
    write_controller,
)
from pendulum_lqg.scoreboard.suites import load_suite

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def suite():
    return load_suite("lecture").with_episodes(2)


@pytest.fixture(scope="module")
def lqg_file(suite, tmp_path_factory):
    from pendulum_lqg.policies.loading import build_policy

    info = build_policy("dlqr+kalman", plant=suite.plants()[1],
                        scenario=suite.config.scenario).info
    doc = controller_file("state_space", lqg_state_space(info["Phi"], info["Gamma"], info["C"],
                                                         info["K"], info["L"]),
                          action_scale=1.0, env=suite.env, method="lqg-as-file", seed=7)
    path = tmp_path_factory.mktemp("linear") / "lqg.json"
    write_controller(path, doc)
    return path


def test_the_file_round_trips(lqg_file):
    doc = linear_controller(lqg_file, where_text="t")
    raw = json.loads(lqg_file.read_text())
    assert doc["state_space"] == raw["state_space"] and doc["method"] == "lqg-as-file"
    assert doc["seed"] == 7 and doc["action_scale"] == 1.0


def test_dlqr_kalman_as_a_file_scores_as_the_builtin(suite, lqg_file):
    from pendulum_lqg.scoreboard.score import score_entry

    as_file = score_entry([suite], agent=f"linear:{lqg_file}")
    builtin = score_entry([suite], policy="dlqr+kalman")
    a, b = as_file["suites"]["lecture"], builtin["suites"]["lecture"]
    assert [r["success"] for r in a["rows"]] == [r["success"] for r in b["rows"]] == [True, True]
    np.testing.assert_allclose([r["cost"] for r in a["rows"]], [r["cost"] for r in b["rows"]],
                               rtol=1e-9)
    assert (as_file["method"], as_file["seed"]) == ("lqg-as-file", 7)
    assert len(as_file["model_sha256"]) == 64


def test_the_history_form_equals_the_state_space_form_and_the_gym_path(suite, tmp_path):
    """u = w·z_k + w'·z_{k−1} as a 2-frame history and as a state-space controller (ξ = z_{k−1})."""
    from pendulum_lqg.scoreboard import episodes as ep

    w_old, w_new = np.array([-3.0, 40.0, 0.2]), np.array([5.0, 60.0, 0.1])
    history = {"frames": 2, "weights": [*w_old, *w_new], "bias": 0.0, "mean": [0.0] * 6,
               "std": [1.0] * 6}
    ss = {"A": np.zeros((3, 3)).tolist(), "B": np.eye(3).tolist(), "C": [w_old.tolist()],
          "D": [w_new.tolist()]}
    rows = {}
    for form, params in (("history", history), ("state_space", ss)):
        path = tmp_path / f"{form}.json"
        write_controller(path, controller_file(form, params, action_scale=10.0, env=suite.env))
        factory = linear_agent(str(path))
        rows[form] = linear_rows(suite, factory.doc, name=form, nthread=1)
        rows[form + "-gym"] = ep.agent_rows(suite, factory, name=form)
    costs = {k: [r["cost"] for r in v] for k, v in rows.items()}
    for key in ("state_space", "history-gym", "state_space-gym"):
        assert [r["failure_reason"] for r in rows[key]] == \
            [r["failure_reason"] for r in rows["history"]]
        np.testing.assert_allclose(costs[key], costs["history"], rtol=1e-9)


@pytest.mark.parametrize(("edit", "message"), [
    (lambda d: d.pop("form"), "t.json: form: missing"),
    (lambda d: d.update(form="fir"), "t.json: form: expected one of history, state_space"),
    (lambda d: d["state_space"].update(B=[[0.0]]), "t.json: state_space.B: expected a list of"),
    (lambda d: d.update(action_scale=0), "t.json: action_scale: expected a finite number in"),
    (lambda d: d.update(version=2), "t.json: version: expected 1"),
])
def test_bad_files_are_one_line_naming_file_and_key(lqg_file, tmp_path, edit, message):
    doc = json.loads(lqg_file.read_text())
    edit(doc)
    path = tmp_path / "t.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(ConfigError) as err:
        linear_agent(str(path))
    assert message in str(err.value) and "\n" not in str(err.value)


def test_the_cli_exits_2_with_one_line(tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "pendulum-lqg linear controller", "version": 1, "form": "history"}')
    res = subprocess.run([sys.executable, "-m", "pendulum_lqg.cli", "score", "--agent",
                          f"linear:{bad}", "--suite", "lecture", "--episodes", "1"],
                         capture_output=True, text=True, check=False)
    assert res.returncode == 2
    assert res.stderr.strip().count("\n") == 0 and "history: missing" in res.stderr
