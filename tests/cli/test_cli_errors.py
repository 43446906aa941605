"""Design and run flags that used to end in a traceback or never end: one line, exit 2."""

from __future__ import annotations

import os

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


# ---- 3. outputs: one rule for every written file (issue 45) --------------------------------------
def test_run_plot_failed_write_keeps_the_old_picture(tmp_path):
    """A write that fails midway (here a file-size limit, as `ulimit -f 4`) leaves the old picture
    whole: the new one is written beside it and renamed only once complete. It used to be
    truncated to the 4 096 bytes written."""
    import resource
    import subprocess
    import sys

    old = b"\x89PNG\r\n\x1a\n" + bytes(range(256)) * 80          # 20 kB, larger than the limit
    picture = tmp_path / "episode.png"
    picture.write_bytes(old)

    def limit_file_size():
        resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))

    done = subprocess.run([sys.executable, "-m", "pendulum_lqg.cli", "run", "--episodes", "1",
                           "--duration", "0.5", "--plot", str(picture)],
                          capture_output=True, text=True, preexec_fn=limit_file_size,
                          cwd=tmp_path, env={**os.environ, "PYTHONDONTWRITEBYTECODE": "1"},
                          timeout=600)
    assert picture.read_bytes() == old, f"{picture.stat().st_size} bytes left"
    assert_one_line_error(done.returncode, done.stderr,
                          f"cannot write or read {picture}: File too large")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["episode.png"]   # no temporary left


@pytest.mark.parametrize("where", ["--plot", "--record", "score --out", "board --out"])
def test_symlink_loop_output_refused_in_one_line(tmp_path, capsys, where):
    """An output path that is a symbolic link to itself: one line naming the option, exit 2,
    before any work (it was a RuntimeError traceback from pathlib)."""
    loop = tmp_path / {"--plot": "loop.png", "--record": "loop.rrd", "score --out": "loop.json",
                       "board --out": "loop.md"}[where]
    loop.symlink_to(loop.name)
    argv = {"--plot": ["run", "--episodes", "1", "--duration", "0.1", "--plot", str(loop)],
            "--record": ["run", "--episodes", "1", "--duration", "0.1", "--record", str(loop)],
            "score --out": ["score", "dlqr+kalman", "--suite", "lecture", "--episodes", "1",
                            "--out", str(loop)],
            "board --out": ["board", str(tmp_path), "--out", str(loop)]}[where]
    status, err = run_cli(capsys, argv)
    assert_one_line_error(status, err, f"{where.split()[-1]}: {loop} is a symbolic link that "
                                       "loops")
    assert os.readlink(loop) == loop.name                      # left as it is
