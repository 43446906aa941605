"""The file boundary (pendulum_lqg.boundary): only regular files, a size and a nesting ceiling, one
line naming the file for anything else."""

from __future__ import annotations

import json
import os

import pytest

from pendulum_lqg.boundary import check_nesting, read_json, read_text, read_toml
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.util.limits import MAX_NESTING


def test_a_regular_file_is_read_as_written(tmp_path):
    (tmp_path / "a.toml").write_text('name = "x"\n[t]\nv = [1, 2.5]\n', encoding="utf-8")
    (tmp_path / "a.json").write_text(json.dumps({"k": [1, {"m": None}]}), encoding="utf-8")
    assert read_toml(tmp_path / "a.toml", where="suite") == {"name": "x", "t": {"v": [1, 2.5]}}
    assert read_json(tmp_path / "a.json", where="board") == {"k": [1, {"m": None}]}


def test_a_folder_a_fifo_and_a_missing_file_are_one_line_naming_the_reader(tmp_path):
    os.mkfifo(tmp_path / "fifo")
    for path, what in ((tmp_path, "a folder"), (tmp_path / "fifo", "a FIFO"),
                       (tmp_path / "none.json", "no file")):
        with pytest.raises(ConfigError) as info:
            read_json(path, where="board")
        message = str(info.value)
        assert message.startswith("board: ") and what in message and "\n" not in message


def test_text_that_is_not_utf8_names_the_byte_and_its_offset(tmp_path):
    (tmp_path / "bad.toml").write_bytes(b"name = 'a'\n\xff")
    with pytest.raises(ConfigError, match=r"suite: .*bad.toml is not UTF-8 text: byte 0xff at "
                                          r"offset 11"):
        read_text(tmp_path / "bad.toml", where="suite")


def test_nesting_deeper_than_the_ceiling_is_refused_and_the_ceiling_itself_is_not(tmp_path):
    deep_ok: object = 0
    for _ in range(MAX_NESTING):
        deep_ok = [deep_ok]
    check_nesting(deep_ok, where="board", path="x.json")          # exactly the ceiling
    with pytest.raises(ConfigError, match=f"nested deeper than {MAX_NESTING} levels"):
        check_nesting([deep_ok], where="board", path="x.json")
    (tmp_path / "deep.json").write_text("[" * (MAX_NESTING + 1) + "]" * (MAX_NESTING + 1))
    with pytest.raises(ConfigError, match=r"board: .*deep\.json is nested deeper"):
        read_json(tmp_path / "deep.json", where="board")
