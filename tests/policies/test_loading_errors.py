"""A plug-in cannot fake success or a traceback: whatever its code raises — ``sys.exit`` included —
is one ``PluginError`` line naming it; its optional members are validated; complex forces and a
non-copyable ``independent_rows`` promise are refused."""

from __future__ import annotations

import threading
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import assert_one_line_error, run_cli

from pendulum_lqg.core.physics import thread_count
from pendulum_lqg.core.runner import _shard_copy, run_episodes
from pendulum_lqg.core.scenario import Scenario
from pendulum_lqg.errors import PendulumLQGError, PluginError
from pendulum_lqg.policies.loading import build_policy, source_digest

#: A plug-in that pushes nothing; ``{setup}`` and ``{member}`` are where a case breaks it.
TEMPLATE = '''
import sys
import numpy as np

{setup}

class Zero:
    independent_rows = False

    def reset(self, n):
        self.n = n
        {in_reset}

    def act(self, y):
        {in_act}
        return np.zeros(y.shape[0])

    def select(self, rows):
        {in_select}
        self.n = len(rows)

{member}

def make(ctx):
    {in_factory}
    return Zero()
'''


def _plugin(tmp_path: Path, name: str = "plug", **parts: str) -> str:
    fill = {"setup": "", "member": "", "in_reset": "pass", "in_act": "pass", "in_select": "pass",
            "in_factory": "pass", **parts}
    path = tmp_path / f"{name}.py"
    path.write_text(TEMPLATE.format(**fill))
    return f"{path}:make"


def _run(plant, ref: str, episodes=range(3), **scenario) -> list[dict]:
    sc = Scenario(duration=scenario.pop("duration", 0.2), **scenario)
    policy = build_policy(ref, plant=plant, scenario=sc)
    return run_episodes(plant, sc, policy, seed=0, episodes=episodes, nthread=1).rows


def _one_line(err: pytest.ExceptionInfo, *fragments: str) -> str:
    text = str(err.value)
    assert "\n" not in text and text.startswith("policy "), text
    for fragment in fragments:
        assert fragment in text, text
    return text


# ---- every BaseException but a Ctrl-C ------------------------------------------------------------
_EXITS = {"SystemExit(0)": ("sys.exit(0)", "SystemExit: 0"),
          "SystemExit(3)": ("sys.exit(3)", "SystemExit: 3"),
          "a BaseException": ("raise BaseException('odd')", "BaseException: odd"),
          "GeneratorExit": ("raise GeneratorExit", "GeneratorExit")}
_PLACES = {"import": ("setup", "importing"), "factory": ("in_factory", "the factory raised"),
           "reset": ("in_reset", "reset raised"), "act": ("in_act", "act raised")}


@pytest.mark.parametrize("exit_kind", list(_EXITS))
@pytest.mark.parametrize("place", list(_PLACES))
def test_sys_exit_and_other_base_exceptions_become_one_plugin_error(tmp_path, plant, place,
                                                                    exit_kind):
    code, shown = _EXITS[exit_kind]
    slot, what = _PLACES[place]
    ref = _plugin(tmp_path, **{slot: code})
    with pytest.raises(PluginError) as err:
        _run(plant, ref)
    _one_line(err, what, shown, ref)


def test_select_and_attribute_access_that_exit_are_plugin_errors(tmp_path, plant):
    ref = _plugin(tmp_path, in_select="sys.exit(0)")
    with pytest.raises(PluginError) as err:          # episodes end at different periods
        _run(plant, ref, episodes=range(2), x0=(0.0, 0.45, 0.0, 0.0), duration=1.0,
             x0_std=(0.0, 0.05, 0.0, 0.0))
    _one_line(err, "select raised SystemExit: 0")
    # a module __getattr__ that exits when the factory is looked up
    path = tmp_path / "lookup.py"
    path.write_text("import sys\ndef __getattr__(name):\n    sys.exit(0)\n")
    with pytest.raises(PluginError) as err:
        _run(plant, f"{path}:make")
    _one_line(err, "reading make raised SystemExit: 0")
    # an object whose every optional member exits when read
    ref = _plugin(tmp_path, "members", member=(
        "class Exits(Zero):\n    def __getattr__(self, name):\n        sys.exit(0)\n"),
        in_factory="return Exits()")
    with pytest.raises(PluginError) as err:
        _run(plant, ref)
    _one_line(err, "reading needs_state raised SystemExit: 0")


