"""LTI plant files through the boundary layer (issue 45): each defect found by the hostile cases
has a test named after it, run through ``load_lti`` and the command line (one line, exit 2)."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest

from pendulum_lqg.cli import main
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.model.lti import MAX_LTI_DIMENSION, load_lti, lti_from_mapping

BASE = {"control_period": 0.01, "A": [[0.0, 1.0], [0.0, 0.0]], "B": [[0.0], [1.0]],
        "C": [[1.0, 0.0]], "W": [1.0, 1.0], "V": [100.0], "R": 1.0}


def write_toml(path: Path, table: dict[str, object]) -> Path:
    """A TOML file of ``table`` (numbers, strings and lists: JSON's spelling is TOML's)."""
    lines = [f"{k} = {v}" if isinstance(v, str) and v.startswith("[") else
             f"{k} = {json.dumps(v)}" for k, v in table.items()]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def refused(path: Path, message: str, capsys: pytest.CaptureFixture[str]) -> None:
    """``load_lti`` raises one ConfigError line matching ``message`` and ``theory --lti`` exits 2
    with that line, no traceback."""
    with pytest.raises(ConfigError, match=message) as exc:
        load_lti(path)
    assert "\n" not in str(exc.value)
    assert main(["theory", "--lti", str(path)]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err


def test_string_in_V_or_R_is_refused(tmp_path, capsys):
    refused(write_toml(tmp_path / "v.toml", {**BASE, "V": ["a"]}),
            r"lti: .*v\.toml: V: expected numbers: .*, got \['a'\]", capsys)
    refused(write_toml(tmp_path / "r.toml", {**BASE, "R": "one"}),
            r"R: expected numbers: .*, got 'one'", capsys)


def test_ragged_W_is_refused(tmp_path, capsys):
    refused(write_toml(tmp_path / "w.toml", {**BASE, "W": [[1.0, 0.0], [1.0]]}),
            r"W: expected numbers: a number, a list or a list of equally long rows", capsys)


def test_states_5_is_refused(tmp_path, capsys):
    refused(write_toml(tmp_path / "s.toml", {**BASE, "states": 5}),
            r"states: expected a list of 2 distinct names .*, got 5", capsys)


@pytest.mark.parametrize("poles, why", [
    ("[[-1, -2]]", r"got \[\[-1, -2\]\]"),
    ('["-1+2j", "-3"]', "not in conjugate pairs"),
    ('["abc", -2]', "got 'abc'"),
    ("[-1]", r"got \[-1\]"),
    (-2, "got -2"),
])
def test_malformed_observer_poles_are_refused(tmp_path, capsys, poles, why):
    refused(write_toml(tmp_path / "p.toml", {**BASE, "observer_poles": poles}),
            f"observer_poles: expected a list of 2 poles .*{why}", capsys)


def test_B_of_empty_rows_is_refused(tmp_path, capsys):
    refused(write_toml(tmp_path / "b.toml", {**BASE, "B": [[], []]}),
            r"B: expected a \(2 × c\) matrix .*, got shape \(2, 0\)", capsys)


def test_5000_deep_nesting_is_refused(tmp_path, capsys):
    path = tmp_path / "deep.toml"
    path.write_text("control_period = 0.01\nA = " + "[" * 5000 + "]" * 5000 + "\n")
    refused(path, "nested deeper than 64 levels", capsys)


def test_garbage_npz_is_refused(tmp_path, capsys):
    path = tmp_path / "garbage.npz"
    path.write_bytes(os.urandom(4096))
    refused(path, r"garbage\.npz: expected an \.npz archive \(numpy\.savez\), got an unreadable",
            capsys)


def test_text_member_npz_is_refused(tmp_path, capsys):
    path = tmp_path / "text.npz"
    np.savez(path, control_period=0.01, A=np.array([["0", "1"], ["0", "0"]]), B=[[0.0], [1.0]])
    refused(path, r"text\.npz: A: expected a numeric array, got dtype <U1", capsys)


def test_npz_member_inflating_beyond_its_ceiling_is_refused_from_its_header(tmp_path, capsys):
    path = tmp_path / "bomb.npz"
    np.savez_compressed(path, control_period=0.01, A=np.zeros((2000, 2000)), B=np.zeros((2, 1)))
    assert path.stat().st_size < 100_000        # 32 MB of zeros once inflated
    refused(path, "A: expected a member of at most 1,048,576 bytes, got 32,000,128", capsys)


def test_1000_states_are_refused_before_any_design(tmp_path, capsys):
    n = 1000
    path = write_toml(tmp_path / "big.toml", {"control_period": 0.01, "A": [[0.0] * n] * n,
                                              "B": [[1.0]] * n})
    refused(path, f"A: expected numbers: .*at most {MAX_LTI_DIMENSION} long.*, got list of 1000 "
                  "items", capsys)


def test_1GB_file_is_refused_unread(tmp_path, capsys):
    path = tmp_path / "huge.toml"
    with open(path, "wb") as f:                  # sparse: no gigabyte is written or read
        f.truncate(2**30)
    refused(path, r"lti: .*huge\.toml is larger than 268,435,456 bytes .*got 1,073,741,824",
            capsys)


def test_duplicate_state_names_are_refused(tmp_path, capsys):
    refused(write_toml(tmp_path / "dup.toml", {**BASE, "states": ["p", "p"]}),
            "states: expected a list of 2 distinct names .*, got 'p' twice", capsys)


@pytest.mark.parametrize("key, value, message", [
    ("states", ["u", "v"], "other than 'u'"),
    ("outputs", ["y1", 5], "identifiers"),
    ("inputs", ["a b"], "identifiers"),
    ("N", [[2.0], [0.0]], r"Q − N R⁻¹ Nᵀ ≥ 0"),
    ("R", [[1.0, 0.0], [0.0, 1.0]], r"R: expected .* \(1 × 1\)"),
    ("force_limit", [1.0, 2.0], "force_limit: expected one or 1 limits"),
    ("x0", [1.0], r"x0: expected a list of 2 numbers, got shape \(1,\)"),
    ("control_period", True, "control_period: expected a finite positive number, got True"),
])
def test_other_bad_values_name_their_key(key, value, message):
    with pytest.raises(ConfigError, match=message):
        lti_from_mapping({**BASE, "Q": [[1.0, 0.0], [0.0, 0.0]], key: value})


def test_an_input_named_as_a_state_is_refused():
    two = {**BASE, "B": [[0.0, 1.0], [1.0, 0.0]], "R": 1.0}
    with pytest.raises(ConfigError, match="inputs: expected names other than the states', got "
                                          "'x1' for both"):
        lti_from_mapping({**two, "inputs": ["x1", "f"]})
    assert lti_from_mapping(two).input_names == ("u1", "u2")


def test_a_fifo_is_refused_without_blocking(tmp_path, capsys):
    path = tmp_path / "fifo.toml"
    os.mkfifo(path)
    refused(path, "is a FIFO", capsys)


def test_npz_names_and_numbers_read_as_the_toml(tmp_path):
    toml = load_lti(write_toml(tmp_path / "di.toml", {**BASE, "states": ["pos", "vel"],
                                                      "observer_poles": ["-2+1j", "-2-1j"]}))
    path = tmp_path / "di.npz"
    np.savez(path, **{k: np.asarray(v) for k, v in BASE.items()}, states=["pos", "vel"],
             observer_poles=["-2+1j", "-2-1j"])
    npz = load_lti(path)
    assert npz.state_names == toml.state_names == ("pos", "vel")
    assert npz.observer_poles == toml.observer_poles == (-2 + 1j, -2 - 1j)
    np.testing.assert_array_equal(npz.Phi, toml.Phi)
