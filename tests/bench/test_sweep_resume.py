"""A resume trusts a unit by its content: an edited plug-in's units are stale, swapped or edited
unit CSVs with a recomputed SHA-256 are caught by their own columns, a corrupt record is
recomputed however deep its JSON nests."""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import pytest

from pendulum_lqg.bench.experiments import load_spec
from pendulum_lqg.cli import main

PLUGIN = '''
import numpy as np

class Gain:
    def __init__(self, K):
        self.K = K

    def reset(self, n):
        pass

    def act(self, y):
        return -(y @ self.K)

def make(ctx):
    return Gain(np.array([{gains}]))
'''
SMALL = """
name = "small"
episodes = 4
seed = 3
chunk = 2
[scenario]
duration = 0.3
[grid]
policy = {policies}
"""


def _setup(tmp_path: Path, policies: str = '["dlqr+kalman", "ctrl.py:make"]',
           gains: str = "1.0, 20.0") -> Path:
    (tmp_path / "ctrl.py").write_text(PLUGIN.format(gains=gains))
    spec = tmp_path / "small.toml"
    spec.write_text(SMALL.format(policies=policies))
    return spec


def _bench(spec: Path, out: Path, *extra: str) -> int:
    """``bench``; quiet unless resuming (a resume reports each unit it recomputes)."""
    quiet = [] if "--resume" in extra else ["--quiet"]
    return main(["bench", str(spec), "--out", str(out), *quiet, *extra])


def _units(out: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted((out / "units").glob("*"))}


# ---- a plug-in edited between two runs -----------------------------------------------------------
def test_the_fingerprint_includes_each_plugins_source(tmp_path):
    spec = _setup(tmp_path)
    before = load_spec(str(spec))
    (tmp_path / "ctrl.py").write_text(PLUGIN.format(gains="1.0, 25.0"))
    after = load_spec(str(spec))
    assert after.fingerprint() != before.fingerprint()
    assert after.definition_fingerprint() == before.definition_fingerprint()
    (tmp_path / "b").mkdir()
    only_builtin = load_spec(str(_setup(tmp_path / "b", policies='["dlqr+kalman"]')))
    assert only_builtin.fingerprint() == only_builtin.definition_fingerprint()


def test_resume_after_editing_a_plugin_recomputes_only_its_units(tmp_path, capsys):
    spec = _setup(tmp_path)
    out = tmp_path / "out"
    assert _bench(spec, out) == 0
    old_units = _units(out)
    # an interrupted sweep: the plug-in's second unit and the summary are missing
    (out / "units" / "c001_e000002-000004.csv").unlink()
    (out / "summary.json").unlink()
    (tmp_path / "ctrl.py").write_text(PLUGIN.format(gains="1.0, 25.0"))     # edited meanwhile
    capsys.readouterr()
    assert _bench(spec, out, "--resume") == 0
    err = capsys.readouterr().err
    assert ("unit c001_e000000-000002: written by another version of the plugin "
            f"{(tmp_path / 'ctrl.py').resolve()}:make (its source changed since); "
            "recomputing it") in err
    now = _units(out)
    for name in ("c000_e000000-000002.csv", "c000_e000002-000004.csv"):
        assert now[name] == old_units[name]              # the built-in's units are kept
    fresh = tmp_path / "fresh"
    assert _bench(spec, fresh) == 0                      # the edited plug-in from scratch
    assert (out / "episodes.csv").read_bytes() == (fresh / "episodes.csv").read_bytes()
    assert (out / "episodes.csv").read_bytes() != b""


def test_resume_after_editing_a_plugin_can_refuse(tmp_path, capsys):
    spec = _setup(tmp_path)
    out = tmp_path / "out"
    assert _bench(spec, out) == 0
    (out / "summary.json").unlink()
    (tmp_path / "ctrl.py").write_text(PLUGIN.format(gains="1.0, 25.0"))
    capsys.readouterr()
    assert _bench(spec, out, "--resume", "--on-mismatch", "refuse") == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(
        "error: --resume: unit c001_e000000-000002 fails its check: written by another version "
        "of the plugin"), err
    assert "(2 unit(s) in all)" in err[0]


