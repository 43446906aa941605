"""Issue 37's attack on the new surfaces — ``score``, ``board``, ``--agent``, ``sb3:`` and suite
files — one test per item, named after it (docs/reliability.md lists the lines they print).

Every bad input is one line ``error: …`` with exit status 2 (Ctrl-C: exit 130), nothing written,
nothing replaced that was not ours.
"""

from __future__ import annotations

import json
import os
import signal
import stat
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from conftest import assert_one_line_error, interruptible_cli, run_cli

from pendulum_lqg.errors import ConfigError

LECTURE = ["--suite", "lecture", "--episodes", "1"]


def _no_scoring(monkeypatch):
    """Scoring would fail the test: the check must come before any work."""
    import pendulum_lqg.scoreboard.score as score

    def refuse(*args, **kwargs):
        raise AssertionError("scoring started")
    monkeypatch.setattr(score, "score_entry", refuse)


def _agent(tmp_path: Path, body: str, name: str = "agent.py") -> str:
    """An agent file whose ``make(env)`` is ``body`` (indented inside the module)."""
    (tmp_path / name).write_text("import sys, time\nimport numpy as np\n\n"
                                 + textwrap.dedent(body))
    return f"{tmp_path / name}:make"


# ---- 1: outputs only replace regular files -----------------------------------------------------
def _special(tmp_path: Path, kind: str) -> Path:
    target = tmp_path / f"target-{kind}"
    if kind == "fifo":
        os.mkfifo(target)
    elif kind == "char device":
        if os.geteuid() != 0:
            pytest.skip("mknod of a character device needs root")
        os.mknod(target, stat.S_IFCHR | 0o666, os.makedev(1, 3))     # what /dev/null is
    else:
        target.mkdir()
    return target


@pytest.mark.parametrize("kind", ["fifo", "char device", "folder"])
@pytest.mark.parametrize("command", ["score", "board"])
def test_item01_out_on_a_fifo_a_device_or_a_folder_is_refused_before_any_work(
        tmp_path, capsys, monkeypatch, kind, command):
    target = _special(tmp_path, kind)
    before = os.stat(target)
    _no_scoring(monkeypatch)
    argv = (["score", "dlqr+kalman", *LECTURE] if command == "score"
            else ["board", str(tmp_path / "no-such-folder")])
    status, err = run_cli(capsys, [*argv, "--out", str(target)])
    assert_one_line_error(status, err, "--out")
    assert kind.split()[0] in err and "expected a regular" in err
    after = os.stat(target)
    assert (after.st_mode, after.st_ino, after.st_rdev) == (before.st_mode, before.st_ino,
                                                           before.st_rdev)


def test_item01_run_record_on_a_fifo_is_refused_before_any_episode(tmp_path, capsys):
    target = _special(tmp_path, "fifo")
    status, err = run_cli(capsys, ["run", "--episodes", "1", "--duration", "0.1",
                                   "--record", str(target)])
    assert_one_line_error(status, err, "--record")
    assert stat.S_ISFIFO(os.stat(target).st_mode)


def test_item01_a_parent_that_cannot_be_a_folder_is_refused_before_scoring(tmp_path, capsys,
                                                                            monkeypatch):
    _no_scoring(monkeypatch)
    (tmp_path / "file").write_text("x")
    status, err = run_cli(capsys, ["score", "dlqr+kalman", *LECTURE,
                                   "--out", str(tmp_path / "file" / "sub" / "score.json")])
    assert_one_line_error(status, err, "--out: cannot ")
    assert "Not a directory" in err and (tmp_path / "file").read_text() == "x"


# ---- 2: ceilings before allocation ---------------------------------------------------------------
def test_item02_score_episodes_beyond_the_ceiling_exits_2_before_any_allocation(
        tmp_path, capsys, monkeypatch):
    _no_scoring(monkeypatch)
    status, err = run_cli(capsys, ["score", "dlqr+kalman", "--suite", "lecture",
                                   "--episodes", str(10**12)])
    assert_one_line_error(status, err, "suite 'lecture': episodes: at most 100,000")
    assert "1,000,000,000,000" in err
    suite = tmp_path / "big.toml"
    suite.write_text('name = "big"\nversion = 1\npurpose = "p"\nreference = "dlqr+kalman"\n'
                     "episodes = 100000000\nseed = 0\n")
    status, err = run_cli(capsys, ["score", "dlqr+kalman", "--suite", str(suite)])
    assert_one_line_error(status, err, f"{suite}: episodes: at most 100,000")


