"""The pendulum-lqg command: outputs, determinism, resumable benches and bad input (exit 2)."""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import interruptible_cli

from pendulum_lqg.cli import main

ROOT = Path(__file__).resolve().parents[2]


def _json(capsys, argv):
    assert main(argv) == 0
    return json.loads(capsys.readouterr().out)


def test_design_json_has_every_key_with_poles(capsys):
    d = _json(capsys, ["design", "--json"])
    for key in ("A", "B", "C", "D", "Phi", "Gamma", "dt", "K_lqr", "K_dlqr", "L_kalman",
                "L_dkalman", "L_luenberger"):
        assert key in d
    for key in ("K_lqr", "K_dlqr", "L_kalman", "L_dkalman", "L_luenberger"):
        assert len(d[f"{key}_poles"]) == 4
    assert d["dt"] == 0.01
    assert np.array(d["A"]).shape == (4, 4) and np.array(d["L_dkalman"]).shape == (4, 2)
    assert d["A"][3][1] == pytest.approx(15.7888, rel=1e-4)
    assert all(np.hypot(*p) < 1 for p in d["K_dlqr_poles"])           # discrete: inside the circle
    assert all(p[0] < 0 for p in d["K_lqr_poles"])                      # continuous: left half plane
    np.testing.assert_allclose(sorted(p[0] for p in d["L_luenberger_poles"]),
                               [-0.7, -0.6, -0.5, -0.4], atol=1e-9)
    assert d["separation"]["continuous_max_error"] < 1e-8
    assert d["zoh_vs_transition_fd_max_abs"] < 1e-3


def test_design_options_change_the_design(capsys):
    a = _json(capsys, ["design", "--json"])
    b = _json(capsys, ["design", "--json", "--q", "10,1,1,1", "--r", "0.1", "--dt", "0.02",
                       "--observer-poles=-2,-3,-4+1j,-4-1j"])
    assert b["dt"] == 0.02 and a["K_lqr"] != b["K_lqr"]
    assert sorted(round(p[1], 9) for p in b["L_luenberger_poles"]) == [-1, 0, 0, 1]


def test_design_text_output(capsys):
    assert main(["design"]) == 0
    out = capsys.readouterr().out
    assert "state x = [p, θ, ṗ, θ̇]" in out and "Separation principle" in out
    assert "Discrete Kalman, predictor gain" in out


def test_run_json_is_deterministic_and_complete(capsys):
    argv = ["run", "--episodes", "6", "--duration", "2", "--seed", "5", "--json"]
    assert main(argv) == 0
    first = capsys.readouterr().out
    assert main(argv) == 0
    second = capsys.readouterr().out
    assert first == second
    d = json.loads(first)
    assert d["success_rate"] == 1.0 and len(d["episodes"]) == 6
    ep = d["episodes"][0]
    for key in ("seed", "success", "cost", "rms_theta", "max_abs_u", "rms_est_err_theta"):
        assert key in ep
    assert d["config"]["seed"] == 5 and d["config"]["policy"] == "dlqr+kalman"
    assert d["config"]["scenario"]["noise"]["measurement_variance"] == [0.01, 0.01]


def test_run_noise_scale_zero_is_noise_free(capsys):
    d = _json(capsys, ["run", "--episodes", "3", "--duration", "2", "--noise-scale", "0",
                       "--json"])
    costs = {round(e["cost"], 12) for e in d["episodes"]}
    assert len(costs) == 1                                   # identical noise-free episodes


