"""Issue 55: the numbers the report and the bench table show, on the cart-pole and on a plant
given as matrices (items 7, 8, 9, 11)."""

from __future__ import annotations

import json
from pathlib import Path

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


def _table_row(md, policy):
    lines = md.splitlines()
    head = next(line for line in lines if line.startswith("| policy |"))
    row = next(line for line in lines if line.startswith(f"| {policy} |"))
    return ([c.strip() for c in head.strip("|").split("|")],
            [c.strip() for c in row.strip("|").split("|")])


def test_item7_bench_table_shows_the_episode_theory(tmp_path):
    """A noise-free double integrator started at x₀ = [1, 0]: its stationary RMS is 0, the episode
    theory is the transient, and the simulated RMS is that transient."""
    lti = Path(__file__).resolve().parents[2] / "experiments" / "lti" / "double_integrator.toml"
    exp = tmp_path / "quiet.toml"
    exp.write_text(f'name = "quiet"\nlti_file = "{lti}"\nepisodes = 2\nseed = 0\n'
                   '[scenario]\nduration = 5.0\n[grid]\npolicy = ["dlqr+kalman"]\n'
                   'noise_scale = [0.0]\n')
    out = tmp_path / "res"
    assert main(["bench", str(exp), "--out", str(out)]) == 0
    th = json.loads((out / "summary.json").read_text())["configurations"][0]["theory"]
    assert th["rms_position"] == 0.0                   # stationary: nothing left without noise
    ep = th["episode"]["rms_position"]
    head, row = _table_row((out / "summary.md").read_text(), "dlqr+kalman")
    i = head.index("RMS position")
    assert head[i + 1] == "theory"
    assert row[i + 1] == f"{ep:.3g} (0)"
    assert float(row[i]) == pytest.approx(ep, rel=2e-3)     # the simulation is the transient
    assert "expected RMS over the episode" in (out / "summary.md").read_text()


class _Keep:
    """A :class:`~pendulum_lqg.analysis.reading.Figures` that keeps the figures it made."""

    def __init__(self):
        from pendulum_lqg.analysis.reading import Figures

        self._mk, self.figures = Figures(), []

    def subplots(self, *args, **kwargs):
        fig, axes = self._mk.subplots(*args, **kwargs)
        self.figures.append(fig)
        return fig, axes


def test_item9_cost_boxes_show_n_and_no_box_below_the_minimum(tmp_path):
    from pendulum_lqg.analysis.figures import MIN_BOX_EPISODES, _cost_boxes

    assert MIN_BOX_EPISODES == 10
    rng = np.random.default_rng(0)
    rows = [{"config": 0, "policy": "dlqr+kalman", "success": True, "cost": float(c)}
            for c in 30 + rng.random(200)]
    rows += [{"config": 1, "policy": "dlqr+luenberger", "success": i < 2, "cost": 5.0 + i}
             for i in range(200)]                              # 2 survivors of 200, cheap ones
    keep = _Keep()
    assert _cost_boxes(rows, tmp_path, "t", ["policy"], None, keep) == "t_cost_distribution.png"
    ax = keep.figures[0].axes[0]
    texts = sorted(t.get_text() for t in ax.texts)
    assert texts == ["n = 2 < 10: no box", "n = 200"]
    labels = [t.get_text() for t in ax.get_yticklabels()]
    assert labels == ["dlqr+luenberger", "dlqr+kalman"]
    # the two survivors are drawn as points at the luenberger row (y = 1), not as a box
    points = [ln for ln in ax.lines if ln.get_marker() == "x"]
    assert len(points) == 1
    assert list(points[0].get_xdata()) == [5.0, 6.0] and list(points[0].get_ydata()) == [1, 1]
    boxes = [ln for ln in ax.lines if ln.get_marker() != "x"
             and np.all(np.isfinite(np.asarray(ln.get_xdata(), dtype=float)))
             and len(ln.get_xdata())]
    ys = {float(y) for ln in boxes for y in ln.get_ydata()}
    assert ys and all(1.5 < y < 2.5 for y in ys)      # every box artist is kalman's (y = 2)
