"""The board page's compact summary is what docs/leaderboard/summary.py makes of the score files."""

from __future__ import annotations

import importlib.util
from pathlib import Path

from pendulum_lqg.scoreboard.board import make_board, read_scores

BOARD = Path(__file__).resolve().parents[2] / "docs" / "leaderboard"


def _summary_module():
    spec = importlib.util.spec_from_file_location("leaderboard_summary", BOARD / "summary.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_committed_summary_and_board_are_made_from_the_committed_scores():
    scores = read_scores(BOARD / "scores")
    summary = _summary_module()
    assert (BOARD / "summary.md").read_text(encoding="utf-8") == summary.summary_markdown(scores)
    assert (BOARD / "board.md").read_text(encoding="utf-8") == make_board(BOARD / "scores")
    assert (BOARD / "summary.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_summary_cell_is_the_full_tables_success_and_gap():
    scores = read_scores(BOARD / "scores")
    suites, rows = _summary_module().summary_cells(scores)
    assert suites == ["full-state", "lecture", "mismatch", "delayed", "lossy", "noisy", "hard"]
    cells = dict(rows)["dlqr+kalman"]
    assert cells[0] == "n/a"                        # a measurement policy on the full-state suite
    lecture = next(d for _, d in scores if d["policy"] == "dlqr+kalman")["suites"]["lecture"]
    assert cells[1] == (lecture["success_rate"], lecture["optimality_gap"]) == (1.0, 0.0)
    table = _summary_module().summary_markdown(scores).splitlines()
    assert table[0] == "| entry | " + " | ".join(suites) + " |"
    assert "| `dlqr+kalman` | n/a | 100 % · +0.00 |" in next(r for r in table if "`dlqr+kalman`" in r)
