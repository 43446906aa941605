"""The bench summary's theory columns: the closed-form stationary loop beside the Monte Carlo."""

from __future__ import annotations

import json

import pytest

from pendulum_lqg.bench.experiments import parse_spec
from pendulum_lqg.bench.results import config_theory
from pendulum_lqg.cli import main
from pendulum_lqg.policies.theory import lecture_theory

GRID = """
name = "free"
episodes = 2
[scenario]
duration = 0.2
plant = "linear-zoh"
theta_max = inf
track_limit = inf
force_limit = inf
[grid]
policy = ["dlqr+luenberger", "dlqr+kalman"]
"""


def test_summary_carries_the_theory_of_each_configuration(tmp_path, capsys):
    spec = tmp_path / "free.toml"
    spec.write_text(GRID)
    assert main(["bench", str(spec), "--out", str(tmp_path / "out"), "--quiet"]) == 0
    table = capsys.readouterr().out
    assert "| theory |" in table and "loop radius" in table
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    from pendulum_lqg.model.plant import load_plant

    expected = lecture_theory(("dlqr+luenberger", "dlqr+kalman"), plant=load_plant())
    for entry in summary["configurations"]:
        th, ref = entry["theory"], expected[entry["values"]["policy"]]
        assert th["plant"] == "linear-zoh" and th["stable"] is True
        assert th["spectral_radius"] == pytest.approx(ref.spectral_radius, rel=1e-12)
        assert th["rms_theta"] == pytest.approx(ref.rms["theta"], rel=1e-9)
        assert th["rms_est_err_theta"] == pytest.approx(ref.estimate_error_std["theta"], rel=1e-9)
        assert f"{th['spectral_radius']:.4f}" in table


@pytest.mark.parametrize("extra, theory", [("", True), ("actuator_delay = 0.01", False)])
def test_theory_is_left_out_where_it_does_not_model_the_loop(extra, theory):
    import tomllib

    data = tomllib.loads(GRID.replace("force_limit = inf", "force_limit = inf\n" + extra))
    spec = parse_spec(data)
    assert (config_theory(spec.configurations[0]) is not None) is theory
