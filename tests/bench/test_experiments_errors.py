"""Bad experiment files name the file and the key; wrong types at any level are one-line errors."""

from __future__ import annotations

import json

import pytest
from conftest import assert_one_line_error, run_cli

from pendulum_lqg.errors import ConfigError, PendulumLQGError


@pytest.mark.parametrize(("content", "message"), [
    (b'[design]\nR = "abc"\n', "design.R: expected a finite positive number, got 'abc'"),
    (b"scenario = 5\n", "scenario: expected a table, got int"),
    (b"design = [1, 2]\n", "design: expected a table, got list"),
    (b"[scenario]\nx0 = true\n", "scenario.x0: expected 4 finite numbers, got True"),
    (b"[grid]\ntheta0 = [[1, 'a']]\n", "x0: expected 4 finite numbers"),
    (b"name = 5\n", "name: expected a string, got 5"),
    (b'name = "../elsewhere"\n', "name: expected a plain name"),
    (b'name = "\xff\xfe"\n', "experiment: "),
    (b"episodes = [\n", "experiment: "),
])
def test_bad_experiment_files_name_the_file_and_the_key(tmp_path, capsys, content, message):
    path = tmp_path / "bad.toml"
    path.write_bytes(content)
    status, err = run_cli(capsys, ["bench", str(path), "--out", str(tmp_path / "o")])
    assert_one_line_error(status, err, message)
    assert str(path) in err, err
    assert not (tmp_path / "o").exists()


def test_non_utf8_and_syntax_errors_from_the_python_api(tmp_path):
    from pendulum_lqg.bench.experiments import load_spec

    path = tmp_path / "latin1.toml"
    path.write_bytes('description = "Größe"\n'.encode("latin-1"))
    with pytest.raises(ConfigError, match=r"^experiment: .*latin1.toml is not UTF-8 text"):
        load_spec(str(path))
    path.write_text("[grid\n")
    with pytest.raises(ConfigError, match=r"^experiment: .*latin1.toml is not valid TOML"):
        load_spec(str(path))


_WRONG_TYPES = ("abc", True, [1, "a"], {"a": 1}, [[1.0]], 5)


def test_wrong_types_at_any_level_raise_one_line_config_errors():
    from pendulum_lqg.bench import experiments as ex

    tables = {"scenario": ex.SCENARIO_KEYS, "noise": ex.NOISE_KEYS, "design": ex.DESIGN_KEYS,
              "model": ex.MODEL_KEYS}
    cases = [{key: v} for key in ex.TOP_KEYS for v in _WRONG_TYPES]
    cases += [{t: {k: v}} for t, keys in tables.items() for k in keys for v in _WRONG_TYPES]
    for key in ex.GRID_KEYS:
        for v in _WRONG_TYPES:
            extra = {"delay": {"delay_kind": ["measurement"]},
                     "delay_kind": {"delay": [0.01]}}.get(key, {})
            cases += [{"grid": {key: [v], **extra}}, {"grid": {key: v, **extra}}]
    refused = 0
    for case in cases:
        try:
            ex.parse_spec(case)
        except PendulumLQGError as exc:
            assert "\n" not in str(exc), (case, str(exc))
            refused += 1
        except Exception as exc:
            pytest.fail(f"{case!r} raised {type(exc).__name__}: {exc}")
    assert refused >= 0.8 * len(cases), (refused, len(cases))


# ---- 4. models -----------------------------------------------------------------------------------


# ---- 5. messages that lost their key or their file -------------------------------------------------
@pytest.mark.parametrize(("content", "message"), [
    (b'[noise]\nmeasurement_variance = [0, 0]\n[grid]\npolicy = ["dlqr+luenberger", '
     b'"dlqr+kalman"]\n', "noise.measurement_variance (V): must be positive definite; smallest "
     "eigenvalue 0 (grid point policy='dlqr+kalman')"),
    (b"episodes = 100000000000000000\n", "episodes × configurations: at most 2,000,000 (the "
     "summary holds every row of the experiment in memory), got 100,000,000,000,000,000"),
])
def test_design_and_size_errors_name_the_key_and_the_file_before_any_unit_runs(
        tmp_path, capsys, content, message):
    path = tmp_path / "named.toml"
    path.write_bytes(content)
    status, err = run_cli(capsys, ["bench", str(path), "--out", str(tmp_path / "o")])
    assert_one_line_error(status, err, message)
    assert err.strip().endswith(f"(in {path})"), err
    assert not (tmp_path / "o").exists()                 # not even the luenberger unit


def test_a_file_too_large_for_the_ceiling_runs_with_fewer_episodes_from_the_command_line(
        tmp_path, capsys):
    path = tmp_path / "big.toml"
    path.write_text('name = "big"\nepisodes = 10000000\n[scenario]\nduration = 0.1\n')
    status, _ = run_cli(capsys, ["bench", str(path), "--episodes", "2", "--quiet",
                                 "--out", str(tmp_path / "o")])
    assert status == 0
    assert json.loads((tmp_path / "o" / "summary.json").read_text())[
        "episodes_per_config"] == 2