# ---- 3, 4: agents guarded like plug-ins ------------------------------------------------------------
_SITES = {
    "factory": "def make(env):\n    {code}\n",
    "reset": ("class A:\n    def reset(self):\n        {code}\n    def act(self, obs):\n"
              "        return np.zeros(1)\n\ndef make(env):\n    return A()\n"),
    "act": ("class A:\n    def reset(self):\n        pass\n    def act(self, obs):\n        {code}\n\n"
            "def make(env):\n    return A()\n"),
}
_WHAT = {"factory": "the factory", "reset": "reset", "act": "act"}


@pytest.mark.parametrize("code", [0, 3])
@pytest.mark.parametrize("site", list(_SITES))
def test_item03_an_agent_calling_sys_exit_exits_2_with_one_line(tmp_path, capsys, site, code):
    ref = _agent(tmp_path, _SITES[site].format(code=f"sys.exit({code})"))
    out = tmp_path / "score.json"
    status, err = run_cli(capsys, ["score", "--agent", ref, *LECTURE, "--out", str(out)])
    assert_one_line_error(status, err, f"agent '{ref}': {_WHAT[site]} raised SystemExit: {code}")
    assert not out.exists() and os.listdir(tmp_path) == ["agent.py"]


@pytest.mark.parametrize("body, what", [
    (_SITES["reset"].format(code="raise RuntimeError('boom')"), "reset raised RuntimeError: boom"),
    ("class A:\n    def __getattr__(self, name):\n        raise ValueError(name)\n\n"
     "def make(env):\n    return A()\n", "reading reset raised ValueError: reset"),
    ("class A:\n    @property\n    def act(self):\n        raise KeyError('act')\n"
     "    def reset(self):\n        pass\n\ndef make(env):\n    return A()\n",
     "reading act raised KeyError: 'act'"),
    ("def make(env):\n    return 1\n\nmake.normalize_action = property(lambda s: 1)\n"
     "class F:\n    def __call__(self, env):\n        return 1\n"
     "    @property\n    def normalize_action(self):\n        raise OSError('no')\n"
     "make = F()\n", "reading normalize_action raised OSError: no"),
])
def test_item04_an_agent_whose_reset_getattr_or_property_raises_gives_one_line(
        tmp_path, capsys, body, what):
    ref = _agent(tmp_path, body)
    status, err = run_cli(capsys, ["score", "--agent", ref, *LECTURE])
    assert_one_line_error(status, err, f"agent '{ref}': {what}")


# ---- 5: board on damaged score files -------------------------------------------------------------
def _entry(fingerprint="f" * 64):
    figures = {"success_rate": 1.0, "cost_mean": 2.0}
    return {"applicable": True, "fingerprint": fingerprint, "episodes": 4, "success_rate": 0.75,
            "cost_mean": 2.5, "optimality_gap": 0.25, "gap_ci": [0.1, 0.4],
            "score_mean": 0.7, "score_ci": [0.5, 0.9],
            "reference": {"policy": "dlqr+kalman", **figures},
            "full_state_bound": {"policy": "dlqr+none", **figures}}


def _score(policy="mine"):
    return {"policy": policy, "kind": "plugin", "score_version": 1, "suites": {"lecture": _entry()}}


def _deep(n):
    return "[" * n + "]" * n


_DAMAGE = {
    "fingerprint missing": (lambda d: d["suites"]["lecture"].pop("fingerprint"),
                            "suites.lecture.fingerprint: missing"),
    "designed_on unknown": (
        lambda d: d["suites"]["lecture"].__setitem__("designed_on", "the true plant"),
        "suites.lecture.designed_on: expected one of plant played, nominal MJCF, "
        "nominal MJCF + model_overrides"),
    "gap_ci not a pair": (lambda d: d["suites"]["lecture"].__setitem__("gap_ci", 3),
                          "suites.lecture.gap_ci: expected a list of 2"),
    "reference a string": (lambda d: d["suites"]["lecture"].__setitem__("reference", "x"),
                           "suites.lecture.reference: expected a table"),
    "success rate nan": (lambda d: d["suites"]["lecture"].__setitem__("success_rate", float("nan")),
                         "suites.lecture.success_rate: expected a finite number in [0, 1]"),
    "cost an integer beyond floats": (
        lambda d: d["suites"]["lecture"].__setitem__("cost_mean", 10**400),
        "suites.lecture.cost_mean: expected a finite number or null"),
    "suites a list": (lambda d: d.__setitem__("suites", []), "suites: expected a table"),
    "entry null": (lambda d: d["suites"].__setitem__("lecture", None),
                   "suites.lecture: expected a table"),
    "episodes a bool": (lambda d: d["suites"]["lecture"].__setitem__("episodes", True),
                        "suites.lecture.episodes: expected a positive integer"),
    "policy a list": (lambda d: d.__setitem__("policy", ["x"]), "policy: expected a non-empty"),
    "version 2": (lambda d: d.__setitem__("score_version", 2), "score_version: expected 1"),
}


