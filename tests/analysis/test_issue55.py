"""Issue 55: the numbers the report and the bench table show, on the cart-pole and on a plant
given as matrices (items 7, 8, 9, 11)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from pendulum_lqg.cli import main


@pytest.fixture(scope="module")
def di_results(tmp_path_factory):
    """The shipped ``bench double_integrator`` (a noise sweep on a matrix plant), 8 episodes."""
    out = tmp_path_factory.mktemp("di") / "res"
    assert main(["bench", "double_integrator", "--episodes", "8", "--out", str(out)]) == 0
    return out


def test_item11_report_on_a_matrix_plant_noise_sweep(di_results, tmp_path):
    rep = tmp_path / "rep"
    assert main(["report", str(di_results), "--out", str(rep)]) == 0
    text = (rep / "report.md").read_text()
    assert "### estimation error per state" in text
    assert (rep / "double_integrator_estimation_error.png").stat().st_size > 10_000


def test_item11_summarize_rows_of_a_matrix_plant(di_results):
    from pendulum_lqg.bench.results import read_csv
    from pendulum_lqg.core.metrics import summarize

    rows = [r for r in read_csv(di_results / "episodes.csv") if r["config"] == 0]
    s = summarize(rows)
    pos = np.array([float(r["rms_position"]) for r in rows])
    assert s["rms_position"]["mean"] == pytest.approx(pos.mean(), rel=1e-12)
    assert s["rms_est_err_velocity"]["mean"] > 0
    assert "rms_theta" not in s
    # the same as the bench's own summary of that configuration
    summ = json.loads((di_results / "summary.json").read_text())["configurations"][0]["summary"]
    assert s["rms_velocity"]["mean"] == pytest.approx(summ["rms_velocity"]["mean"], rel=1e-12)
