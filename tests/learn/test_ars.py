"""ARS (pendulum_lqg.learn.ars): its step on a quadratic is the closed form, the policy does not
move when the statistics do, a run of two iterations writes its controller and record, a run
stopped at a checkpoint and resumed ends at the same controller bit for bit, and a run started
from a clone starts at the clone's score."""

from __future__ import annotations

import json

import numpy as np
import pytest

from pendulum_lqg.cli import main
from pendulum_lqg.learn import ars


def test_ars_step_on_a_quadratic_is_the_closed_form():
    """r(M) = −|M − M*|²: r(M + νδ) − r(M − νδ) = −4ν δ·(M − M*) exactly, so with every direction
    kept the step is α/(N σ_R) Σ −4ν (δ·(M − M*)) δ, which for N ≫ d points along M* − M."""
    rng = np.random.default_rng(0)
    d, n, nu, alpha = 6, 4000, 0.1, 0.5
    M, target = np.zeros(d), rng.standard_normal(d)
    deltas = rng.standard_normal((n, d))
    r_plus = -(((M + nu * deltas) - target) ** 2).sum(axis=1)
    r_minus = -(((M - nu * deltas) - target) ** 2).sum(axis=1)
    step = ars.ars_update(M, deltas, r_plus, r_minus, alpha=alpha, top=n) - M
    sigma = np.std(np.concatenate([r_plus, r_minus]))
    expected = alpha / (n * sigma) * ((-4 * nu * deltas @ (M - target)) @ deltas)
    np.testing.assert_allclose(step, expected, rtol=1e-10)
    cosine = step @ (target - M) / np.linalg.norm(step) / np.linalg.norm(target - M)
    assert cosine > 0.99


def test_ars_keeps_the_best_directions():
    deltas = np.eye(3)
    r_plus, r_minus = np.array([1.0, 5.0, 2.0]), np.array([0.0, 1.0, 3.0])
    step = ars.ars_update(np.zeros(3), deltas, r_plus, r_minus, alpha=1.0, top=1)
    # direction 1 (max 5) alone: (5 − 1)/σ_R with σ_R = std([5, 1]) = 2
    np.testing.assert_allclose(step, [0.0, 2.0, 0.0])


def test_new_statistics_leave_the_policy_unchanged():
    rng = np.random.default_rng(1)
    stats = ars.RunningStats(4)
    stats.add(rng.normal(2.0, 3.0, (50, 4)))
    mean0, std0 = stats.mean.copy(), stats.std()
    M, bias = rng.standard_normal(4), 0.3
    stats.add(rng.normal(-1.0, 0.5, (80, 4)))
    M1, bias1 = ars.renormalized(M, bias, mean0, std0, stats)
    h = rng.standard_normal((7, 4))
    np.testing.assert_allclose((h - stats.mean) / stats.std() @ M1 + bias1,
                               (h - mean0) / std0 @ M + bias, rtol=1e-12)


def _train(out, *extra):
    return main(["train", "ars-history", "--seed", "100", "--steps", "4000", "--eval-every",
                 "1500", "--out", str(out), *extra])


def test_a_two_iteration_run_writes_its_controller_and_record(tmp_path, capsys,
                                                             few_curve_episodes):
    assert main(["train", "ars-history", "--seed", "100", "--steps", "2000", "--frames", "64",
                 "--out", str(tmp_path)]) == 0
    doc = json.loads((tmp_path / "ars-history-seed100.json").read_text())
    t = doc["training"]
    assert doc["form"] == "history" and doc["history"]["frames"] == 64
    assert len(doc["history"]["weights"]) == 3 * 64 and t["iterations"] == 2
    assert t["directions_per_iteration"] == 16 and t["start"] == "zero"
    assert t["settings"] == {"alpha": 0.02, "nu": 0.03, "frames": 64, "directions": 16,
                             "top": 8, "steps": 2000}
    assert t["budget"]["episodes"] == 32 and t["budget"]["steps"] >= 2000
    lines = (tmp_path / "ars-history-seed100-curve.csv").read_text().splitlines()
    assert lines[0].startswith("env_steps,wall_seconds,success_rate,score_mean")
    assert [int(line.split(",")[0]) for line in lines[1:]] == [0, t["budget"]["steps"]]
    assert "score 0.000" in capsys.readouterr().err          # rounded progress