BAD_INPUT = [
    (["run", "--observer", "kalmann"], "argument --observer: invalid choice: 'kalmann'"),
    (["run", "--episodes", "0"], "argument --episodes: expected a positive integer, got '0'"),
    (["run", "--dt", "0.0105"], "control_period: 0.0105 s is not a positive integer multiple"),
    # a declared flag is checked by its declaration, when it is parsed (problem/frontends.py)
    (["run", "--noise-scale", "-1"], "argument --noise-scale: expected a finite number ≥ 0, "
                                     "got '-1'"),
    (["run", "--duration", "nan"], "argument --duration: expected a finite positive number, "
                                   "got 'nan'"),
    (["design", "--q", "1,1,1"], "Q: expected 4 finite non-negative numbers"),
    (["design", "--q", "1,-1,1,1"], "Q: expected 4 finite non-negative numbers"),
    (["design", "--r", "0"], "R: expected a finite positive number, got 0.0"),
    (["design", "--v", "0,0.01"], "V: must be positive definite"),
    (["design", "--w", "-1"], "process_density: expected 4 finite non-negative numbers"),
    (["design", "--observer-poles=-1,-2"], "observer_poles: expected 4 poles, found 2"),
    (["design", "--observer-poles=-1+1j,-2,-3,-4"], "observer_poles: pole -1+1j has no "
                                                      "complex-conjugate partner"),
    (["bench", "no_such_experiment"], "experiment: no file 'no_such_experiment'"),
    (["design", "--model", "/no/such/model.xml"], "model: file not found: /no/such/model.xml"),
    (["run", "--model", str(ROOT / "README.md")], "model: cannot parse"),
]


@pytest.mark.parametrize(("argv", "message"), BAD_INPUT)
def test_bad_input_exits_2_with_one_line(capsys, argv, message):
    try:
        status = main(argv)
    except SystemExit as exc:      # argparse's own errors
        status = exc.code
    err = capsys.readouterr().err
    assert status == 2
    last = err.strip().splitlines()[-1]
    assert last.startswith("error: ") and message in last, err
    assert "Traceback" not in err


def test_bad_input_from_the_console_script_has_no_traceback():
    proc = subprocess.run([sys.executable, "-m", "pendulum_lqg.cli", "run", "--dt", "-1"],
                          capture_output=True, text=True, cwd=ROOT)
    assert proc.returncode == 2
    assert proc.stderr.strip() == "error: control_period: expected a finite positive number, got -1.0"


# ---- bench ---------------------------------------------------------------------------------------
SMALL = """
name = "small"
episodes = 6
seed = 3
chunk = 2
[scenario]
duration = 1.0
[grid]
policy = ["dlqr+kalman", "dlqr+luenberger"]
noise_scale = [0.0, 1.0]
"""


def _bench(tmp_path, *extra):
    spec = tmp_path / "small.toml"
    spec.write_text(SMALL)
    return main(["bench", str(spec), "--out", str(tmp_path / "out"), "--quiet", *extra])


def test_bench_writes_rows_summary_and_refuses_to_overwrite(tmp_path, capsys):
    assert _bench(tmp_path) == 0
    out = tmp_path / "out"
    lines = (out / "episodes.csv").read_text().splitlines()
    assert len(lines) == 1 + 4 * 6
    assert lines[0].startswith("schema_version,config,policy,noise_scale,episode,seed,success,")
    assert all(line.startswith("1,") for line in lines[1:])
    summary = json.loads((out / "summary.json").read_text())
    assert len(summary["configurations"]) == 4 and summary["schema_version"] == 1
    assert "| dlqr+kalman | 1.0 |" in (out / "summary.md").read_text()
    capsys.readouterr()
    assert _bench(tmp_path) == 2
    assert "already holds results; pass --force" in capsys.readouterr().err
    before = (out / "episodes.csv").read_bytes()
    assert _bench(tmp_path, "--force") == 0
    assert (out / "episodes.csv").read_bytes() == before          # byte-identical rerun


def test_bench_resume_completes_to_identical_results(tmp_path, capsys):
    assert _bench(tmp_path) == 0
    out = tmp_path / "out"
    full = (out / "episodes.csv").read_bytes()
    units = sorted((out / "units").glob("*.csv"))
    assert len(units) == 12
    for f in units[5:]:
        f.unlink()
    (out / "episodes.csv").unlink()
    assert _bench(tmp_path, "--resume") == 0
    assert (out / "episodes.csv").read_bytes() == full


