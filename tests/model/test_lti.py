"""Plants given as matrices (pendulum_lqg.model.lti): the experiments' files, their designs against the
documents' numbers, the theory, and one-line errors."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from pendulum_lqg.cli import main
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.model.lti import load_lti, lti_from_mapping
from pendulum_lqg.policies.lti import design_lti_policy, lti_scenario, lti_theory

EXPERIMENTS = Path(__file__).resolve().parents[2] / "experiments" / "lti"


def test_double_integrator_designs_tend_to_the_continuous_ones():
    """At T = 0.01 s the sampled LQ gain is close to K = [1, √2] and the filter gain to L·T with
    the Kalman–Bucy L = [√3, 1]ᵀ (theory §5.2); the continuous lqr gain is exact."""
    di = load_lti(EXPERIMENTS / "double_integrator.toml")
    assert di.n_states == 2 and di.state_names == ("position", "velocity")
    np.testing.assert_allclose(design_lti_policy(di, "lqr+none").K, [[1, math.sqrt(2)]],
                               atol=1e-9)
    np.testing.assert_allclose(design_lti_policy(di, "dlqr+none").K, [[1, math.sqrt(2)]],
                               rtol=1e-2)
    L = design_lti_policy(di, "dlqr+kalman").info["L"]
    np.testing.assert_allclose(L.ravel(), [math.sqrt(3) * 0.01, 0.01], rtol=2e-2)
    # the stationary estimation error of the sampled filter tends to the Kalman–Bucy
    # Σ = [[√3, 1], [1, √3]]: both stds √√3
    err = lti_theory(di, ("dlqr+kalman",))["dlqr+kalman"].estimate_error_std
    assert err["position"] == pytest.approx(3 ** 0.25, rel=1e-2)
    assert err["velocity"] == pytest.approx(3 ** 0.25, rel=1e-2)


def test_ogata_and_franklin_files_reproduce_the_documents():
    ogata = load_lti(EXPERIMENTS / "ogata_discrete.toml")
    assert ogata.discrete
    np.testing.assert_allclose(design_lti_policy(ogata, "dlqr+none").K, [[1.0, 0.7913]],
                               atol=5e-5)
    franklin = load_lti(EXPERIMENTS / "franklin_third_order.toml")
    poles = design_lti_policy(franklin, "dlqr+luenberger").info["observer_poles"]
    expected = np.exp(np.array([-21, -22 + 2j, -22 - 2j]) * 0.02)
    assert np.sort_complex(poles) == pytest.approx(np.sort_complex(expected), abs=1e-9)
    # MATLAB's dlqe(Φ, Ψ, C, Rw, Rv) returns the filter gain; python-control's the predictor gain
    control = pytest.importorskip("control")
    kf = design_lti_policy(franklin, "dlqr+kalman").info["L"]
    L_p = control.dlqe(franklin.Phi, franklin.G, franklin.C, 0.01, 0.01)[0]
    np.testing.assert_allclose(franklin.Phi @ kf, L_p, rtol=1e-8)


def test_lti_theory_scalar_closed_form():
    """x⁺ = a x + u + w, full state, u = −k x: Var x = Wd / (1 − (a − k)²)."""
    plant = lti_from_mapping({"control_period": 1.0, "Phi": [[1.2]], "Gamma": [[1.0]],
                              "W": [0.5], "V": [1.0], "Q": [[1.0]], "R": 1.0})
    res = lti_theory(plant, ("dlqr+none",))["dlqr+none"]
    k = float(design_lti_policy(plant, "dlqr+none").K[0, 0])
    assert res.spectral_radius == pytest.approx(abs(1.2 - k))
    assert res.std["x1"] == pytest.approx(math.sqrt(0.5 / (1 - (1.2 - k) ** 2)), rel=1e-12)


def test_theory_cli_on_the_double_integrator(capsys):
    import json

    assert main(["theory", "--lti", str(EXPERIMENTS / "double_integrator.toml"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out["policies"]) == {"dlqr+none", "dlqr+kalman", "dlqr+luenberger"}
    assert all(p["stable"] for p in out["policies"].values())
    assert set(out["policies"]["dlqr+kalman"]["std"]) == {"position", "velocity"}


@pytest.mark.parametrize("table, message", [
    ({"control_period": 0.1, "A": [[0, 1], [0, 0]]}, "B: missing \\(A and B go together\\)"),
    ({"control_period": 0.1, "A": [[0, 1]], "B": [[0], [1]]}, r"A: expected a \(1 × 1\) .*"
                                                             r"got shape \(1, 2\)"),
    ({"control_period": 0.1, "A": [[0]], "B": [[1]], "Phi": [[1]]}, "either A and B"),
    ({"control_period": 0.1, "A": [[0]], "B": [[1]], "W": [-1]}, "W: expected a symmetric "
                                                              "positive semidefinite matrix, got "
                                                              "smallest eigenvalue -1"),
    ({"control_period": 0.1, "A": [[0]], "B": [[1]], "bogus": 1}, "unknown key 'bogus'"),
    ({"control_period": -1, "A": [[0]], "B": [[1]]}, "control_period"),
])
def test_bad_lti_tables_name_the_key(table, message):
    with pytest.raises(ConfigError, match=message):
        lti_from_mapping(table)


def test_npz_and_toml_give_the_same_plant(tmp_path):
    di = load_lti(EXPERIMENTS / "double_integrator.toml")
    path = tmp_path / "di.npz"
    np.savez(path, control_period=0.01, A=di.A, B=di.B, C=di.C, W=np.diag(di.W), V=np.diag(di.V),
             Q=di.Q, R=1.0)
    again = load_lti(path)
    np.testing.assert_array_equal(again.Phi, di.Phi)
    np.testing.assert_array_equal(again.V, di.V)
    with pytest.raises(ConfigError, match="policy: expected one of lqr, dlqr"):
        design_lti_policy(again, "dlqr+hinf")


# ---- run and bench with an LTI plant ------------------------------------------------------------
def test_run_cli_on_the_double_integrator_gives_run_episodes_rows(capsys):
    """``run --lti`` gives the rows of run_episodes on the same plant, scenario and policy (the
    one loop), under the file's state names, with the file's x0 and force limit (inf)."""
    import json

    from pendulum_lqg.cli.parser import jsonable
    from pendulum_lqg.core.runner import run_episodes
    from pendulum_lqg.policies.lti import lti_scenario

    path = EXPERIMENTS / "double_integrator.toml"
    assert main(["run", "--lti", str(path), "--episodes", "4", "--duration", "3",
                 "--policy", "dlqr+luenberger", "--seed", "2", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["config"]["x0"] == [1.0, 0.0] and out["config"]["force_limit"] == "inf"
    assert out["config"]["state_limits"] == ["inf", "inf"]
    # the scenario reported without the cart-pole's fields (x0, theta_max, noise densities)
    assert out["config"]["scenario"]["noise"] == {"scale": 1.0}
    assert "x0" not in out["config"]["scenario"] and "theta_max" not in out["config"]["scenario"]
    plant = load_lti(path)
    rows = run_episodes(plant, lti_scenario(plant, duration=3.0),
                        design_lti_policy(plant, "dlqr+luenberger"), seed=2,
                        episodes=range(4)).rows
    assert json.dumps(out["episodes"]) == json.dumps(jsonable(rows))      # nan → null in both
    assert {"rms_position", "max_abs_velocity", "rms_est_err_velocity"} <= set(out["summary"])
    assert "rms_theta" not in out["summary"]


@pytest.mark.parametrize("extra, message", [
    (["--theta0", "0.2"], "--theta0: not with --plant"),
    (["--record", "x.rrd"], "--record: not with --plant"),
    (["--plant", "linear-euler"], "--simulator: the plant 'double_integrator' is simulated by linear-zoh"),
    (["--dt", "0.05"], "--dt: the LTI plant 'double_integrator' is sampled at 0.01 s"),
])
def test_run_cli_refuses_the_cartpoles_options_with_lti(capsys, extra, message):
    assert main(["run", "--lti", str(EXPERIMENTS / "double_integrator.toml"), "--episodes", "1",
                 *extra]) == 2
    assert message in capsys.readouterr().err


def test_bench_on_an_lti_experiment(tmp_path):
    """The shipped double_integrator experiment: its CSV columns named after the file's states,
    its rows those of run_episodes, and its summary's theory the theory's numbers."""
    import json

    from pendulum_lqg.bench.experiments import load_spec
    from pendulum_lqg.core.runner import run_episodes
    from pendulum_lqg.policies.lti import lti_scenario
    from pendulum_lqg.util.files import read_csv

    out = tmp_path / "di"
    assert main(["bench", "double_integrator", "--episodes", "3", "--out", str(out),
                 "--quiet"]) == 0
    rows = read_csv(out / "episodes.csv")
    assert len(rows) == 4 * 3 and "rms_velocity" in rows[0] and "rms_theta" not in rows[0]
    plant = load_lti(EXPERIMENTS / "double_integrator.toml")
    mine = run_episodes(plant, lti_scenario(plant, duration=20.0, noise_scale=0.5),
                        design_lti_policy(plant, "dlqr+kalman"), seed=0, episodes=range(3)).rows
    assert [r["cost"] for r in rows[:3]] == [r["cost"] for r in mine]
    summary = json.loads((out / "summary.json").read_text())
    first = summary["configurations"][0]
    th = lti_theory(plant, ("dlqr+kalman",), noise_scale=0.5, duration=20.0)["dlqr+kalman"]
    assert first["theory"]["rms_position"] == th.std["position"]
    assert first["theory"]["rms_est_err_velocity"] == th.estimate_error_std["velocity"]
    assert "| RMS position | theory |" in (out / "summary.md").read_text()
    spec = load_spec("double_integrator")
    assert spec.configurations[0].lti_file.endswith("lti/double_integrator.toml")


@pytest.mark.parametrize("extra, message", [
    ('[scenario]\nx0 = [1, 0, 0, 0]\n', "scenario.x0: not with lti_file"),
    ('[noise]\nprocess_density = [1, 1, 1, 1]\n', "noise.process_density: not with lti_file"),
    ('[grid]\ntheta0 = [0.1]\n', "grid.theta0: not with lti_file"),
    ('[grid]\npolicy = ["plug.py:make"]\n', "grid.policy: 'plug.py:make': a plug-in"),
    ('[grid]\npolicy = ["dlqr+kalman-tv"]\n', "policy: expected one of lqr, dlqr"),
])
def test_bench_lti_experiment_refuses_the_cartpoles_keys(tmp_path, extra, message):
    from pendulum_lqg.bench.experiments import load_spec

    path = tmp_path / "e.toml"
    path.write_text(f'lti_file = "{EXPERIMENTS / "double_integrator.toml"}"\n' + extra)
    with pytest.raises(ConfigError, match=message):
        load_spec(str(path))


# ---- design --lti -------------------------------------------------------------------------------
def test_design_lti_double_integrator_gives_the_textbook_gains(capsys):
    """K = [1, √2] (LQR with Q = CᵀC, R = 1) and L = [√3, 1]ᵀ (Kalman–Bucy with W = I₂ and the
    measurement density V·T = 1): docs/theory.md §5.2."""
    import json

    assert main(["design", "--lti", str(EXPERIMENTS / "double_integrator.toml"), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(d["K_lqr"], [[1.0, math.sqrt(2)]], rtol=0, atol=1e-9)
    np.testing.assert_allclose(d["L_kalman"], [[math.sqrt(3)], [1.0]], rtol=0, atol=1e-9)
    assert d["states"] == ["position", "velocity"] and d["inputs"] == ["u1"]
    assert d["separation"]["continuous_max_error"] < 1e-12
    assert d["separation"]["discrete_max_error"] < 1e-12
    # the discrete gains are the ones run --lti's policies use
    for name, key in (("dlqr+kalman", "L_dkalman"), ("dlqr+luenberger", "L_dluenberger")):
        policy = design_lti_policy(load_lti(EXPERIMENTS / "double_integrator.toml"), name)
        np.testing.assert_allclose(policy.K, d["K_dlqr"], rtol=1e-12)
        np.testing.assert_allclose(policy.info["L"], d[key], rtol=1e-12)


def test_design_lti_of_a_discrete_plant_has_only_the_discrete_designs(capsys):
    import json

    assert main(["design", "--lti", str(EXPERIMENTS / "ogata_discrete.toml"), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(d["K_dlqr"], [[1.0, 0.7913]], atol=1e-4)     # Ogata's table
    assert "K_lqr" not in d and "A" not in d and "continuous_max_error" not in d["separation"]
    assert main(["design", "--lti", str(EXPERIMENTS / "ogata_discrete.toml")]) == 0
    out = capsys.readouterr().out
    assert "Discrete LQR" in out and "Continuous LQR" not in out


@pytest.mark.parametrize("extra", [["--q", "1,1"], ["--dt", "0.02"], ["--model", "x.xml"]])
def test_design_lti_refuses_the_cartpoles_options(capsys, extra):
    path = str(EXPERIMENTS / "double_integrator.toml")
    assert main(["design", "--lti", path, *extra]) == 2
    assert f"{extra[0]}: not with --plant" in capsys.readouterr().err


# ---- pictures of any plant ----------------------------------------------------------------------
@pytest.mark.parametrize("file, labels", [
    ("double_integrator.toml", ["position", "velocity", "y1", "u1"]),
    ("two_mass.toml", ["p1", "p2", "v1", "v2", "y1", "y2", "f1", "f2"]),
])
def test_episode_figure_of_an_lti_plant_has_a_panel_per_state_output_and_input(file, labels):
    """n + p + m panels, each labelled with the file's name; the input panels draw the limit in
    force (the two-mass file's ±5 N per motor) and the output panels y and C x."""
    from pendulum_lqg.analysis.episode_plot import plot_episode
    from pendulum_lqg.core.runner import run_episodes

    plant = load_lti(EXPERIMENTS / file)
    sc = lti_scenario(plant, duration=1.0)
    tr = run_episodes(plant, sc, design_lti_policy(plant, "dlqr+kalman"), seed=0, episodes=[0],
                      trajectory=True).trajectories[0]
    fig = plot_episode(tr, plant=plant, scenario=sc)
    assert [ax.get_ylabel() for ax in fig.axes] == labels
    n, p = plant.n_states, plant.n_outputs
    for j, ax in enumerate(fig.axes[n + p:]):
        limits = sorted(line.get_ydata()[0] for line in ax.lines if line.get_linestyle() == "--")
        assert limits == ([-5.0, 5.0] if file == "two_mass.toml" else [])
        np.testing.assert_array_equal(ax.lines[-1 - len(limits)].get_ydata(),
                                      np.asarray(tr.u).reshape(len(tr.t), -1)[:, j])
    np.testing.assert_array_equal(fig.axes[n].lines[1].get_ydata(), tr.y_true[:, 0])


def test_run_lti_plot_writes_the_picture(tmp_path, capsys):
    path = tmp_path / "two.png"
    assert main(["run", "--lti", str(EXPERIMENTS / "two_mass.toml"), "--episodes", "2",
                 "--duration", "1", "--plot", str(path)]) == 0
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert f"plot: {path} (episode 0)" in capsys.readouterr().err
