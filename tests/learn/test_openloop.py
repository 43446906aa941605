"""``sysid-openloop`` (the earlier ``sysid-lqg``, renamed and kept as evidence): its budgets, and a
short run that writes a state-space controller identified from open-loop bursts with its record."""

from __future__ import annotations

import json

from pendulum_lqg.cli import main
from pendulum_lqg.learn.openloop import BUDGETS, HORIZON, budgets_for


def test_the_budgets_stop_at_steps():
    assert budgets_for(None) == BUDGETS
    assert budgets_for(60_000) == (5_000, 10_000, 20_000, 50_000, 60_000)
    assert budgets_for(5_000) == (5_000,)


def test_a_short_open_loop_run_writes_its_controller_and_curve(tmp_path, capsys,
                                                               few_curve_episodes):
    assert main(["train", "sysid-openloop", "--seed", "7", "--steps", "6000", "--out",
                 str(tmp_path)]) == 0
    doc = json.loads((tmp_path / "sysid-openloop-seed7.json").read_text())
    t = doc["training"]
    assert (doc["method"], doc["seed"], doc["form"], doc["action_scale"]) == \
        ("sysid-openloop", 7, "state_space", 1.0)
    # the first episodes whose logged samples reach the budget: at most one burst beyond it
    assert 6000 <= t["budget"]["logged_steps"] < 6000 + HORIZON
    assert set(t["model"]) == {"A", "B", "W", "V"} and len(t["model"]["A"]) == 4
    rows = (tmp_path / "sysid-openloop-seed7-curve.csv").read_text().splitlines()
    assert [int(r.split(",")[0]) for r in rows[1:]][-1] == t["budget"]["logged_steps"]
    assert len(rows) == 3                                   # 5 000 and 6 000
