"""Issue 55: the board reads what ``score`` writes for a matrix plant's suite (item 10), and counts
a method's runs per suite (the small thing of the run count)."""

from __future__ import annotations

import json
from pathlib import Path

from pendulum_lqg.cli import main
from pendulum_lqg.scoreboard.board import make_board
from pendulum_lqg.scoreboard.stats import failure_aware_figures

ROOT = Path(__file__).resolve().parents[2]


def test_item10_board_reads_the_score_files_of_a_matrix_plant_suite(tmp_path, capsys):
    suite = ROOT / "experiments" / "lti" / "two_mass_suite.toml"
    for policy in ("dlqr+luenberger", "dlqr+kalman"):
        assert main(["score", policy, "--suite", str(suite), "--episodes", "4",
                     "--out", str(tmp_path / f"{policy}.json")]) == 0
    capsys.readouterr()
    assert main(["board", str(tmp_path)]) == 0
    out, err = capsys.readouterr()
    assert err == ""
    lines = out.splitlines()
    assert lines[0] == ("| entry | kind | two-mass: success | two-mass: J | two-mass: gap | "
                        "two-mass: score |")
    ref = next(line for line in lines if line.startswith("| `dlqr+kalman` |"))
    assert ref.split(" | ")[2] == "100 %" and ref.split(" | ")[5].startswith("1.00")
    said = next(line for line in lines if line.startswith("| designed on |"))
    assert "the plant played (its LTI file)" in said


def _rows(n, cost):
    return [{"episode": i, "seed": 10 + i, "success": True, "failure_reason": "", "cost": cost}
            for i in range(n)]


def _entry(rows):
    figures = {"success_rate": 1.0, "cost_mean": 1.0}
    return {"applicable": True, "fingerprint": "f" * 64, "episodes": len(rows),
            "success_rate": 1.0, "cost_mean": 1.0, "optimality_gap": None,
            **failure_aware_figures(rows, rows), "rows": rows,
            "reference": {"policy": "dlqr+kalman", **figures},
            "full_state_bound": {"policy": "dlqr+none", **figures}}


def _write(folder, name, seed, suites):
    doc = {"policy": f"m-seed{seed}", "kind": "agent", "score_version": 1, "method": "m",
           "seed": seed, "suites": {s: _entry(_rows(4, 1.0)) for s in suites}}
    (folder / name).write_text(json.dumps(doc), encoding="utf-8")


def test_board_run_count_is_per_suite(tmp_path):
    _write(tmp_path, "a.json", 0, ["lecture", "mismatch"])
    _write(tmp_path, "b.json", 1, ["lecture"])
    _write(tmp_path, "c.json", 2, ["lecture"])
    _write(tmp_path, "d.json", 2, ["mismatch"])       # seed 2's other suite, in a second file
    table = make_board(tmp_path)
    row = next(line for line in table.splitlines() if line.startswith("| `m` |"))
    cells = row.split(" | ")
    assert cells[1] == "3 (0, 1, 2)"
    assert cells[2] == "100 % [100 %, 100 %]"                       # lecture: all three runs
    assert cells[4] == "100 % [100 %, 100 %] (n = 2)"               # mismatch: seeds 0 and 2
    assert "Counted once" not in table
