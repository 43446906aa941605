"""``score --plant NAME|FILE``: a plant scored on its own suite. The reference plays itself (gap 0,
score 1), a matrix plant's FILE gives the old ``--suite FILE`` route's score file byte for byte,
``--plant cartpole`` is the cart-pole's score, a linear controller file of the plant's three
outputs plays there (the reference written as a file scores as the built-in), and the
combinations that make no sense are one line ``error: --plant: …``, exit 2, nothing written."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from pendulum_lqg.cli import main

ROOT = Path(__file__).resolve().parents[2]
TWO_MASS = ROOT / "experiments" / "lti" / "two_mass.toml"
TWO_MASS_SUITE = ROOT / "experiments" / "lti" / "two_mass_suite.toml"


def _score(capsys, *argv: str) -> dict:
    assert main(["score", *argv, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


@pytest.fixture(scope="module")
def double_lqg_file(tmp_path_factory):
    """The double cart-pole's own dlqr+kalman written as a state-space controller of
    z = [p, θ₁, θ₂, u_prev] (four inputs a period)."""
    from pendulum_lqg.model.catalog import load_named_plant
    from pendulum_lqg.policies.lti import design_lti_policy
    from pendulum_lqg.scoreboard.linear import controller_file, lqg_state_space, write_controller

    plant = load_named_plant("double-cartpole")
    info = design_lti_policy(plant, "dlqr+kalman").info
    doc = controller_file("state_space", lqg_state_space(info["Phi"], info["Gamma"], info["C"],
                                                         info["K"], info["L"]),
                          action_scale=1.0, env={"plant": "double-cartpole"},
                          method="lqg-as-file", seed=3)
    path = tmp_path_factory.mktemp("plant") / "double-lqg.json"
    write_controller(path, doc)
    return path


def test_the_double_cartpole_reference_plays_itself(capsys):
    """dlqr+kalman on the double cart-pole's suite is its reference: the same rows, so the gap is 0
    and the failure-aware score 1 exactly; every episode survives (docs/family.md: ≥ 99 %), and
    the full-state bound costs less."""
    doc = _score(capsys, "dlqr+kalman", "--plant", "double-cartpole", "--episodes", "20")
    assert list(doc["suites"]) == ["double-cartpole"]
    e = doc["suites"]["double-cartpole"]
    assert e["applicable"] and e["episodes"] == 20 and e["success_rate"] == 1.0
    assert e["optimality_gap"] == 0.0 and e["gap_ci"] == [0.0, 0.0] and e["score_mean"] == 1.0
    assert e["reference"] == {"policy": "dlqr+kalman", "success_rate": 1.0,
                              "cost_mean": e["cost_mean"]}
    assert e["full_state_bound"]["cost_mean"] < e["cost_mean"]
    assert e["lti_file"] == str(ROOT / "models" / "double_cartpole.toml")
    assert [r["episode"] for r in e["rows"]] == list(range(20))
    other = _score(capsys, "dlqr+luenberger", "--plant", "double-cartpole", "--episodes", "20")
    o = other["suites"]["double-cartpole"]
    assert o["fingerprint"] == e["fingerprint"] and o["cost_mean"] != e["cost_mean"]
    assert [r["seed"] for r in o["rows"]] == [r["seed"] for r in e["rows"]]


def test_a_matrix_plant_file_equals_the_suite_file_route_byte_for_byte(tmp_path, capsys):
    """two_mass_suite.toml writes exactly a plant's own suite: both routes give the same file."""
    by_plant, by_suite = tmp_path / "plant.json", tmp_path / "suite.json"
    assert main(["score", "dlqr+luenberger", "--plant", str(TWO_MASS), "--episodes", "10",
                 "--json", "--out", str(by_plant)]) == 0
    shown_plant = capsys.readouterr().out
    assert main(["score", "dlqr+luenberger", "--suite", str(TWO_MASS_SUITE), "--episodes", "10",
                 "--json", "--out", str(by_suite)]) == 0
    shown_suite = capsys.readouterr().out
    assert by_plant.read_bytes() == by_suite.read_bytes()
    assert shown_plant == shown_suite
    assert json.loads(shown_plant)["suites"]["two-mass"]["gap_episodes"] == 10


