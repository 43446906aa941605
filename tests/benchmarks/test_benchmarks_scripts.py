"""The scripts of benchmarks/ meet the command line's contract (issue 45, item 4): a bad flag, a
library error, an output that is not a regular file or folder, or a missing optional library is
one line ``error: …``, exit status 2, no traceback — checked before any work."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def run_script(stem: str, *args: str, cwd: Path, blocked: str | None = None,
               ) -> subprocess.CompletedProcess[str]:
    """``python benchmarks/STEM.py ARGS`` in ``cwd``; ``blocked``: a module whose import fails
    (a stand-in of that name first on the path raises ImportError), as where it is not
    installed."""
    env = dict(os.environ)
    if blocked is not None:
        stub = cwd / "blocked"
        stub.mkdir(exist_ok=True)
        (stub / f"{blocked}.py").write_text(f"raise ImportError('no module named {blocked}')\n")
        env["PYTHONPATH"] = os.pathsep.join([str(stub), env.get("PYTHONPATH", "")])
    return subprocess.run([sys.executable, str(ROOT / "benchmarks" / f"{stem}.py"), *args],
                          cwd=cwd, env=env, capture_output=True, text=True, timeout=600)


def assert_one_line(done: subprocess.CompletedProcess[str], starts: str) -> None:
    assert done.returncode == 2, (done.returncode, done.stderr)
    assert "Traceback" not in done.stderr, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith(f"error: {starts}"), done.stderr
    assert done.stdout == "", done.stdout           # refused before any work


#: Every script that stays in benchmarks/, with a bad value of one of its options.
BAD_FLAGS = [
    ("compare_results", ["no-such-folder", "."], "a: expected a results folder, got "
                                                  "'no-such-folder' (no such folder)"),
    ("env_benchmark", ["--steps", "1e12"], "--steps: expected an integer from 1 to 10,000,000, "
                                           "got '1e12'"),
    ("executor_benchmark", ["--episodes", "-3"], "--episodes: expected an integer from 1 to "
                                                 "100,000, got '-3'"),
    ("identify_benchmark", ["--repeat", "0"], "--repeat: expected an integer from 1 to 100, "
                                              "got '0'"),
    ("instructions", ["loop", "--episodes", "0"], "--episodes: expected an integer from 1 to "
                                                  "100,000, got '0'"),
    ("leaderboard", ["--frames", "5"], "unrecognized arguments: --frames 5"),
    ("loop_profile", ["--duration", "nan"], "--duration: expected a finite positive number, "
                                            "got 'nan'"),
    ("startup", ["--rounds", "0"], "--rounds: expected an integer from 1 to 100, got '0'"),
    ("vector_benchmark", ["--gap", "inf"], "--gap: expected a finite number from 0 to 1e+06, "
                                           "got 'inf'"),
]


@pytest.mark.parametrize(("stem", "args", "starts"), BAD_FLAGS, ids=[c[0] for c in BAD_FLAGS])
def test_benchmark_script_bad_flag_is_one_line_exit_2(tmp_path, stem, args, starts):
    assert_one_line(run_script(stem, *args, cwd=tmp_path), starts)


def test_every_remaining_benchmark_script_is_covered():
    moved = {"train_agents", "train_linear", "pilot_agents", "noise_ladder", "rl_figures"}
    here = {p.stem for p in (ROOT / "benchmarks").glob("*.py")} - moved
    assert here == {stem for stem, _, _ in BAD_FLAGS}


def test_benchmark_script_library_error_is_one_line(tmp_path):
    done = run_script("executor_benchmark", "--experiment", "no-such-experiment", cwd=tmp_path)
    assert_one_line(done, "experiment: ")


def test_benchmark_script_duration_beyond_the_scenario_ceiling_is_one_line(tmp_path):
    done = run_script("loop_profile", "--duration", "1e12", "--episodes", "1", cwd=tmp_path)
    assert_one_line(done, "duration: expected at most 1e+08 control periods")


def _special(tmp_path: Path, kind: str) -> Path:
    target = tmp_path / f"target-{kind}"
    if kind == "fifo":
        os.mkfifo(target)
    elif kind == "folder":
        target.mkdir()
    else:
        target.write_text("a file the user keeps\n")
    return target


@pytest.mark.parametrize("kind", ["folder", "fifo"])
def test_benchmark_script_output_file_that_is_a_folder_or_fifo_is_refused(tmp_path, kind):
    target = _special(tmp_path, kind)
    done = run_script("instructions", "env", "--out", str(target), cwd=tmp_path)
    says = {"folder": "is a folder", "fifo": "is a FIFO (named pipe)"}[kind]
    assert_one_line(done, f"--out: {target} {says}; expected a regular file or a new path for the "
                          "callgrind profile")
    assert target.exists() and not target.is_file()


@pytest.mark.parametrize("kind", ["file", "fifo"])
def test_benchmark_script_output_folder_that_is_a_file_or_fifo_is_refused(tmp_path, kind):
    target = _special(tmp_path, kind)
    done = run_script("leaderboard", "--out", str(target), cwd=tmp_path)
    says = {"file": "is a regular file", "fifo": "is a FIFO (named pipe)"}[kind]
    assert_one_line(done, f"--out: {target} {says}; expected a folder for the scores and the board")
    if kind == "file":
        assert target.read_text() == "a file the user keeps\n"


def test_leaderboard_replaces_existing_scores_only_with_force(tmp_path):
    out = tmp_path / "board"
    (out / "scores").mkdir(parents=True)
    kept = out / "scores" / "dlqr+kalman.json"
    kept.write_text('{"kept": true}\n')
    done = run_script("leaderboard", "--out", str(out), cwd=tmp_path)
    assert_one_line(done, f"--out: {out} already holds 1 of these files (e.g. "
                          "scores/dlqr+kalman.json); pass --force to replace them")
    assert kept.read_text() == '{"kept": true}\n'


@pytest.mark.parametrize(("stem", "args", "module", "says"), [
    ("env_benchmark", [], "imageio", "gymnasium's InvertedPendulum-v5 (the env compared with) "
                                     "needs imageio, which is not installed"),
    ("executor_benchmark", [], "ray", "the Ray executor needs ray, which is not installed"),
    ("leaderboard", ["--rl"], "stable_baselines3", "--rl (the RL models) needs "
                                                   "stable_baselines3, which is not installed"),
], ids=["imageio", "ray", "rl"])
def test_benchmark_script_missing_extra_named_in_one_line(tmp_path, stem, args, module, says):
    done = run_script(stem, *args, cwd=tmp_path, blocked=module)
    assert_one_line(done, says)
    assert "install " in done.stderr