@pytest.mark.slow
def test_bench_resume_after_sigint_matches_uninterrupted(tmp_path):
    spec = tmp_path / "s.toml"
    # 4 configurations × 10 units of 2 episodes: room to interrupt after 3 units and before 40
    spec.write_text(SMALL.replace("episodes = 6", "episodes = 20").replace("duration = 1.0",
                                                                           "duration = 3.0"))
    ref, part = tmp_path / "ref", tmp_path / "part"
    cmd = interruptible_cli("bench", spec, "--quiet")
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    # the reference in this process (the same command; only the interrupted run needs a process)
    assert main(["bench", str(spec), "--quiet", "--out", str(ref)]) == 0
    proc = subprocess.Popen([*cmd, "--out", str(part)], cwd=ROOT, env=env,
                            stderr=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    deadline = time.time() + 60
    while time.time() < deadline and len(list((part / "units").glob("*.csv"))) < 3:
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "interrupted:" in err and "--resume" in err
    done = list((part / "units").glob("*.csv"))
    assert 3 <= len(done) < 40
    assert not list(part.rglob(".*.tmp"))                          # nothing half-written
    assert not (part / ".lock").exists()
    subprocess.run([*cmd, "--out", str(part), "--resume"], check=True, cwd=ROOT, env=env,
                   capture_output=True)
    assert (part / "episodes.csv").read_bytes() == (ref / "episodes.csv").read_bytes()
    assert (part / "summary.json").read_bytes() == (ref / "summary.json").read_bytes()


@pytest.mark.parametrize(("text", "message"), [
    ("episodes = 2\n[grid]\npolicy = ['dlqr+kalman']\nnoise_scal = [1.0]\n",
     "grid: unknown key 'noise_scal'; known keys: policy, controller, observer, noise_scale"),
    ("episodes = 2\n[scenario]\nduraton = 1.0\n",
     "scenario: unknown key 'duraton'; known keys: control_period, duration"),
    ("episods = 2\n", "experiment: unknown key 'episods'; known keys: name, description, episodes"),
    ("episodes = 2\n[grid]\npolicy = ['dlqr+kalmann']\n", "observer: unknown 'kalmann'"),
    ("episodes = 2\n[grid]\ncontrol_period = [0.0125]\n", "control_period: 0.0125 s is not"),
    ("episodes = 2\n[noise]\nscale = -3\n", "noise_scale: expected a finite number ≥ 0"),
    ("episodes = 2\n[model]\npole_mass = -1\n", "pole_mass: expected a finite positive number"),
    ("episodes = [\n", "is not valid TOML"),
])
def test_bad_experiment_files(tmp_path, capsys, text, message):
    spec = tmp_path / "bad.toml"
    spec.write_text(text)
    assert main(["bench", str(spec), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and message in err and "\n" not in err, err
    assert not (tmp_path / "o").exists()


def test_cli_module_imports_no_heavy_dependencies():
    code = ("import sys, pendulum_lqg.cli; "
            "print(sorted(m for m in ('numpy', 'mujoco', 'control', 'scipy', 'rich', 'rerun') "
            "if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT,
                         check=True).stdout.strip()
    assert out in ("[]", "['numpy']"), out   # gymnasium registration may bring numpy, no more


def test_results_are_byte_identical_for_any_thread_count(tmp_path):
    spec = tmp_path / "small.toml"
    spec.write_text(SMALL)
    outs = []
    for nthread in ("1", "2"):
        out = tmp_path / f"out{nthread}"
        assert main(["bench", str(spec), "--out", str(out), "--quiet", "--nthread", nthread]) == 0
        outs.append(out)
    for name in ("episodes.csv", "summary.json", "summary.md", "spec.json"):
        assert (outs[0] / name).read_bytes() == (outs[1] / name).read_bytes(), name
    # timestamps live apart, in meta.json
    assert (outs[0] / "meta.json").read_bytes() != (outs[1] / "meta.json").read_bytes()


def test_a_second_run_into_a_busy_folder_is_refused(tmp_path, capsys):
    from pendulum_lqg.util.files import FileLock

    out = tmp_path / "out"
    out.mkdir()
    writer = FileLock(out / ".lock", where="out")         # a live writer holds the folder's lock
    writer.acquire()
    spec = tmp_path / "small.toml"
    spec.write_text(SMALL)
    assert main(["bench", str(spec), "--out", str(out), "--resume", "--quiet"]) == 2
    assert f"is being written by another run (pid {os.getpid()})" in capsys.readouterr().err
    writer.release()
    (out / ".lock").write_text("999999999")                # an old version's PID file: no lock
    assert main(["bench", str(spec), "--out", str(out), "--resume", "--quiet"]) == 0
    assert not (out / ".lock").exists()


# ---- what a new user tripped on: negative values, help ---------------------------------------------
def test_negative_numbers_and_lists_are_taken_in_their_natural_form(capsys):
    assert main(["design", "--observer-poles", "-2,-3,-4,-5", "--q", "1,2,3,4", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    poles = sorted(complex(re, im).real for re, im in d["L_luenberger_poles"])
    assert poles == pytest.approx([-5, -4, -3, -2], abs=1e-9)
    assert main(["design", "--observer-poles", "-1+2j,-1-2j,-3,-4", "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert sorted(complex(re, im).imag for re, im in d["L_luenberger_poles"]) == \
        pytest.approx([-2, 0, 0, 2], abs=1e-9)
    assert main(["run", "--theta0", "-0.1", "--episodes", "1", "--duration", "0.5", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["config"]["scenario"]["x0"][1] == -0.1
    with pytest.raises(SystemExit) as exit_:                          # still a clean error
        main(["run", "--theta0", "-", "--episodes", "1"])
    assert exit_.value.code == 2
    assert "error: argument --theta0: expected a finite number" in capsys.readouterr().err


def test_every_subcommand_and_option_has_help():
    from pendulum_lqg.cli import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    assert set(sub.choices) == {"design", "run", "bench", "report", "perf", "score", "board",
                                "theory", "train"}
    for name, p in sub.choices.items():
        assert p.description, f"{name} has no description"
        for action in p._actions:
            if isinstance(action, argparse._HelpAction):
                continue
            assert action.help and len(action.help) > 10, f"{name} {action.dest} has no help"
            takes_value = action.nargs != 0 and action.option_strings
            if takes_value and action.dest not in ("policy", "out", "record", "model", "address"):
                assert "default" in action.help, f"{name} {action.dest}: help names no default"


def test_run_summary_reports_settling_time_only_noise_free(capsys):
    assert main(["run", "--episodes", "2", "--duration", "2", "--noise-scale", "0"]) == 0
    quiet = capsys.readouterr().out
    assert "settling time [s] (|θ| ≤ 0.02 rad from then on; successes)" in quiet
    assert "time saturated [% of the episode]" in quiet
    assert main(["run", "--episodes", "2", "--duration", "2"]) == 0
    noisy = capsys.readouterr().out
    assert "settling time [s]" not in noisy and "not reported under noise" in noisy


def test_bench_record_after_bench_records_from_the_finished_results(tmp_path, capsys):
    """The README's order — `bench NAME`, then `bench NAME --record DIR` — works as written."""
    assert _bench(tmp_path) == 0
    out = tmp_path / "out"
    before = (out / "episodes.csv").read_bytes(), (out / "summary.json").read_bytes()
    rec = tmp_path / "recordings"
    rec.mkdir()                                   # an existing folder is fine too
    assert _bench(tmp_path, "--record", str(rec)) == 0
    assert ((out / "episodes.csv").read_bytes(), (out / "summary.json").read_bytes()) == before
    names = sorted(p.name for p in rec.glob("*.rrd"))
    assert names == ["small_c000_dlqr+kalman_noise_scale0.0.rrd",
                     "small_c001_dlqr+kalman_noise_scale1.0.rrd",
                     "small_c002_dlqr+luenberger_noise_scale0.0.rrd",
                     "small_c003_dlqr+luenberger_noise_scale1.0.rrd"]
    capsys.readouterr()
    # another experiment's results in the folder are still refused without --force
    assert main(["bench", str(tmp_path / "small.toml"), "--out", str(out), "--quiet", "--seed",
                 "4", "--record", str(rec)]) == 2
    assert "already holds results" in capsys.readouterr().err
