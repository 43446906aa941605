"""benchmarks/noise_ladder.py without the rl extra: the reference scored at each noise scale is
what ``score --noise-scale`` writes, and the figure's table is the median and quartiles of the runs
in each group."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from conftest import load_benchmark_script

from pendulum_lqg.cli import main

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def ladder():
    return load_benchmark_script("noise_ladder", "noise_ladder")


def test_the_ladder_scores_are_the_score_commands_files_and_make_a_table(ladder, tmp_path,
                                                                          capsys):
    folder = tmp_path / "ladder"
    assert ladder.main(["score", "--scales", "0", "1", "--episodes", "3",
                        "--scores", str(folder)]) == 0
    assert sorted(p.name for p in folder.iterdir()) == ["reference-at0.json", "reference-at1.json"]
    assert main(["score", "dlqr+kalman", "--suite", "lecture", "--episodes", "3",
                 "--noise-scale", "0", "--out", str(tmp_path / "cli.json")]) == 0
    assert (folder / "reference-at0.json").read_bytes() == (tmp_path / "cli.json").read_bytes()
    # two runs of a method trained at the suite's noise, three of one trained on the ladder
    base = json.loads((folder / "reference-at1.json").read_text())
    for k, (success, score) in enumerate([(0.2, 0.1), (0.6, 0.5)]):
        doc = {**base, "policy": f"sb3:m{k}.zip", "kind": "agent", "method": "ppo-history",
               "seed": k}
        doc["suites"]["lecture"].update(success_rate=success, score_mean=score)
        (folder / f"m{k}-at1.json").write_text(json.dumps(doc))
    for k, success in enumerate([0.1, 0.3, 0.9]):
        doc = {**base, "policy": f"sb3:n{k}.zip", "kind": "agent",
               "method": "ppo-history-noise1", "seed": k}
        doc["suites"]["lecture"].update(success_rate=success, score_mean=success / 2)
        (folder / f"n{k}-at1.json").write_text(json.dumps(doc))
    table = ladder.ladder_table(folder, "lecture")
    assert sorted(table) == ["LQG reference (dlqr+kalman)",
                             "ppo-history (trained at the scored noise)",
                             "ppo-history (trained at the suite's noise)"]
    assert sorted(table["LQG reference (dlqr+kalman)"]) == [0.0, 1.0]
    text = ladder.markdown(table, "lecture")
    row = next(line for line in text.splitlines() if "suite's noise" in line)
    assert row.endswith("| 2 |  | 40 % [30, 50], 0.30 [0.20, 0.40] |")    # median, quartiles
    row = next(line for line in text.splitlines() if "scored noise" in line)
    assert row.endswith("| 3 |  | 30 % [20, 60], 0.15 [0.10, 0.30] |")
    capsys.readouterr()
    assert ladder.main(["figure", "--scores", str(folder),
                        "--figure", str(tmp_path / "fig" / "ladder.png")]) == 0
    assert (tmp_path / "fig" / "ladder.png").stat().st_size > 10_000
    assert (tmp_path / "fig" / "ladder.md").read_text() == text