@pytest.mark.parametrize("damage", [*_DAMAGE, "nested 200 000 deep", "not JSON", "not UTF-8",
                                    "a FIFO", "a folder"])
def test_item05_board_skips_a_damaged_score_file_naming_it_and_the_key(tmp_path, capsys, damage):
    scores = tmp_path / "scores"
    scores.mkdir()
    (scores / "good.json").write_text(json.dumps(_score("good")))
    bad = scores / "bad.json"
    if damage in _DAMAGE:
        data = _score("bad")
        _DAMAGE[damage][0](data)
        bad.write_text(json.dumps(data))
        reason = _DAMAGE[damage][1]
    elif damage == "nested 200 000 deep":
        bad.write_text(_deep(200_000))
        reason = "nested deeper than 64 levels"
    elif damage == "not JSON":
        bad.write_text("{")
        reason = "is not valid JSON"
    elif damage == "not UTF-8":
        bad.write_bytes(b'{"policy": "\xff"}')
        reason = "is not UTF-8 text"
    elif damage == "a FIFO":
        os.mkfifo(bad)
        reason = "is a FIFO (named pipe); expected a regular file"
    else:
        bad.mkdir()
        reason = "is a folder; expected a regular file"
    status, err = run_cli(capsys, ["board", str(scores), "--out", str(tmp_path / "board.md")])
    assert status == 0, err
    assert err.strip().splitlines() == [err.strip()] and "Traceback" not in err
    assert err.startswith("board: skipped bad.json: ") and reason in err, err
    table = (tmp_path / "board.md").read_text()
    assert "`good`" in table and "`bad`" not in table
    assert "Skipped (damaged score files): bad.json: " in table


def test_item05_a_board_of_damaged_files_only_is_refused_in_one_line(tmp_path, capsys):
    (tmp_path / "bad.json").write_text(_deep(200_000))
    status, err = run_cli(capsys, ["board", str(tmp_path)])
    assert_one_line_error(status, err, f"board: {tmp_path} holds no readable score file")
    assert "skipped bad.json" in err


def test_item05_a_cell_cannot_break_the_table(tmp_path):
    from pendulum_lqg.scoreboard.board import make_board

    (tmp_path / "a.json").write_text(json.dumps(_score("a | b\nc")))
    row = next(line for line in make_board(tmp_path).splitlines() if line.startswith("| `a"))
    assert row.startswith(r"| `a \| b c` | plugin |")


# ---- 6: damaged sb3 training records ---------------------------------------------------------------
@pytest.mark.parametrize("record, line", [
    ({"algo": ["PPO"]}, "algo: expected one of PPO"),
    ({"algo": "PPO", "env": []}, "env: expected a table"),
    ({"algo": "PPO", "env": None}, "env: expected a table"),
    ({"algo": "PPO", "env": {"observation_mode": 3}}, "env.observation_mode: expected one of"),
    ({"algo": "PPO", "frame_stack": 10**12}, "frame_stack: at most 10,000"),
    ({"algo": "PPO", "obs_norm": {"mean": "x", "var": [1]}}, "obs_norm.mean: expected a list"),
    ({"algo": "PPO", "normalize_action": "yes"}, "normalize_action: expected true or false"),
    (None, "nested deeper than 64 levels"),
])
def test_item06_a_damaged_sb3_training_record_is_one_line(tmp_path, capsys, record, line):
    model = tmp_path / "m.zip"
    model.write_bytes(b"PK")
    meta = tmp_path / "m.json"
    meta.write_text(_deep(100_000) if record is None else json.dumps(record))
    status, err = run_cli(capsys, ["score", "--agent", f"sb3:{model}", *LECTURE])
    assert_one_line_error(status, err, "agent: ")
    assert line in err and (str(meta) in err), err


