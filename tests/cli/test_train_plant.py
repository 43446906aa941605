"""``train --plant NAME|FILE METHOD``: ARS trains on the double cart-pole's env (its history
sized from the plant's three outputs) and writes a controller ``score --plant`` accepts; the
methods tied to the cart-pole and the plants the env cannot take are one line ``error:
--plant: …``, exit 2, with nothing written."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from pendulum_lqg.cli import main
from pendulum_lqg.learn.methods import METHODS

ROOT = Path(__file__).resolve().parents[2]
TWO_MASS = ROOT / "experiments" / "lti" / "two_mass.toml"


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    """A short ars-history run on the double cart-pole (two curve points after the start)."""
    out = tmp_path_factory.mktemp("train") / "run"
    assert main(["train", "ars-history", "--plant", "double-cartpole", "--steps", "4000",
                 "--eval-every", "1000", "--frames", "4", "--out", str(out)]) == 0
    return out


def test_ars_on_the_double_cartpole_writes_a_controller_of_its_outputs(trained):
    doc = json.loads((trained / "ars-history-seed0.json").read_text())
    assert doc["form"] == "history" and doc["history"]["frames"] == 4
    assert len(doc["history"]["weights"]) == 4 * 4        # z = [p, θ₁, θ₂, u/s] per frame
    assert doc["env"] == {"plant": "double-cartpole", "duration": 10.0, "noise_scale": 1.0}
    assert doc["training"]["suite"] == "double-cartpole" and doc["action_scale"] == 10.0
    with (trained / "ars-history-seed0-curve.csv").open() as f:
        points = list(csv.DictReader(f))
    assert int(points[0]["env_steps"]) == 0 and len(points) >= 2
    assert not (trained / "ars-history-seed0-checkpoint.json").exists()


def test_score_plant_accepts_the_trained_controller(trained, capsys):
    path = trained / "ars-history-seed0.json"
    assert main(["score", "--plant", "double-cartpole", "--agent", f"linear:{path}",
                 "--episodes", "4", "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    e = doc["suites"]["double-cartpole"]
    assert e["applicable"] and [r["episode"] for r in e["rows"]] == [0, 1, 2, 3]
    assert (doc["method"], doc["seed"]) == ("ars-history", 0)
    assert e["reference"]["policy"] == "dlqr+kalman" and e["reference"]["success_rate"] == 1.0


def test_the_resume_command_names_the_plant():
    import argparse

    from pendulum_lqg.cli.train import _resume_command

    args = argparse.Namespace(method="ars-history", seed=0, plant_ref="double-cartpole",
                              suite=None, steps="2000", eval_every=None, noise_scale=None,
                              frames=None, alpha=None, nu=None, init=None)
    assert _resume_command(args, "run") == ("pendulum-lqg train ars-history --seed 0 --plant "
                                            "double-cartpole --steps 2000 --out run --resume")


def test_which_methods_take_a_plant():
    """The ARS methods read the plant's sizes from its env; the others name why not."""
    takes = [name for name, m in METHODS.items() if m.plant_refusal is None]
    assert takes == ["ars-history", "ars-history-clone"]


def _cartpole_clone(tmp_path: Path) -> Path:
    from pendulum_lqg.scoreboard.linear import controller_file, write_controller

    doc = controller_file("history", {"frames": 64, "weights": [0.0] * 192, "bias": 0.0,
                                      "mean": [0.0] * 192, "std": [1.0] * 192},
                          action_scale=10.0, env={})
    path = tmp_path / "clone.json"
    write_controller(path, doc)
    return path


@pytest.mark.parametrize(("argv", "message"), [
    (["sysid-lqg", "--plant", "double-cartpole"],
     "--plant: sysid-lqg trains on the cart-pole only: it identifies the cart-pole's structured"),
    (["sysid-openloop", "--plant", "double-cartpole"],
     "--plant: sysid-openloop trains on the cart-pole only"),
    (["ls-clone", "--plant", "double-cartpole"],
     "--plant: ls-clone trains on the cart-pole only: its teacher is sysid-lqg's model"),
    (["ppo-history", "--plant", "double-cartpole"],
     "--plant: ppo-history trains on the cart-pole only: its model is scored on the cart-pole's"),
    (["sac-history", "--plant", "double-cartpole"],
     "--plant: sac-history trains on the cart-pole only"),
    (["ars-history", "--plant", str(TWO_MASS)],
     "--plant: ars-history trains on the env: the environments take one input"),
    (["ars-history", "--plant", "double-cartpole", "--suite", "lecture"],
     "--plant: 'double-cartpole' trains on its own suite; --suite lecture names another"),
    (["ars-history", "--plant", "linear-zoh"],
     "--plant: expected a plant name or a plant file, got the simulator word 'linear-zoh'"),
    (["ars-history", "--plant", "no-such-plant"], "--plant: expected a plant name"),
    (["ars-history-clone", "--plant", "double-cartpole", "--init", "CLONE"],
     "expected 4 inputs per frame (the plant's 3 outputs and u), got 3"),
])
def test_refusals_are_one_line_exit_2_nothing_written(argv, message, tmp_path, capsys):
    argv = [str(_cartpole_clone(tmp_path)) if a == "CLONE" else a for a in argv]
    out = tmp_path / "run"
    assert main(["train", *argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error: ") and message in err[0], err
    assert not out.exists()


def test_a_stopped_plant_run_resumes_to_the_same_controller(trained, tmp_path, monkeypatch,
                                                            capsys):
    """Ctrl-C after the first curve point, then --resume (the checkpoint's arrays are sized by the
    plant's outputs, 4 × 4): the controller of the uninterrupted run, bit for bit; the resume
    command names --plant."""
    import os
    import signal

    from pendulum_lqg.learn.curve import Curve

    add = Curve.add

    def add_then_stop(self, env_steps, rows, **kw):
        point = add(self, env_steps, rows, **kw)
        if env_steps > 0:
            os.kill(os.getpid(), signal.SIGINT)
        return point

    argv = ["train", "ars-history", "--plant", "double-cartpole", "--steps", "4000",
            "--eval-every", "1000", "--frames", "4", "--out", str(tmp_path / "cut")]
    monkeypatch.setattr(Curve, "add", add_then_stop)
    assert main(argv) == 130
    said = capsys.readouterr().err.strip().splitlines()[-1]
    assert "--plant double-cartpole" in said and said.endswith("--resume")
    monkeypatch.setattr(Curve, "add", add)
    assert main([*argv, "--resume"]) == 0
    whole = json.loads((trained / "ars-history-seed0.json").read_text())
    cut = json.loads((tmp_path / "cut" / "ars-history-seed0.json").read_text())
    assert json.dumps(cut["history"]) == json.dumps(whole["history"])