def test_plant_cartpole_is_the_cartpole_score(capsys):
    """--plant cartpole names the default plant: the shipped suites' score, byte for byte."""
    argv = ["dlqr+kalman", "--suite", "lecture", "--episodes", "3"]
    assert main(["score", *argv, "--json"]) == 0
    plain = capsys.readouterr().out
    assert main(["score", *argv, "--plant", "cartpole", "--json"]) == 0
    assert capsys.readouterr().out == plain


def test_the_reference_as_a_linear_file_scores_as_the_builtin(double_lqg_file, capsys):
    """A linear controller of three outputs on the double cart-pole: the reference's own LQG as a
    file plays the reference's episodes (the same successes, J to 1e-9, gap ≈ 0), and the file's
    run goes into the score file."""
    ref = _score(capsys, "dlqr+kalman", "--plant", "double-cartpole", "--episodes", "6")
    doc = _score(capsys, "--plant", "double-cartpole", "--agent", f"linear:{double_lqg_file}",
                 "--episodes", "6")
    a, b = doc["suites"]["double-cartpole"], ref["suites"]["double-cartpole"]
    assert a["applicable"] and doc["kind"] == "agent" and doc["method"] == "lqg-as-file"
    assert [r["success"] for r in a["rows"]] == [r["success"] for r in b["rows"]] == [True] * 6
    np.testing.assert_allclose([r["cost"] for r in a["rows"]], [r["cost"] for r in b["rows"]],
                               rtol=1e-9)
    assert abs(a["optimality_gap"]) < 1e-9


def test_a_controller_of_other_outputs_is_not_applicable(double_lqg_file, capsys):
    """The cart-pole's controller (y = [p, θ]) on the double cart-pole, and the double cart-pole's
    on the cart-pole's suite: not applicable, the reason naming the outputs."""
    cartpole_file = ROOT / "experiments" / "agents" / "models" / "ars-history-clone-seed0.json"
    doc = _score(capsys, "--plant", "double-cartpole", "--agent", f"linear:{cartpole_file}",
                 "--episodes", "2")
    e = doc["suites"]["double-cartpole"]
    assert e["applicable"] is False
    assert "takes 2 outputs" in e["reason"] and "this plant has 3" in e["reason"]
    doc = _score(capsys, "--suite", "lecture", "--agent", f"linear:{double_lqg_file}",
                 "--episodes", "2")
    e = doc["suites"]["lecture"]
    assert e["applicable"] is False and "takes 3 outputs" in e["reason"]


def test_a_plugin_is_not_applicable_on_a_plant_suite(capsys):
    doc = _score(capsys, "my_plugin.py:make", "--plant", "double-cartpole", "--episodes", "2")
    e = doc["suites"]["double-cartpole"]
    assert e["applicable"] is False and "plug-in" in e["reason"]


@pytest.mark.parametrize(("argv", "message"), [
    (["--plant", "double-cartpole", "--suite", "lecture"],
     "--plant: 'double-cartpole' is scored on its own suite; --suite lecture names another"),
    (["--plant", "cartpole", "--suite", str(TWO_MASS_SUITE)],
     "--plant: 'cartpole' plays the shipped cart-pole suites; --suite"),
    (["--plant", "mujoco"], "--plant: expected a plant name or a plant file, got the simulator"),
    (["--plant", "no-such-plant"], "--plant: expected a plant name (cartpole, double-cartpole"),
    (["--plant", ""], "--plant: expected a plant name"),
])
def test_refusals_are_one_line_exit_2_nothing_written(argv, message, tmp_path, capsys):
    out = tmp_path / "score.json"
    assert main(["score", "dlqr+kalman", *argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"error: {err[0].removeprefix('error: ')}"] and message in err[0]
    assert not out.exists()