# ---- 7: only regular files are read, and at most the size ceiling ------------------------------------
def test_item07_score_suite_and_board_read_only_regular_files(tmp_path, capsys, monkeypatch):
    fifo = tmp_path / "suite.toml"
    os.mkfifo(fifo)
    status, err = run_cli(capsys, ["score", "dlqr+kalman", "--suite", str(fifo)])
    assert_one_line_error(status, err, f"suite: {fifo} is a FIFO (named pipe); expected a regular")
    status, err = run_cli(capsys, ["score", "dlqr+kalman", "--suite", "/dev/zero"])
    assert_one_line_error(status, err, "suite: /dev/zero is a character device; expected a regular")
    import pendulum_lqg.boundary as boundary

    monkeypatch.setattr(boundary, "MAX_INPUT_BYTES", 100)
    big = tmp_path / "big.toml"
    big.write_text("# " + "x" * 200 + "\n")
    status, err = run_cli(capsys, ["score", "dlqr+kalman", "--suite", str(big)])
    assert_one_line_error(status, err, f"suite: {big} is larger than 100 bytes")


# ---- 8: --out '' ---------------------------------------------------------------------------------
@pytest.mark.parametrize("command", ["score", "board"])
def test_item08_out_empty_is_refused(tmp_path, capsys, monkeypatch, command):
    _no_scoring(monkeypatch)
    argv = ["score", "dlqr+kalman", *LECTURE] if command == "score" else ["board", str(tmp_path)]
    status, err = run_cli(capsys, [*argv, "--out", ""])
    assert_one_line_error(status, err, "--out: expected a ")
    assert err.rstrip().endswith("got ''")


# ---- 9: suite-file errors name the file and the key ----------------------------------------------------
def _suite_file(tmp_path: Path, reference: str = "dlqr+kalman", env: str = "") -> Path:
    path = tmp_path / "my_suite.toml"
    path.write_text(f'name = "mine"\nversion = 1\npurpose = "p"\nreference = "{reference}"\n'
                    f"episodes = 2\nseed = 0\n\n[env]\nduration = 0.2\n{env}")
    return path


@pytest.mark.parametrize("reference, env, line", [
    ("dlqr+kalman+x", "", "{f}: reference: expected a built-in 'controller+observer'"),
    ("dlqr+magic", "", "{f}: reference: expected a built-in 'controller+observer'"),
    ("dlqr+kalman", 'model_path = "{d}/nope.xml"', "{f}: env.model_path: "),
    ("dlqr+kalman", "measurement_variance = [0, 0]",
     "{f}: its reference 'dlqr+kalman': V: must be positive definite"),
])
def test_item09_suite_file_errors_name_the_file_and_the_key_not_the_policy(
        tmp_path, capsys, reference, env, line):
    path = _suite_file(tmp_path, reference, env.format(d=tmp_path))
    status, err = run_cli(capsys, ["score", "dlqr+kalman", "--suite", str(path)])
    assert_one_line_error(status, err, line.format(f=path))
    assert "policy:" not in err


# ---- 10: the render size names the parameter that is too large --------------------------------------
def test_item10_a_render_height_beyond_the_buffer_names_height():
    import gymnasium as gym

    from pendulum_lqg.envs.registration import ENV_ID, register_envs

    register_envs()
    with pytest.raises(ConfigError, match=r"^height: at most \d+ pixels .*got 1000000000$"):
        env = gym.make(ENV_ID, render_mode="rgb_array", height=10**9)
        env.reset(seed=0)
        env.render()


# ---- 11: Ctrl-C is one line and exit 130, nothing half-written -----------------------------------------
def test_item11_ctrl_c_during_score_exits_130_with_one_line_and_no_score_file(tmp_path):
    marker = tmp_path / "acting"
    ref = _agent(tmp_path, f"""\
        class A:
            def reset(self):
                pass
            def act(self, obs):
                open({str(marker)!r}, "w").close()
                time.sleep(3600)

        def make(env):
            return A()
        """)
    out = tmp_path / "out" / "score.json"
    proc = subprocess.Popen(interruptible_cli("score", "--agent", ref, *LECTURE, "--out", out),
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            cwd=tmp_path)
    while not marker.exists() and proc.poll() is None:
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert err.strip().splitlines() == ["interrupted: stopped by Ctrl-C before the command "
                                        "finished"], err
    assert not out.exists() and os.listdir(out.parent) == []


