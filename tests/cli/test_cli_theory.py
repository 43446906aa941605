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


# ---- the expected RMS over the episode beside the stationary one -------------------------------
DI = "experiments/lti/double_integrator.toml"


def test_theory_json_carries_the_episode_from_x0(capsys):
    """``episode``: the expected RMS from the scenario's x₀ = [0, 0.1, 0, 0] and x̂₀ = 0. With a
    known start at rest (``--theta0 0 --estimate0 true``) and a long episode it tends to the
    stationary RMS; from the 0.1 rad tilt the transient raises θ's."""
    assert main(["theory", "dlqr+none", "--json"]) == 0
    tilted = json.loads(capsys.readouterr().out)["policies"]["dlqr+none"]
    assert main(["theory", "dlqr+none", "--theta0", "0", "--estimate0", "true", "--duration",
                 "1000", "--json"]) == 0
    rest = json.loads(capsys.readouterr().out)["policies"]["dlqr+none"]
    assert tilted["episode"]["rms"]["theta"] > 1.5 * tilted["rms"]["theta"]
    assert rest["episode"]["rms"]["theta"] == pytest.approx(rest["rms"]["theta"], rel=1e-2)
    assert rest["episode"]["periods"] == 100_000 and rest["episode"]["skip"] == 0


def test_theory_noise_scale_1e200_refuses_in_one_line(capsys):
    """Issue 45: an OverflowError traceback before; now the documented ceiling (10¹²)."""
    for argv in (["theory", "--noise-scale", "1e200"],
                 ["theory", "--lti", DI, "--noise-scale", "1e200"]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert "noise_scale: expected at most 1e+12 (the ceiling)" in err
        assert "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_bench_grid_with_overflowing_noise_refuses_before_any_unit(tmp_path, capsys):
    """Issue 45: the sweep crashed after computing every unit, and again on --resume; now the
    grid point is refused when the experiment is read, before a results folder exists."""
    spec = tmp_path / "big.toml"
    spec.write_text('name = "big"\nepisodes = 2\n[scenario]\nduration = 0.1\n'
                    '[grid]\nnoise_scale = [1.0, 1e200]\n')
    out = tmp_path / "out"
    assert main(["bench", str(spec), "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "noise_scale: expected at most 1e+12" in err and "grid point noise_scale=1e+200" in err
    assert not out.exists()


def test_theory_lti_one_state_prints_its_table(tmp_path, capsys):
    """Issue 45: a traceback before (the table took two states); now one state's columns."""
    f = tmp_path / "one.toml"
    f.write_text('name = "one"\ncontrol_period = 0.1\nA = [[-1.0]]\nB = [[1.0]]\nC = [[1.0]]\n'
                 'W = [1.0]\nV = [0.1]\nR = 1.0\n')
    assert main(["theory", "--lti", str(f), "dlqr+kalman"]) == 0
    out = capsys.readouterr().out
    assert "std x1" in out and "RMS x1" in out and "std error of x1" in out
    assert main(["theory", "--lti", str(f), "dlqr+kalman", "--json"]) == 0
    entry = json.loads(capsys.readouterr().out)["policies"]["dlqr+kalman"]
    assert f"{entry['std']['x1']:.3g}" in out


@pytest.mark.parametrize("option", [["--theta-max", "0.3"], ["--track-limit", "3"],
                                    ["--force-limit", "5"], ["--plant", "linear-euler"],
                                    ["--observer-poles", "-1,-2"], ["--process-noise", "force"],
                                    ["--model", "my.xml"], ["--q", "1,1"], ["--r", "2"],
                                    ["--w", "1,1"], ["--v", "1"], ["--dt", "0.02"],
                                    ["--theta0", "0.2"]])
def test_theory_lti_refuses_cartpole_options(capsys, option):
    """Issue 45: ``theory --lti`` ignored the cart-pole's options; now each is refused by name."""
    assert main(["theory", "--lti", DI, *option]) == 2
    err = capsys.readouterr().err
    assert err.strip() == f"error: {option[0]}: not with --plant" + err.strip().split(
        "not with --plant")[1] and "Traceback" not in err


@pytest.mark.parametrize("lti", [[], ["--lti", DI]])
def test_theory_negative_noise_scale_refused(capsys, lti):
    """Issue 45: ``--lti`` squared a negative scale away; now refused, with or without it."""
    with pytest.raises(SystemExit) as exc:
        main(["theory", *lti, "--noise-scale", "-1"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "--noise-scale: expected a finite number ≥ 0, got '-1'" in err and "Traceback" not in err


@pytest.mark.parametrize("lti", [[], ["--lti", DI]])
def test_theory_negative_duration_refused(capsys, lti):
    """Issue 45: ``--lti --duration -5`` printed a negative J; now refused."""
    with pytest.raises(SystemExit) as exc:
        main(["theory", *lti, "--duration", "-5"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert "--duration: expected a finite positive number, got '-5'" in err and "Traceback" not in err


def test_run_prints_the_theory_beside_the_monte_carlo(capsys):
    """``run`` on the linear plant: the JSON's ``theory`` is the theory command's, for the run's
    own start and burn-in; the text ends with the two theory lines."""
    argv = ["run", "--plant", "linear-zoh", "--episodes", "2", "--duration", "1",
            "--burn-in", "0.5"]
    assert main([*argv, "--json"]) == 0
    run = json.loads(capsys.readouterr().out)
    assert main(["theory", "dlqr+kalman", "--duration", "1", "--burn-in", "0.5", "--json"]) == 0
    theory = json.loads(capsys.readouterr().out)["policies"]["dlqr+kalman"]
    assert run["theory"]["episode"] == theory["episode"]
    assert run["theory"]["episode"]["skip"] == 50
    assert run["config"]["scenario"]["burn_in"] == 0.5
    assert main(argv) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[-2].startswith("theory (linear-zoh loop, limits off), expected RMS over the "
                              "episode after 0.5 s: p ")
    assert out[-1].startswith("theory, stationary std: p ")


def test_run_lti_json_carries_the_episode_theory(capsys):
    assert main(["run", "--lti", DI, "--episodes", "2", "--duration", "1", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out["theory"]["episode"]["rms"]) == {"position", "velocity"}
    assert "burn_in" not in out["config"]["scenario"]          # the default: as before


def test_run_of_a_plugin_says_the_theory_does_not_apply(capsys):
    assert main(["run", "--policy", "experiments/plugin_example.py:make", "--episodes", "1",
                 "--duration", "0.2"]) == 0
    assert capsys.readouterr().out.splitlines()[-1].startswith("theory: not for this loop (a "
                                                               "plug-in policy")


def test_theory_lti_takes_a_plant_sampled_slower_than_the_loops_ceiling(tmp_path, capsys):
    """A file sampled every 2 s (a slow process) is past the simulated loop's 1 s ceiling of the
    control period, but the theory has no such ceiling: its tables, stationary and episode."""
    f = tmp_path / "slow.toml"
    f.write_text('name = "slow"\ncontrol_period = 2.0\nA = [[-0.01]]\nB = [[1.0]]\n'
                 'C = [[1.0]]\nW = [1.0]\nV = [0.1]\nx0 = [2.0]\n')
    assert main(["theory", "--lti", str(f), "dlqr+kalman", "--duration", "100", "--json"]) == 0
    entry = json.loads(capsys.readouterr().out)["policies"]["dlqr+kalman"]
    assert entry["stable"] and entry["episode"]["periods"] == 50
    assert entry["episode"]["rms"]["x1"] > entry["rms"]["x1"]      # the start at x₀ = 2


def test_two_inputs_have_their_own_spread_in_theory_and_run(capsys):
    """Several inputs: theory --json gives u_std_by_input and episode.u_rms_by_input by the file's
    names, run prints each input in its theory lines and keeps them in --json; the cart-pole's
    theory has neither key."""
    assert main(["theory", "--lti", "experiments/lti/two_mass.toml", "dlqr+kalman", "--json"]) == 0
    ka = json.loads(capsys.readouterr().out)["policies"]["dlqr+kalman"]
    assert set(ka["u_std_by_input"]) == set(ka["episode"]["u_rms_by_input"]) == {"f1", "f2"}
    assert ka["u_std"] == ka["u_std_by_input"]["f1"]
    assert main(["run", "--lti", "experiments/lti/two_mass.toml", "--episodes", "2"]) == 0
    lines = [x for x in capsys.readouterr().out.splitlines() if x.startswith("theory")]
    assert all(" f1 " in x and " f2 " in x for x in lines) and len(lines) == 2
    assert main(["theory", "dlqr+kalman", "--json"]) == 0
    assert "by_input" not in capsys.readouterr().out
