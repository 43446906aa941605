"""Shipped data: what the wheel carries, and the paths the docs show resolving to the packaged copies
from any folder."""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest
from conftest import assert_one_line_error, run_cli

from pendulum_lqg.bench.experiments import load_spec
from pendulum_lqg.model.lti import load_lti
from pendulum_lqg.policies.loading import resolve_ref
from pendulum_lqg.util.resources import data_dir, find_file

ROOT = Path(__file__).resolve().parents[2]
#: What stays out of the wheel: trained models, their training records and curves, the pilot's runs.
NOT_SHIPPED = ("experiments/agents/models", "experiments/agents/pilot")


def _wheel_selection() -> set[str]:
    """The data files the wheel's ``include`` patterns select (hatch's root-anchored globs)."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["hatch"]["build"]
    wheel = config["targets"]["wheel"]
    assert "force-include" not in wheel          # force-include bypasses every exclusion
    assert wheel["sources"] == {"models": "pendulum_lqg/_data/models",
                                "experiments": "pendulum_lqg/_data/experiments"}
    chosen = {str(p.relative_to(ROOT)) for pattern in wheel["include"]
              if not pattern.startswith("/pendulum_lqg")
              for p in ROOT.glob(pattern.lstrip("/")) if p.is_file()}
    return chosen


def test_the_wheel_ships_the_data_meant_to_be_used_and_no_trained_model():
    data = {str(p.relative_to(ROOT)) for folder in ("models", "experiments")
            for p in (ROOT / folder).rglob("*")
            if p.is_file() and "__pycache__" not in p.parts}
    meant = {f for f in data if not f.startswith(NOT_SHIPPED)}
    assert any(f.startswith(NOT_SHIPPED) for f in data)      # the exclusion has something to do
    assert _wheel_selection() == meant
    for doc_path in ("experiments/plugin_lqg.py", "experiments/plugin_example.py",
                     "experiments/agents/zero_force.py", "experiments/agents/python_control_lqg.py",
                     "experiments/lti/double_integrator.toml", "experiments/suites/lecture.toml",
                     "experiments/lecture.toml", "models/cartpole.xml"):
        assert doc_path in meant


@pytest.fixture
def elsewhere(tmp_path, monkeypatch):
    """A current folder without the repository's files, as for an installed wheel."""
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_the_docs_paths_resolve_to_the_shipped_copies_from_any_folder(elsewhere):
    shipped = data_dir("experiments")
    assert find_file("experiments/plugin_lqg.py") == (shipped / "plugin_lqg.py").resolve()
    assert find_file("plugin_lqg.py") == (shipped / "plugin_lqg.py").resolve()
    assert resolve_ref("experiments/agents/zero_force.py:make") == \
        f"{(shipped / 'agents' / 'zero_force.py').resolve()}:make"
    plant = load_lti("experiments/lti/double_integrator.toml")
    assert plant.name == "double_integrator"
    assert plant.Phi.tolist() == [[1.0, plant.control_period], [0.0, 1.0]]     # ẍ = u, ZOH
    spec = load_spec("experiments/lecture.toml")
    assert spec.name == "lecture" and spec.base_dir == shipped.resolve()
    # not found anywhere: the path the user gave, made absolute, for the caller's error
    assert find_file("experiments/nope.py") == elsewhere.resolve() / "experiments" / "nope.py"


def test_a_local_file_wins_over_the_shipped_copy_and_the_experiment_folder_over_both(elsewhere):
    mine = elsewhere / "experiments" / "plugin_lqg.py"
    mine.parent.mkdir()
    mine.write_text("make = None\n")
    assert find_file("experiments/plugin_lqg.py") == mine.resolve()
    near = elsewhere / "exp"
    (near / "experiments").mkdir(parents=True)
    (near / "experiments" / "plugin_lqg.py").write_text("make = None\n")
    assert find_file("experiments/plugin_lqg.py", near) == \
        (near / "experiments" / "plugin_lqg.py").resolve()
    assert find_file("/abs/x.py", near) == Path("/abs/x.py")


def test_run_with_the_docs_plugin_path_from_another_folder(elsewhere, capsys):
    status, err = run_cli(capsys, ["run", "--policy", "experiments/plugin_lqg.py:make",
                                   "--episodes", "1", "--duration", "1", "--json"])
    assert status == 0, err


def test_a_trained_model_that_is_not_there_says_the_wheel_does_not_ship_them(elsewhere, capsys):
    status, err = run_cli(capsys, ["score", "--agent",
                                   "linear:experiments/agents/models/ars-history-seed0.json",
                                   "--suite", "lecture"])
    assert_one_line_error(status, err, "agent: linear:experiments/agents/models/")
    assert "trained models are not shipped in the wheel" in err