def test_train_resume_after_a_stop_ends_at_the_same_controller_bit_for_bit(tmp_path, monkeypatch,
                                                                         capsys,
                                                                         few_curve_episodes):
    """A run stopped at its first checkpoint and resumed writes the controller an uninterrupted
    run of the same seed writes (the record differs only in its wall time)."""
    assert _train(tmp_path / "whole") == 0
    from pendulum_lqg.learn.curve import Curve

    add = Curve.add

    def add_then_stop(self, env_steps, rows, **kw):           # Ctrl-C after the first point
        point = add(self, env_steps, rows, **kw)
        if env_steps > 0:
            import os
            import signal
            os.kill(os.getpid(), signal.SIGINT)
        return point

    monkeypatch.setattr(Curve, "add", add_then_stop)
    assert _train(tmp_path / "cut") == 130
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err.startswith("stopped at ") and err.endswith(
        f"--out {tmp_path / 'cut'} --resume")
    assert (tmp_path / "cut" / "ars-history-seed100-checkpoint.json").is_file()
    assert not (tmp_path / "cut" / "ars-history-seed100.json").exists()
    monkeypatch.setattr(Curve, "add", add)
    assert _train(tmp_path / "cut", "--resume") == 0
    whole = json.loads((tmp_path / "whole" / "ars-history-seed100.json").read_text())
    cut = json.loads((tmp_path / "cut" / "ars-history-seed100.json").read_text())
    assert json.dumps(cut["history"]) == json.dumps(whole["history"])       # bit for bit
    for doc in (whole, cut):
        doc["training"].pop("wall_seconds")
    assert cut == whole
    strip = [lambda p: [line.split(",")[:1] + line.split(",")[2:]
                        for line in p.read_text().splitlines()]]
    assert strip[0](tmp_path / "cut" / "ars-history-seed100-curve.csv") == \
        strip[0](tmp_path / "whole" / "ars-history-seed100-curve.csv")
    assert not (tmp_path / "cut" / "ars-history-seed100-checkpoint.json").exists()


def test_a_run_from_the_clone_starts_at_the_clone(tmp_path, monkeypatch, capsys,
                                                 few_curve_episodes):
    """ars-history-clone's first curve point is its start, the clone's own figures; the record
    names the start and counts its data apart."""
    import sys

    from stand_ins import closed_loop_module

    monkeypatch.setitem(sys.modules, "pendulum_lqg.learn.closed_loop", closed_loop_module([]))
    assert main(["train", "ls-clone", "--seed", "100", "--steps", "3000", "--out",
                 str(tmp_path)]) == 0
    clone = tmp_path / "ls-clone-seed100.json"
    assert main(["train", "ars-history-clone", "--seed", "100", "--steps", "1", "--init",
                 str(clone), "--out", str(tmp_path)]) == 0
    start = (tmp_path / "ls-clone-seed100-curve.csv").read_text().splitlines()[1].split(",")
    curve = (tmp_path / "ars-history-clone-seed100-curve.csv").read_text().splitlines()
    first = curve[1].split(",")
    # the start's std comes back from its variance: equal to the clone's to rounding
    assert first[0] == "0" and first[2] == start[2] == "1.0"
    np.testing.assert_allclose([float(v) for v in first[3:6]], [float(v) for v in start[3:6]],
                               rtol=1e-12)
    t = json.loads((tmp_path / "ars-history-clone-seed100.json").read_text())["training"]
    assert t["start"] == str(clone) and t["iterations"] == 1
    assert t["budget"]["start_steps"] == 43_000 and (t["settings"]["alpha"], t["settings"]["nu"]) \
        == (2e-4, 5e-4)


@pytest.mark.parametrize(("args", "message"), [
    (["--frames", "16"], "--init: "),
    ([], "--init: ars-history-clone starts from a clone"),
])
def test_ars_from_a_clone_needs_a_matching_clone(tmp_path, capsys, args, message):
    from pendulum_lqg.scoreboard.linear import controller_file

    path = tmp_path / "c.json"
    path.write_text(json.dumps(controller_file(
        "history", {"frames": 64, "weights": [0.0] * 192, "bias": 0.0, "mean": [0.0] * 192,
                    "std": [1.0] * 192}, action_scale=10.0, env={})))
    init = ["--init", str(path)] if args else []
    status = main(["train", "ars-history-clone", "--seed", "1", "--out", str(tmp_path / "o"),
                   *init, *args])
    err = capsys.readouterr().err
    assert status == 2 and err.startswith(f"error: {message}") and len(err.splitlines()) == 1