def test_item11_ctrl_c_during_bench_before_its_sweep_is_one_line(capsys, monkeypatch):
    import pendulum_lqg.bench.experiments as experiments

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt
    monkeypatch.setattr(experiments, "load_spec", interrupted)
    status, err = run_cli(capsys, ["bench", "lecture"])
    assert status == 130 and err == "interrupted: stopped by Ctrl-C before the command finished\n"


# ---- 12: the watchdog of user code ------------------------------------------------------------------
def test_item12_an_agent_whose_act_blocks_is_stopped_naming_the_call(tmp_path, capsys):
    ref = _agent(tmp_path, _SITES["act"].format(code="time.sleep(3600)"))
    out = tmp_path / "score.json"
    status, err = run_cli(capsys, ["score", "--agent", ref, *LECTURE, "--call-timeout", "1",
                                   "--out", str(out)])
    assert_one_line_error(status, err, f"agent '{ref}': act has not returned after 1 s "
                                       "(--call-timeout); the run is stopped")
    assert not out.exists()


def test_item12_a_plugin_whose_act_waits_on_a_lock_is_stopped_in_run(tmp_path, capsys):
    (tmp_path / "stuck.py").write_text(textwrap.dedent("""\
        import threading
        import numpy as np

        class P:
            def reset(self, n):
                pass
            def act(self, y):
                threading.Event().wait()
                return np.zeros(y.shape[0])

        def make(ctx):
            return P()
        """))
    ref = f"{tmp_path / 'stuck.py'}:make"
    status, err = run_cli(capsys, ["run", "--policy", ref, "--episodes", "1", "--duration", "0.1",
                                   "--call-timeout", "1"])
    assert_one_line_error(status, err, f"policy '{ref}': act has not returned after 1 s")


