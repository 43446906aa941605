"""Each study and the report, run end to end on freshly generated small results (not the committed
ones): the CLI writes them, the numbers are checked against theory, the report draws them."""

from __future__ import annotations

import json

import pytest

from pendulum_lqg.cli import main

MARGINS = """
name = "m"
study = "margins"
episodes = 1
seed = 0
[margins]
q = [0.1, 10.0, 1000.0]
n_omega = 400
nyquist_points = 40
[grid]
policy = ["lqr+none", "dlqr+kalman"]
control_period = [0.01, 0.1]
"""

ROA = """
name = "r"
study = "roa"
episodes = 6
seed = 0
[scenario]
duration = 2.0
theta_max = 1.5
[roa]
tolerance = 0.05
map_theta = [-1.0, 1.0, 5]
map_theta_dot = [-2.0, 2.0, 3]
[grid]
policy = ["dlqr+none", "dlqr+kalman"]
"""

GRID = """
name = "noise"
episodes = 6
seed = 1
chunk = 3
[scenario]
duration = 1.0
[grid]
policy = ["dlqr+kalman", "dlqr+luenberger"]
noise_scale = [0.0, 1.0]
"""


@pytest.fixture(scope="module")
def fresh(tmp_path_factory):
    root = tmp_path_factory.mktemp("fresh")
    for name, text in (("margins", MARGINS), ("roa", ROA), ("noise", GRID)):
        spec = root / f"{name}.toml"
        spec.write_text(text)
        assert main(["bench", str(spec), "--out", str(root / "results" / name), "--quiet"]) == 0
    return root


def test_margins_study_on_fresh_results(fresh):
    s = json.loads((fresh / "results" / "margins" / "summary.json").read_text())
    lq = next(loop for loop in s["loops"] if loop["loop"] == "LQ (continuous)")
    # Kalman's inequality |1 + L(jω)| ≥ 1: phase margin ≥ 60°, gain margin [1/2, ∞)
    assert lq["min_return_difference"] >= 1 - 1e-6
    assert lq["phase_margin_deg"] >= 60 and lq["gain_margin_lower"] <= 0.5
    sampled = {(loop["policy"], loop["control_period"]) for loop in s["loops"]}
    assert {("dlqr+kalman", 0.01), ("dlqr+kalman", 0.1)} <= sampled
    assert len(s["ltr"]) >= 3


def test_roa_study_on_fresh_results(fresh):
    s = json.loads((fresh / "results" / "roa" / "summary.json").read_text())
    by = {c["label"]: c for c in s["configurations"]}
    assert set(by) == {"policy=dlqr+none", "policy=dlqr+kalman"}
    for c in by.values():
        assert 0.05 <= c["theta_star"] <= c["theta_fail"] <= 1.2
        assert 0 < c["map_recovered_fraction"] <= 1     # (0, 0) at least recovers
    rows = (fresh / "results" / "roa" / "roa_map.csv").read_text().splitlines()
    assert len(rows) == 1 + 2 * 5 * 3


def test_report_on_fresh_results(fresh, tmp_path):
    assert main(["report", str(fresh / "results"), "--out", str(tmp_path)]) == 0
    text = (tmp_path / "report.md").read_text()
    for name in ("m_nyquist.png", "m_ltr.png", "m_sampled.png", "r_maps.png",      # by name
                 "r_theta_star.png", "noise_success_vs_noise_scale.png",
                 "noise_cost_distribution.png"):
        png = tmp_path / name
        assert png.is_file() and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", name
        assert f"]({name})" in text
