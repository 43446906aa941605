"""Ceilings checked before any work starts (one line, exit 2), a capped thread count, and long runs
that report progress without changing their results."""

from __future__ import annotations

import json
import os

import pytest

from pendulum_lqg.cli import main
from pendulum_lqg.core.loop import Simulator
from pendulum_lqg.core.physics import _cpu_count
from pendulum_lqg.core.scenario import Scenario
from pendulum_lqg.model.plant import load_plant
from pendulum_lqg.util import limits


def _one_line_exit_2(capsys, argv, fragment):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and fragment in err[0], err
    return err[0]


def test_run_episode_ceiling(capsys):
    _one_line_exit_2(capsys, ["run", "--episodes", str(limits.MAX_RUN_EPISODES + 1)],
                     "--episodes: at most 100,000")
    _one_line_exit_2(capsys, ["run", "--episodes", "1001", "--record", "x.rrd"],
                     "--episodes: at most 1,000")


def test_bench_row_ceiling_is_checked_before_anything_is_written(tmp_path, capsys):
    spec = tmp_path / "big.toml"
    spec.write_text('name = "big"\nepisodes = 1000000\n[grid]\nnoise_scale = [0.0, 1.0, 2.0]\n')
    _one_line_exit_2(capsys, ["bench", str(spec), "--out", str(tmp_path / "out")],
                     "episodes × configurations: at most 2,000,000")
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("table,fragment", [
    ("[roa]\nmap_theta = [-1.0, 1.0, 1000]\nmap_theta_dot = [-1.0, 1.0, 1000]",
     "roa.map_theta × map_theta_dot points: at most 40,000"),
    ("[roa]\nmap_theta = [-1.0, 1.0, 2.5]", "whole number"),
    ("[margins]\nn_omega = 1000000000", "margins.n_omega: at most 100,000"),
    ("[margins]\nn_omega = 1e9", "margins.n_omega: expected an integer"),
])
def test_study_sizes_are_bounded(tmp_path, capsys, table, fragment):
    study = "roa" if "[roa]" in table else "margins"
    spec = tmp_path / "s.toml"
    spec.write_text(f'name = "s"\nstudy = "{study}"\nepisodes = 2\n{table}\n')
    _one_line_exit_2(capsys, ["bench", str(spec), "--out", str(tmp_path / "out")], fragment)


def test_thread_count_is_capped_to_the_cores():
    with Simulator(load_plant(), Scenario(), nthread=1000) as sim:
        assert sim.nthread == _cpu_count() <= (os.cpu_count() or 1)


def test_a_long_run_reports_progress_and_batching_changes_nothing(capsys, monkeypatch):
    argv = ["run", "--episodes", "5", "--duration", "0.5", "--json"]
    assert main(argv) == 0
    whole = json.loads(capsys.readouterr().out)
    monkeypatch.setattr(limits, "RUN_BATCH", 2)
    monkeypatch.setattr(limits, "PROGRESS_EVERY_S", 0.0)
    assert main(argv) == 0
    captured = capsys.readouterr()
    assert json.loads(captured.out)["episodes"] == whole["episodes"]
    assert "run: 2/5 episodes" in captured.err and "run: 4/5 episodes" in captured.err


def test_a_huge_grid_is_refused_before_validating_and_a_grid_compiles_its_model_once(
        tmp_path, capsys):
    from pendulum_lqg.bench import experiments, sources

    values = ", ".join(str(i / 1000) for i in range(1000))
    durations = ", ".join(str(1 + i / 1000) for i in range(1000))
    spec = tmp_path / "huge.toml"
    spec.write_text(f'name = "huge"\n[grid]\nnoise_scale = [{values}]\nduration = [{durations}]\n')
    _one_line_exit_2(capsys, ["bench", str(spec)], "grid: at most 100,000 (configurations")
    sources.simulated_plant.cache_clear()
    spec.write_text(f'name = "wide"\n[grid]\nnoise_scale = [{values}]\n')
    loaded = experiments.load_spec(str(spec))
    assert len(loaded.configurations) == 1000
    assert sources.simulated_plant.cache_info().misses == 1      # one compile, not 1000
    assert loaded.with_overrides() is loaded                           # no second validation
