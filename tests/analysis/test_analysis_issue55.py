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


def test_item8_episode_band_is_the_filters_covariance_from_its_start(plant):
    """dlqr+kalman from θ₀ = 0.1 with x̂₀ = 0: the stationary P (σ_θ ≈ 0.028) left the true θ
    outside x̂ ± 2σ at the start; the band is now the filter's covariance from M0 = 0.01 I over
    time, which holds the truth through the transient and tends to the stationary P."""
    from pendulum_lqg import Scenario, run_episodes
    from pendulum_lqg.analysis.episode_plot import plot_episode
    from pendulum_lqg.design.kalman import joseph_update
    from pendulum_lqg.policies.loading import build_policy

    sc = Scenario(duration=0.3)
    policy = build_policy("dlqr+kalman", plant=plant, scenario=sc)
    trs = run_episodes(plant, sc, policy, seed=0, episodes=range(100),
                       trajectory=True).trajectories
    est = policy.estimator
    P_ss = est.P
    tr = trs[0]
    # sample 0: the measurement update of M0 with the filter's own (steady) gain
    np.testing.assert_allclose(tr.P[0], joseph_update(0.01 * np.eye(4), est.gain, est.C,
                                                      est.start.V), rtol=1e-12)
    assert tr.P[0, 1, 1] > 10 * P_ss[1, 1]
    err = np.array([t.x_hat - t.x for t in trs])[:, :10, 1]      # θ̂ − θ, the first 0.1 s
    inside = (np.abs(err) <= 2 * np.sqrt(tr.P[:10, 1, 1])).mean()
    inside_stationary = (np.abs(err) <= 2 * np.sqrt(P_ss[1, 1])).mean()
    assert inside >= 0.99                                         # a 2σ band
    assert inside_stationary < 0.5
    fig = plot_episode(tr, plant=plant, scenario=sc)
    xs, ys = fig.axes[1].collections[0].get_paths()[0].vertices.T
    assert ys[xs == tr.t[0]].max() == pytest.approx(tr.x_hat[0, 1] + 2 * np.sqrt(tr.P[0, 1, 1]))
    # a long episode ends at the stationary covariance
    long = run_episodes(plant, Scenario(duration=20.0), policy, seed=0, episodes=[0],
                        trajectory=True).trajectories[0]
    np.testing.assert_allclose(long.P[-1], P_ss, rtol=1e-6, atol=1e-12)


def test_item8_lost_samples_are_predictions_in_the_band(plant):
    """A lost sample has no measurement update: its covariance is the prior's, larger."""
    from pendulum_lqg import Scenario, run_episodes
    from pendulum_lqg.design.kalman import joseph_update
    from pendulum_lqg.policies.loading import build_policy

    sc = Scenario(duration=0.5, dropout=0.3)
    policy = build_policy("dlqr+kalman", plant=plant, scenario=sc)
    tr = run_episodes(plant, sc, policy, seed=1, episodes=[0], trajectory=True).trajectories[0]
    lost = ~np.isfinite(tr.y).all(axis=1)
    k = int(np.nonzero(lost[1:])[0][0]) + 1                       # a lost sample after the first
    est = policy.estimator
    M_k = est.Phi @ tr.P[k - 1] @ est.Phi.T + est.start.Qd
    np.testing.assert_allclose(tr.P[k], M_k, rtol=1e-12)
    updated = joseph_update(M_k, est.gain, est.C, est.start.V)
    assert tr.P[k, 1, 1] > 1.1 * updated[1, 1]                     # no update: wider


def test_item8_matrix_plant_band_starts_at_its_x0():
    """A plant given as matrices has no M0 option: its band starts from the second moment of its
    start, x0 x0ᵀ + diag(x0_std²) with x̂₀ = 0 (the double integrator: x0 = [1, 0])."""
    from pendulum_lqg import Scenario, run_episodes
    from pendulum_lqg.design.kalman import joseph_update
    from pendulum_lqg.model.lti import load_lti
    from pendulum_lqg.policies.lti import design_lti_policy

    lti = load_lti(Path(__file__).resolve().parents[2] / "experiments" / "lti"
                   / "double_integrator.toml")
    policy = design_lti_policy(lti, "dlqr+kalman")
    sc = Scenario(control_period=lti.control_period, duration=0.5, plant="linear-zoh")
    trs = run_episodes(lti, sc, policy, seed=2, episodes=range(50),
                       trajectory=True).trajectories
    est = policy.estimator
    sd = np.zeros(2) if lti.x0_std is None else lti.x0_std
    M0 = np.outer(lti.x0, lti.x0) + np.diag(sd ** 2)
    assert M0[0, 0] == 1.0
    np.testing.assert_allclose(trs[0].P[0], joseph_update(M0, est.gain, est.C, lti.V),
                               rtol=1e-12)
    err = np.array([t.x_hat - t.x for t in trs])[:, :20, 0]         # the first 0.2 s
    assert (np.abs(err) <= 2 * np.sqrt(trs[0].P[:20, 0, 0])).mean() >= 0.95      # a 2σ band
    assert trs[0].P[0, 0, 0] < 0.7 * est.P[0, 0]       # from its start, not from the limit P
