"""The picture of an episode: its panels, the ±2σ band from P, the limits, and `run --plot`."""

from __future__ import annotations

import math
import os
import re
import stat
import subprocess
import sys
from pathlib import Path

import matplotlib
import numpy as np
import pytest

from pendulum_lqg import Scenario, run_episodes
from pendulum_lqg.analysis.episode_plot import STATE_LABELS, plot_episode
from pendulum_lqg.cli import main
from pendulum_lqg.core.rules import saturate
from pendulum_lqg.policies.loading import build_policy

ROOT = Path(__file__).resolve().parents[2]


def _episode(plant, name, **scenario):
    sc = Scenario(duration=1.0, **scenario)
    policy = build_policy(name, plant=plant, scenario=sc)
    res = run_episodes(plant, sc, policy, seed=3, episodes=[0], trajectory=True)
    assert res.trajectories is not None
    return res.trajectories[0], sc


def test_one_panel_per_state_then_y_and_u_with_the_limits(plant):
    tr, sc = _episode(plant, "dlqr+kalman")
    fig = plot_episode(tr, plant=plant, scenario=sc)
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert labels == [*STATE_LABELS, "y", "u [N]"]
    # the dashed limits: ±track on p, ±θ_max on θ, ±u_max on u — from the plant and the scenario
    def hlines(ax):
        return sorted(line.get_ydata()[0] for line in ax.get_lines() if line.get_linestyle() == "--"
                      and np.ptp(line.get_ydata()) == 0 and len(line.get_xdata()) == 2)
    assert hlines(fig.axes[0]) == pytest.approx([-plant.track_limit, plant.track_limit])
    assert hlines(fig.axes[1]) == pytest.approx([-sc.theta_max, sc.theta_max])
    assert hlines(fig.axes[5]) == pytest.approx([-plant.u_max, plant.u_max])
    assert plant.track_limit == pytest.approx(2.4) and plant.u_max == pytest.approx(10.0)
    # the limits in force are the scenario's: a smaller track and force, θ_max switched off
    tr, sc = _episode(plant, "dlqr+kalman", track_limit=1.5, force_limit=4.0, theta_max=math.inf)
    fig = plot_episode(tr, plant=plant, scenario=sc)
    assert hlines(fig.axes[0]) == pytest.approx([-1.5, 1.5])
    assert hlines(fig.axes[1]) == []
    assert hlines(fig.axes[5]) == pytest.approx([-4.0, 4.0])
    # the measurement panel draws y itself, both channels
    ys = [line.get_ydata() for line in fig.axes[4].get_lines()]
    np.testing.assert_array_equal(ys[0], tr.y[:, 0])
    np.testing.assert_array_equal(ys[1], tr.y[:, 1])


def test_the_band_is_the_estimate_plus_minus_two_sigma_of_the_kalman_covariance(plant):
    tr, sc = _episode(plant, "dlqr+kalman")
    fig = plot_episode(tr, plant=plant, scenario=sc)
    for i, ax in enumerate(fig.axes[:4]):
        (band,) = ax.collections
        xs, ys = band.get_paths()[0].vertices.T
        sigma = np.sqrt(tr.P[:, i, i])
        assert np.all(sigma > 0)
        # at every sample time the band spans exactly x̂ − 2σ … x̂ + 2σ
        lo = np.array([ys[xs == t].min() for t in tr.t])
        hi = np.array([ys[xs == t].max() for t in tr.t])
        np.testing.assert_allclose(lo, tr.x_hat[:, i] - 2 * sigma, rtol=0, atol=1e-12)
        np.testing.assert_allclose(hi, tr.x_hat[:, i] + 2 * sigma, rtol=0, atol=1e-12)


def test_an_estimator_without_covariance_gets_no_band(plant):
    tr, sc = _episode(plant, "dlqr+luenberger")
    assert np.isnan(tr.P).all()
    fig = plot_episode(tr, plant=plant, scenario=sc)
    assert all(not ax.collections for ax in fig.axes[:4])
    np.testing.assert_array_equal(fig.axes[1].get_lines()[1].get_ydata(), tr.x_hat[:, 1])


class _Proportional:
    """u = gain · θ measured, not saturated: the loop saturates it."""

    def __init__(self, gain: float) -> None:
        self.gain = gain

    def reset(self, n: int) -> None:
        pass

    def act(self, y: np.ndarray) -> np.ndarray:
        return self.gain * y[:, 1]


