"""One schema per external format (pendulum_lqg.boundary.schemas): a committed score file reads
back whole, and a damaged one names the file and the key path."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from pendulum_lqg.boundary.schemas import score_file
from pendulum_lqg.errors import ConfigError

SCORES = Path(__file__).resolve().parents[2] / "docs" / "leaderboard" / "scores"


def _committed() -> Path:
    return sorted(SCORES.glob("rl_sysid-lqg-seed0.json"))[0]


def test_a_committed_score_file_reads_back_with_its_figures():
    path = _committed()
    raw = json.loads(path.read_text(encoding="utf-8"))
    read = score_file(path)
    assert read["policy"] == raw["policy"]
    assert set(read["suites"]) == set(raw["suites"])
    lecture = read["suites"]["lecture"]
    assert lecture["episodes"] == raw["suites"]["lecture"]["episodes"]
    assert lecture["score_mean"] == raw["suites"]["lecture"]["score_mean"]


@pytest.mark.parametrize(("damage", "key"), [
    (lambda d: d["suites"]["lecture"].__setitem__("episodes", 0), "suites.lecture.episodes"),
    (lambda d: d["suites"]["lecture"].__setitem__("fingerprint", 7), "suites.lecture.fingerprint"),
    (lambda d: d.__setitem__("policy", ""), "policy"),
    (lambda d: d["suites"]["lecture"]["reference"].pop("success_rate"),
     "suites.lecture.reference.success_rate"),
])
def test_a_damaged_score_file_names_the_file_and_the_key(tmp_path, damage, key):
    data = json.loads(_committed().read_text(encoding="utf-8"))
    damage(data)
    path = tmp_path / "damaged.json"
    path.write_text(json.dumps(data), encoding="utf-8")
    with pytest.raises(ConfigError) as info:
        score_file(path)
    message = str(info.value)
    assert message.startswith(f"board: {path}: {key}: ") and "\n" not in message
