"""Design and run flags that used to end in a traceback or never end: one line, exit 2."""

from __future__ import annotations

import pytest
from conftest import assert_one_line_error, run_cli


# ---- 1. design / run flags that used to end in a traceback or never end ------------------------
@pytest.mark.parametrize(("argv", "name", "detail"), [
    (["design", "--q", "0,0,0,0"], "Q:", "no stabilising LQR"),
    (["design", "--r", "1e300"], "lqr:", "check the scaling of Q and R"),
    (["design", "--w", "1e300"], "kalman:", "check the scaling of W and V"),
    (["design", "--w", "0,0,0,0"], "W:", "no stabilising Kalman filter"),
    (["design", "--dt", "100"], "control_period:", "expected at most 1 s"),
    (["design", "--dt", "1e5"], "control_period:", "expected at most 1 s"),
    (["run", "--duration", "1e308", "--episodes", "1"], "duration:", "at most 1e+08 control"),
    (["run", "--duration", "2e6", "--episodes", "1"], "duration:", "at most 1e+08 control"),
])
def test_design_and_run_flags_end_in_one_line_errors(capsys, argv, name, detail):
    status, err = run_cli(capsys, argv)
    assert_one_line_error(status, err, name)
    assert detail in err, err


# ---- 2. ceilings and names that were missing -----------------------------------------------------
@pytest.mark.parametrize(("argv", "name", "detail"), [
    (["run", "--dt", "1e-320", "--episodes", "1"], "control_period:",
     "expected at least 1e-06 s (the floor), got 1e-320 s"),
    (["perf", "--repeats", "1000000000"], "repeats:", "at most 100 (alternating pairs"),
    (["perf", "--episodes", "1000000000000"], "episodes:", "at most 100,000"),
    (["perf", "--duration", "1e6"], "episodes × duration:",
     "at most 10,000,000 (physics steps of the batch, 1,024 episodes × 1,000,000,000 steps"),
    (["perf", "--episodes", "100000", "--duration", "1"], "episodes × duration:",
     "got 100,000,000"),
])
def test_sizes_and_periods_are_refused_before_any_work(capsys, argv, name, detail):
    import time

    t = time.perf_counter()
    status, err = run_cli(capsys, argv)
    assert_one_line_error(status, err, name)
    assert detail in err, err
    assert time.perf_counter() - t < 30            # refused, not run (imports included)


def test_record_paths_that_cannot_be_a_recording_are_refused_before_running(tmp_path, capsys):
    import time

    for path, detail in ((str(tmp_path), f"record: {tmp_path} is a folder; expected a file path"),
                         ("", "record: expected a file path for the recording (FILE.rrd), got ''")):
        t = time.perf_counter()
        status, err = run_cli(capsys, ["run", "--episodes", "200", "--duration", "10",
                                       "--record", path])
        assert_one_line_error(status, err, detail)
        assert time.perf_counter() - t < 30        # before the 200 episodes, not after
    status, err = run_cli(capsys, ["bench", "lecture", "--episodes", "1", "--record", "",
                                   "--out", str(tmp_path / "o")])
    assert_one_line_error(status, err, "--record: expected a folder for the recordings, got ''")