def test_a_plugin_edited_while_a_sweep_runs_stops_it_and_resume_completes_it(tmp_path, capsys):
    from pendulum_lqg.bench.executors import LocalExecutor
    from pendulum_lqg.bench.sweep import run_sweep
    from pendulum_lqg.errors import PluginError

    spec = _setup(tmp_path)
    out = tmp_path / "out"

    class EditsMidway(LocalExecutor):
        def run(self, units):
            for i, outcome in enumerate(super().run(units)):
                yield outcome
                if i == 2:                 # the plug-in's first unit is done
                    (tmp_path / "ctrl.py").write_text(PLUGIN.format(gains="1.0, 25.0"))

    with pytest.raises(PluginError, match="its source changed since the experiment was read"):
        run_sweep(load_spec(str(spec)), out, executor=EditsMidway())
    assert len(list((out / "units").glob("*.csv"))) == 3
    capsys.readouterr()
    assert _bench(spec, out, "--resume") == 0
    assert "unit c001_e000000-000002: written by another version" in capsys.readouterr().err
    fresh = tmp_path / "fresh"
    assert _bench(spec, fresh) == 0
    assert (out / "episodes.csv").read_bytes() == (fresh / "episodes.csv").read_bytes()


# ---- units checked by their content --------------------------------------------------------------
def _rehash(out: Path, key: str) -> None:
    """Make the unit's record match its (tampered) CSV again, as a careless tool would."""
    record_path = out / "units" / f"{key}.json"
    record = json.loads(record_path.read_text())
    record["sha256"] = hashlib.sha256((out / "units" / f"{key}.csv").read_bytes()).hexdigest()
    record_path.write_text(json.dumps(record))


def _resume_recomputes(spec: Path, out: Path, capsys, key: str, why: str) -> None:
    full = (out / "episodes.csv").read_bytes()
    (out / "summary.json").unlink()
    capsys.readouterr()
    assert _bench(spec, out, "--resume") == 0
    err = capsys.readouterr().err
    assert f"unit {key}: {why}" in err and "recomputing it" in err, err
    assert (out / "episodes.csv").read_bytes() == full


def test_swapped_unit_csvs_with_recomputed_hashes_are_recomputed(tmp_path, capsys):
    spec = _setup(tmp_path, policies='["dlqr+kalman", "dlqr+luenberger"]')
    out = tmp_path / "out"
    assert _bench(spec, out) == 0
    a, b = out / "units" / "c000_e000000-000002.csv", out / "units" / "c001_e000000-000002.csv"
    ta, tb = a.read_bytes(), b.read_bytes()
    a.write_bytes(tb)
    b.write_bytes(ta)
    _rehash(out, a.stem)
    _rehash(out, b.stem)
    _resume_recomputes(spec, out, capsys, a.stem,
                       "its CSV holds other episodes: row 1 has config '1', expected '0'")


def test_an_edited_episode_column_with_a_recomputed_hash_is_recomputed(tmp_path, capsys):
    spec = _setup(tmp_path, policies='["dlqr+kalman"]')
    out = tmp_path / "out"
    assert _bench(spec, out) == 0
    # the second unit's rows relabelled as the first's, its record rehashed and its range kept
    first, second = (out / "units" / f"c000_e00000{i}-00000{i + 2}.csv" for i in (0, 2))
    second.write_bytes(first.read_bytes())
    _rehash(out, second.stem)
    _resume_recomputes(spec, out, capsys, second.stem,
                       "its CSV holds other episodes: row 1 has episode '0', expected '2'")


@pytest.mark.parametrize(("text", "why"), [
    ("[" * 100_000 + "]" * 100_000,
     "check record corrupt (is nested deeper than 64 levels (the ceiling of tables and lists in a "
     "file))"),
    ("{not json", "check record corrupt (is not valid JSON (Expecting property name enclosed in "
                  "double quotes at line 1, column 2))"),
    ("[1, 2]", "check record corrupt (expected a table (JSON object), got [1, 2])"),
    ('{"fingerprint": 5}', "check record corrupt (fingerprint: expected a non-empty string, got 5)"),
    ("RECORD_WITH_NESTED_COLUMNS",
     "check record corrupt (columns: expected a list whose items are each a string, got "
     "[[['config']], [['config']], [['config']]])"),
])
def test_a_corrupt_check_record_is_recomputed_however_deep_it_nests(tmp_path, capsys, text, why):
    spec = _setup(tmp_path, policies='["dlqr+kalman"]')
    out = tmp_path / "out"
    assert _bench(spec, out) == 0
    record = out / "units" / "c000_e000000-000002.json"
    if text == "RECORD_WITH_NESTED_COLUMNS":
        data = json.loads(record.read_text())
        data["columns"] = [[["config"]]] * 3
        text = json.dumps(data)
    record.write_text(text)
    _resume_recomputes(spec, out, capsys, record.stem, why)