def test_the_policy_force_before_saturation_is_kept_and_drawn(plant):
    sc = Scenario(duration=0.5, x0=(0.0, 0.1, 0.0, 0.0))
    (tr,) = run_episodes(plant, sc, _Proportional(300.0), seed=3, episodes=[0],
                         trajectory=True).trajectories or []
    assert tr.u_policy is not None and np.abs(tr.u_policy).max() > plant.u_max
    np.testing.assert_array_equal(tr.u, saturate(tr.u_policy, plant.u_max))
    fig = plot_episode(tr, plant=plant, scenario=sc)
    labels = [line.get_label() for line in fig.axes[5].get_lines()]
    assert labels[:2] == ["u asked by the policy", "u applied"]
    assert not fig.axes[0].collections          # no estimator: no estimate, no band
    labels = [line.get_label() for line in fig.axes[0].get_lines()]
    assert len(labels) == 3 and labels[0] == "x (true)" and "failure limit" in labels


def test_the_figure_renders_itself_for_jupyter_without_pyplot(plant):
    tr, sc = _episode(plant, "dlqr+kalman")
    png = plot_episode(tr, plant=plant, scenario=sc)._repr_png_()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 10_000


def test_plotting_leaves_the_callers_matplotlib_state_alone(plant):
    tr, sc = _episode(plant, "dlqr+kalman")
    before = (matplotlib.get_backend(), dict(matplotlib.rcParams))
    plot_episode(tr, plant=plant, scenario=sc)
    assert (matplotlib.get_backend(), dict(matplotlib.rcParams)) == before
    code = ("import sys, pendulum_lqg.analysis.episode_plot, pendulum_lqg.cli; "
            "print(sorted(m for m in ('matplotlib', 'matplotlib.pyplot') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT,
                         check=True).stdout.strip()
    assert out == "[]", out


def test_run_plot_writes_a_png_of_the_first_episode(tmp_path, capsys, monkeypatch):
    import pendulum_lqg.analysis.episode_plot as episode_plot

    saved = []
    real_save = episode_plot.save_episode_plot
    monkeypatch.setattr(episode_plot, "save_episode_plot",
                        lambda fig, path: saved.append(fig) or real_save(fig, path))
    out = tmp_path / "ep.png"
    assert main(["run", "--plot", str(out), "--episodes", "1", "--duration", "1"]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert f"plot: {out} (episode 0)" in capsys.readouterr().err
    (fig,) = saved              # one panel per state, then y and u
    assert [ax.get_ylabel() for ax in fig.axes] == [*STATE_LABELS, "y", "u [N]"]
    assert fig.get_suptitle().startswith("dlqr+kalman: episode 0 (seed ")


def test_run_plot_episode_k_writes_an_svg(tmp_path, capsys):
    out = tmp_path / "ep.svg"
    assert main(["run", "--plot", str(out), "--plot-episode", "2", "--episodes", "3",
                 "--duration", "1"]) == 0
    assert out.read_text().lstrip().startswith("<?xml") and "<svg" in out.read_text()


@pytest.mark.parametrize(("argv", "message"), [
    (["--plot", "ep.gif"], "--plot: expected a file name ending in .png, .svg, .pdf"),
    (["--plot", "ep.png", "--plot-episode", "1"], "--plot-episode: expected an episode of this run"),
    (["--plot-episode", "1"], "--plot-episode: needs --plot FILE"),
    (["--plot", ""], "--plot: expected a file name ending in .png"),
])
def test_bad_plot_options_exit_2_with_one_line(tmp_path, capsys, monkeypatch, argv, message):
    monkeypatch.chdir(tmp_path)
    assert main(["run", "--episodes", "1", "--duration", "0.1", *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "\n" not in err, err
    assert not list(tmp_path.iterdir())


def test_plot_refuses_a_folder_or_a_fifo_before_running(tmp_path, capsys):
    # the picture's target is checked like every output: only a new path or a regular file
    (tmp_path / "dir.png").mkdir()
    os.mkfifo(tmp_path / "fifo.png")
    for name in ("dir.png", "fifo.png"):
        assert main(["run", "--episodes", "1", "--duration", "0.1",
                     "--plot", str(tmp_path / name)]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("error: --plot:") and "\n" not in err, err
    assert (tmp_path / "dir.png").is_dir() and stat.S_ISFIFO((tmp_path / "fifo.png").stat().st_mode)


def test_plot_creates_its_folder(tmp_path):
    out = tmp_path / "new" / "folder" / "ep.png"
    assert main(["run", "--episodes", "1", "--duration", "0.2", "--plot", str(out)]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_no_module_of_the_package_uses_pyplot():
    # pyplot keeps global figures and a global backend; the package draws with Figure objects
    users = [str(p.relative_to(ROOT)) for p in (ROOT / "pendulum_lqg").rglob("*.py")
             if re.search(r"matplotlib\.pyplot|from matplotlib import .*pyplot",
                          p.read_text(encoding="utf-8"))]
    assert users == [], users