def test_a_ctrl_c_in_plugin_code_still_stops_the_run(tmp_path, plant):
    ref = _plugin(tmp_path, in_act="raise KeyboardInterrupt")
    with pytest.raises(KeyboardInterrupt):
        _run(plant, ref)


def test_cli_run_exits_2_with_one_line_when_a_plugin_calls_sys_exit_0(tmp_path, capsys):
    for slot in ("setup", "in_factory", "in_act"):
        ref = _plugin(tmp_path, f"exit_{slot}", **{slot: "sys.exit(0)"})
        status, err = run_cli(capsys, ["run", "--policy", ref, "--episodes", "2",
                                       "--duration", "0.2"])
        assert_one_line_error(status, err, f"policy {ref!r}")
        assert "SystemExit: 0" in err


def test_bench_exits_2_and_keeps_the_units_written_when_a_plugin_exits(tmp_path, capsys):
    ref = _plugin(tmp_path, in_act="sys.exit(3)")
    toml = tmp_path / "mixed.toml"
    toml.write_text(f'name = "mixed"\nepisodes = 2\n[scenario]\nduration = 0.2\n'
                    f'[grid]\npolicy = ["dlqr+kalman", "{ref}"]\n')
    out = tmp_path / "out"
    status, err = run_cli(capsys, ["bench", str(toml), "--out", str(out), "--quiet"])
    assert_one_line_error(status, err, "policy ")
    assert "act raised SystemExit: 3" in err
    assert [p.name for p in (out / "units").glob("*.csv")] == ["c000_e000000-000002.csv"]


# ---- forces and the command line -----------------------------------------------------------------
def test_complex_forces_are_refused_on_both_paths(tmp_path, plant):
    ref = _plugin(tmp_path, in_act="return np.zeros(y.shape[0]) + 1j")
    with pytest.raises(PluginError) as err:
        _run(plant, ref)
    _one_line(err, "act returned complex forces", "expected real forces")

    class NoSelect:                  # a policy of the protocol, outside the plug-in adapter
        def reset(self, n):
            pass

        def act(self, y):
            return np.zeros(y.shape[0], dtype=complex) + 0.5j

    sc = Scenario(duration=0.2)
    with pytest.raises(PendulumLQGError, match=r"^u: expected real forces \[N\], got complex"):
        run_episodes(plant, sc, NoSelect(), seed=0, episodes=range(2), nthread=1)


def test_an_empty_policy_name_is_refused(capsys):
    status, err = run_cli(capsys, ["run", "--policy", "", "--episodes", "1"])
    assert_one_line_error(status, err, "policy: expected 'controller+observer'")
    assert "got ''" in err


# ---- the optional members, validated -------------------------------------------------------------
@pytest.mark.parametrize(("member", "message"), [
    ("needs_state = 'yes'", "needs_state must be True or False, got 'yes'"),
    ("@property\n    def needs_state(self):\n        raise RuntimeError('no')",
     "reading needs_state raised RuntimeError: no"),
    ("info = 5", "info must be a dict of design data (gains, poles), got int"),
    ("info = {1: 2}", "info must have string keys"),
    ("select = 3", "select must be a method select(rows), got int"),
    ("independent_rows = 'yes'", "independent_rows must be True or False, got 'yes'"),
    ("independent_rows = True\n    def __init__(self):\n        self.lock = threading.Lock()",
     "copy.deepcopy (independent_rows = True promises a working deep copy) raised TypeError"),
    ("x_hat = 'garbage'", "x_hat returned str; expected an array of shape (3, 4)"),
    ("@property\n    def x_hat(self):\n        return np.zeros((self.n, 3))",
     "x_hat has shape (3, 3); expected (3, 4)"),
    ("@property\n    def x_hat(self):\n        return np.zeros((self.n, 4)) * 1j",
     "x_hat returned complex values"),
    ("@property\n    def x_hat(self):\n        raise ValueError('stale')",
     "reading x_hat raised ValueError: stale"),
    ("estimator = 3", "estimator must be an object with x_prior, innovation and P (what "
     "recordings log), got int"),
])
def test_optional_members_that_raise_or_hold_garbage_are_one_line_errors(tmp_path, plant, member,
                                                                         message):
    ref = _plugin(tmp_path, setup="import threading", member=(
        f"class Odd(Zero):\n    {member}\n"), in_factory="return Odd()")
    with pytest.raises(PluginError) as err:
        _run(plant, ref)
    _one_line(err, message, ref)


