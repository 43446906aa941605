"""``pendulum-lqg theory`` and the limit options of ``run``."""

from __future__ import annotations

import json

import pytest

from pendulum_lqg.cli import main


def test_theory_json_gives_the_issue_answer(capsys):
    """The acceptance command: Luenberger stable with std p beyond the ±2.4 m track; the keys."""
    assert main(["theory", "dlqr+luenberger", "dlqr+kalman", "--plant", "linear-zoh",
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    lu, ka = out["policies"]["dlqr+luenberger"], out["policies"]["dlqr+kalman"]
    assert lu["stable"] is True and lu["std"]["p"] > 2.4
    assert ka["stable"] is True and ka["std"]["p"] < 2.4
    for entry in (lu, ka):
        assert set(entry["std"]) == set(entry["estimate_error_std"]) == {"p", "theta", "p_dot",
                                                                          "theta_dot"}
        assert {"spectral_radius", "u_std", "cost_rate"} <= set(entry)
        assert entry["cost_J"] == pytest.approx(10.0 * entry["cost_rate"])


def test_theory_noise_scale_scales_every_std(capsys):
    """The loop is linear: twice the noise std, twice every stationary std."""
    stds = []
    for scale in ("1", "2"):
        assert main(["theory", "dlqr+kalman", "--noise-scale", scale, "--json"]) == 0
        stds.append(json.loads(capsys.readouterr().out)["policies"]["dlqr+kalman"]["std"])
    for name in stds[0]:
        assert stds[1][name] == pytest.approx(2 * stds[0][name], rel=1e-9)


def test_theory_table_prints_the_verdicts(capsys):
    assert main(["theory", "dlqr+luenberger"]) == 0
    assert "exceeds the track ±2.4 m" in capsys.readouterr().out


@pytest.mark.parametrize("argv, message", [
    (["theory", "dlqr+nope"], "observer"),
    (["theory", "plugin.py:make"], "plugin"),
    (["run", "--track-limit", "inf", "--episodes", "1"], "track_limit"),
])
def test_theory_and_limit_errors_are_one_line(capsys, argv, message):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err


def test_run_with_every_limit_off_on_the_linear_plant(capsys):
    """The lecture's unbounded linear loop: Luenberger survives every episode once no limit is
    in force (with the limits on it fails at the track, README)."""
    assert main(["run", "--observer", "luenberger", "--plant", "linear-euler", "--episodes", "4",
                 "--theta-max", "inf", "--track-limit", "inf", "--force-limit", "inf",
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["summary"]["successes"] == 4
    assert out["summary"]["saturated_fraction"]["mean"] == 0.0