@pytest.mark.slow           # waits out the watchdog's 5 s grace; the interruptible case stays quick
def test_item12_a_call_that_cannot_be_interrupted_ends_the_process_with_the_line(tmp_path):
    # SIGALRM blocked inside act: the handler never runs, as in C code that never returns
    ref = _agent(tmp_path, _SITES["act"].format(
        code="import signal; signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGALRM}); "
             "time.sleep(3600)"))
    proc = subprocess.run(interruptible_cli("score", "--agent", ref, *LECTURE,
                                            "--call-timeout", "1"),
                          capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.strip().splitlines() == [
        f"error: agent '{ref}': act has not returned after 1 s (--call-timeout); the run is "
        "stopped (it cannot be interrupted)"]


def test_item12_call_timeout_must_be_a_non_negative_number(capsys):
    status, err = run_cli(capsys, ["score", "dlqr+kalman", "--call-timeout", "-1"])
    assert status == 2 and "error: argument --call-timeout: expected a finite number ≥ 0, " \
        "got '-1'" in err


# ---- 13: nesting ceilings in TOML ----------------------------------------------------------------------
@pytest.mark.parametrize("kind", ["suite", "experiment"])
def test_item13_a_toml_file_nested_5000_deep_is_one_line(tmp_path, capsys, kind):
    path = tmp_path / "deep.toml"
    path.write_text(f"x = {_deep(5000)}\n")
    argv = (["score", "dlqr+kalman", "--suite", str(path)] if kind == "suite"
            else ["bench", str(path), "--out", str(tmp_path / "res")])
    status, err = run_cli(capsys, argv)
    assert_one_line_error(status, err, f"{kind}: {path} is nested deeper than 64 levels")
    path.write_text(f"x = {_deep(100)}\n")          # parsed (under the recursion limit), refused
    status, err = run_cli(capsys, argv)
    assert_one_line_error(status, err, f"{kind}: {path} is nested deeper than 64 levels")


# ---- 14: the results folder's lock ----------------------------------------------------------------------
_HOLD = ("import sys, time; from pathlib import Path; from pendulum_lqg.util.files import FileLock; "
         "lock = FileLock(Path(sys.argv[1]), where='out:'); lock.acquire(); print('held', "
         "flush=True); time.sleep(3600)")


def test_item14_the_results_lock_is_held_by_one_run_and_freed_when_it_dies(tmp_path):
    from pendulum_lqg.util.files import FileLock

    path = tmp_path / ".lock"
    holder = subprocess.Popen([sys.executable, "-c", _HOLD, str(path)], stdout=subprocess.PIPE,
                              text=True)
    try:
        assert holder.stdout.readline() == "held\n"
        for _ in range(2):           # both contenders refused, each naming the holder
            with pytest.raises(ConfigError, match=rf"^out: is being written by another run "
                                                  rf"\(pid {holder.pid}\)$"):
                FileLock(path, where="out:").acquire()
    finally:
        holder.kill()
        holder.wait()
    first, second = FileLock(path, where="out:"), FileLock(path, where="out:")
    first.acquire()                  # the dead holder's lock is free, without any takeover step
    with pytest.raises(ConfigError, match=rf"\(pid {os.getpid()}\)"):
        second.acquire()             # and exactly one of two later runs gets it
    first.release()
    assert not path.exists()
    second.acquire()
    assert path.read_text() == str(os.getpid())
    second.release()


def test_item14_a_lock_removed_by_its_holder_between_open_and_flock_is_not_taken(tmp_path,
                                                                                   monkeypatch):
    import fcntl

    from pendulum_lqg.util.files import FileLock

    path = tmp_path / ".lock"
    real_flock, calls = fcntl.flock, []

    def flock_after_the_holder_left(fd, op):
        real_flock(fd, op)
        if not calls:                # the file this run opened is removed under it, once
            calls.append(fd)
            path.unlink()
    monkeypatch.setattr(fcntl, "flock", flock_after_the_holder_left)
    lock = FileLock(path, where="out:")
    lock.acquire()
    assert len(calls) == 1 and path.exists()     # it locked the new file, not the removed one
    assert os.path.samestat(os.fstat(lock._fd), os.stat(path))
    lock.release()


# ---- 15: progress on stderr only -----------------------------------------------------------------------
def test_item15_the_sweep_progress_bar_writes_to_stderr_never_stdout(capsys):
    from types import SimpleNamespace

    from pendulum_lqg.bench.sweep import _with_progress

    units = [SimpleNamespace(key=f"u{i}", config=SimpleNamespace(label=f"config {i}"), start=0,
                             stop=1) for i in range(3)]
    outcomes = [(u, [{"x": 1}], None) for u in units]
    assert list(_with_progress(iter(outcomes), units, 3, 0, True, None)) == outcomes
    out, err = capsys.readouterr()
    assert out == "" and "3/3" in err


# ---- 16: the atomic write ----------------------------------------------------------------------------
@pytest.mark.parametrize("failure", [OSError(28, "No space left on device"), KeyboardInterrupt()])
@pytest.mark.parametrize("stage", ["fsync", "replace"])
def test_item16_a_failed_atomic_write_leaves_the_old_file_and_no_temporary(tmp_path, monkeypatch,
                                                                           failure, stage):
    import pendulum_lqg.util.files as files

    target = tmp_path / "score.json"
    target.write_text("old\n")

    def fail(*args):
        raise failure
    monkeypatch.setattr(files.os, stage, fail)
    with pytest.raises(type(failure)):
        files.atomic_write(target, "new\n")
    monkeypatch.undo()
    assert target.read_text() == "old\n" and os.listdir(tmp_path) == ["score.json"]


def test_item16_the_atomic_write_fsyncs_the_folder_after_the_rename(tmp_path, monkeypatch):
    import pendulum_lqg.util.files as files

    target = tmp_path / "new.json"
    synced = []
    real = os.fsync

    def fsync(fd):
        synced.append((stat.S_ISDIR(os.fstat(fd).st_mode), target.exists()))
        real(fd)
    monkeypatch.setattr(files.os, "fsync", fsync)
    files.atomic_write(target, "x")
    assert synced == [(False, False), (True, True)]      # the file before, its folder after


# ---- 17: a plug-in runs from exactly the bytes that are fingerprinted ----------------------------------
@pytest.mark.parametrize("write_bytecode", [True, False])
def test_item17_a_plugin_edited_within_the_same_second_runs_its_new_bytes(
        tmp_path, monkeypatch, write_bytecode):
    from pendulum_lqg.policies.loading import load_factory, source_digest

    monkeypatch.setattr(sys, "dont_write_bytecode", not write_bytecode)
    path = tmp_path / "edited.py"
    ref = f"{path}:make"
    stamp = time.time_ns()
    values = []
    for value in ("1.0", "2.0"):         # the same size, the same mtime: a .pyc check passes
        path.write_text(f"def make(ctx):\n    return {value}\n")
        os.utime(path, ns=(stamp, stamp))
        values.append((load_factory(ref)(None), source_digest(ref)))
    assert [v for v, _ in values] == [1.0, 2.0]
    assert values[0][1] != values[1][1]
    assert not (tmp_path / "__pycache__").exists()