def test_an_estimator_is_recorded_when_well_formed_and_refused_when_not(tmp_path, plant):
    good = ("class Est:\n    def __init__(self, n):\n        self.x_prior = np.ones((n, 4))\n"
            "        self.innovation = np.zeros((n, 2))\n        self.P = np.eye(4)\n"
            "class WithEst(Zero):\n    def act(self, y):\n        self.estimator = Est(y.shape[0])\n"
            "        return np.zeros(y.shape[0])\n    estimator = Est(3)\n")
    ref = _plugin(tmp_path, "good", member=good, in_factory="return WithEst()")
    sc = Scenario(duration=0.05)
    policy = build_policy(ref, plant=plant, scenario=sc)
    res = run_episodes(plant, sc, policy, seed=0, episodes=range(3), nthread=1, trajectory=True)
    tr = res.trajectories[0]
    assert np.all(tr.x_prior == 1.0) and np.all(tr.innovation == 0.0)
    assert tr.P.shape == (5, 4, 4) and np.all(tr.P == np.eye(4))
    bad = good.replace("self.P = np.eye(4)", "self.P = np.eye(3)")
    ref = _plugin(tmp_path, "bad", member=bad, in_factory="return WithEst()")
    policy = build_policy(ref, plant=plant, scenario=sc)
    with pytest.raises(PluginError) as err:
        run_episodes(plant, sc, policy, seed=0, episodes=range(3), nthread=1, trajectory=True)
    _one_line(err, "estimator.P has shape (3, 3); expected (3, 4, 4)")


def test_a_policy_that_promises_copies_it_cannot_make_is_one_line_not_a_traceback(plant):
    class Locked:                    # a policy of the protocol, outside the plug-in adapter
        independent_rows = True

        def __init__(self):
            self.lock = threading.Lock()

        def reset(self, n):
            pass

        def act(self, y):
            return np.zeros(y.shape[0])

    with pytest.raises(PendulumLQGError, match=r"^policy: independent_rows = True promises") as e:
        _shard_copy(Locked())
    assert "cannot pickle '_thread.lock' object" in str(e.value) and "\n" not in str(e.value)
    if thread_count(2) >= 2:         # the runner makes the copies before any shard starts
        t = time.perf_counter()
        with pytest.raises(PendulumLQGError, match=r"^policy: independent_rows"):
            run_episodes(plant, Scenario(duration=60.0), Locked(), seed=0, episodes=range(64),
                         nthread=2)
        assert time.perf_counter() - t < 5.0


# ---- the source an experiment's fingerprint includes ---------------------------------------------
def test_source_digest_follows_the_file_the_module_and_the_package(tmp_path, monkeypatch):
    ref = _plugin(tmp_path)
    before = source_digest(ref)
    assert source_digest(ref) == before and len(before) == 64
    path = Path(ref.rpartition(":")[0])
    path.write_text(path.read_text() + "\n# an edit\n")
    assert source_digest(ref) != before
    # a module on sys.path, and a package (every .py file of it)
    (tmp_path / "pkg").mkdir()
    (tmp_path / "pkg" / "__init__.py").write_text("from pkg.ctrl import make\n")
    (tmp_path / "pkg" / "ctrl.py").write_text(path.read_text())
    monkeypatch.syspath_prepend(str(tmp_path))
    one = source_digest("plug:make"), source_digest("pkg:make"), source_digest("pkg.ctrl:make")
    (tmp_path / "pkg" / "ctrl.py").write_text(path.read_text() + "# another edit\n")
    two = source_digest("plug:make"), source_digest("pkg:make"), source_digest("pkg.ctrl:make")
    assert one[0] == two[0] and one[1] != two[1] and one[2] != two[2]
    with pytest.raises(PluginError, match="cannot import module 'no_such_module'"):
        source_digest("no_such_module:make")


def test_an_edited_plugin_file_is_imported_afresh_in_the_same_process(tmp_path, plant):
    ref = _plugin(tmp_path, in_act="return np.full(y.shape[0], 1.0)")
    first = _run(plant, ref, episodes=range(1))
    _plugin(tmp_path, in_act="return np.full(y.shape[0], 2.0)")
    second = _run(plant, ref, episodes=range(1))
    assert first[0]["rms_u"] == 1.0 and second[0]["rms_u"] == 2.0
