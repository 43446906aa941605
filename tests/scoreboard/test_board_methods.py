"""The failure-aware score in score files and on the board, and the board's methods table, on
small synthetic score files with hand-checked numbers."""

from __future__ import annotations

import json

import numpy as np
import pytest

from pendulum_lqg.boundary.schemas import score_file
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.scoreboard import stats
from pendulum_lqg.scoreboard.board import make_board
from pendulum_lqg.scoreboard.score import suite_score
from pendulum_lqg.scoreboard.suites import load_suite

FINGERPRINT = "f" * 64
REF_COSTS, REF_OK = [1.0, 3.0, 2.0, 4.0], [True, True, False, True]


def _rows(costs, success):
    return [{"episode": i, "seed": 100 + i, "success": s, "failure_reason": "" if s else "angle",
             "cost": c} for i, (c, s) in enumerate(zip(costs, success, strict=True))]


def _file(folder, name, policy, rows, reference_rows=None, **top):
    """A one-suite score file; its failure-aware score against ``reference_rows`` (default: its
    own rows, so that every survived episode scores 1), as ``score`` stores it."""
    ok = [r for r in rows if r["success"]]
    figures = {"success_rate": 1.0, "cost_mean": 2.0}
    entry = {"applicable": True, "fingerprint": FINGERPRINT, "episodes": len(rows),
             "success_rate": len(ok) / len(rows), "cost_mean": 2.0, "optimality_gap": None,
             **stats.failure_aware_figures(rows, reference_rows or rows),
             "reference": {"policy": "dlqr+kalman", **figures},
             "full_state_bound": {"policy": "dlqr+none", **figures}, "rows": rows}
    doc = {"policy": policy, "kind": "agent", "score_version": 1, **top,
           "suites": {"lecture": entry}}
    (folder / name).write_text(json.dumps(doc), encoding="utf-8")
    return entry


def _line(table, start):
    return next(line for line in table.splitlines() if line.startswith(start))


def test_failure_aware_figures_are_the_mean_ratio_with_failures_at_zero():
    ref = _rows(REF_COSTS, REF_OK)
    # the reference failed episode 2: its mean surviving J (1 + 3 + 4) / 3 stands in
    entry = _rows([2.0, 3.0, 8.0 / 3, 1.0], [True, False, True, True])
    fig = stats.failure_aware_figures(entry, ref)
    assert fig["score_mean"] == pytest.approx((0.5 + 0.0 + 1.0 + 4.0) / 4)
    lo, hi = fig["score_ci"]
    assert 0.0 <= lo < fig["score_mean"] < hi <= 4.0       # resampled means of {0.5, 0, 1, 4}
    assert stats.failure_aware_figures(entry, _rows(REF_COSTS, [False] * 4)) == {
        "score_mean": None, "score_ci": [None, None]}       # no reference survivor: undefined


def test_a_suite_entry_carries_the_failure_aware_score_and_the_reference_scores_one():
    suite = load_suite("lecture").with_episodes(4)
    ref = _rows(REF_COSTS, [True] * 4)
    entry = _rows([2.0, 6.0, 1.0, 9.0], [True, True, False, False])
    out = suite_score(suite, entry, ref, ref)
    assert out["score_mean"] == pytest.approx((0.5 + 0.5) / 4)
    assert suite_score(suite, ref, ref, ref)["score_mean"] == 1.0
    assert suite_score(suite, ref, ref, ref)["score_ci"] == [1.0, 1.0]


def test_board_shows_the_stored_score_and_skips_a_file_without_one(tmp_path):
    ref = _rows(REF_COSTS, REF_OK)
    _file(tmp_path, "ref.json", "dlqr+kalman", ref)
    rows = _rows([2.0, 3.0, 8.0 / 3, 1.0], [True, False, True, True])
    _file(tmp_path, "new.json", "new-entry", rows, reference_rows=ref)
    fig = stats.failure_aware_figures(rows, ref)
    lo, hi = fig["score_ci"]
    assert fig["score_mean"] == pytest.approx(1.375)
    table = make_board(tmp_path)
    assert _line(table, "| `new-entry` |").endswith(f"| 1.38 [{lo:.2f}, {hi:.2f}] |")
    # the reference against itself: 1 where it survived, 0 on its failed episode 2
    assert "| 0.75 [" in _line(table, "| `dlqr+kalman` |")
    _file(tmp_path, "undefined.json", "no-survivor", rows,
          reference_rows=_rows(REF_COSTS, [False] * 4))          # no reference survivor: null
    assert _line(make_board(tmp_path), "| `no-survivor` |").endswith("| n/a |")
    doc = json.loads((tmp_path / "new.json").read_text())
    del doc["suites"]["lecture"]["score_mean"]                   # a file without the score
    (tmp_path / "new.json").write_text(json.dumps(doc))
    warned: list[str] = []
    table = make_board(tmp_path, warn=warned.append)
    assert "| `new-entry` |" not in table
    assert warned == ["board: skipped new.json: suites.lecture.score_mean: missing"]


def test_board_aggregates_the_runs_of_a_method_by_iqm_with_stratified_bootstrap(tmp_path):
    ref = _rows(REF_COSTS, [True] * 4)
    _file(tmp_path, "ref.json", "dlqr+kalman", ref)
    # four runs; successes 0, 1, 2, 3 of 4 episodes → IQM of {0, .25, .5, .75} = mean(.25, .5)
    for seed in range(4):
        ok = [i < seed for i in range(4)]
        _file(tmp_path, f"ppo-{seed}.json", f"sb3:m/ppo-history-seed{seed}.zip",
              _rows(REF_COSTS, ok), ref, method="ppo-history", seed=seed)
    _file(tmp_path, "ppo-again.json", "sb3:m/copy.zip", _rows(REF_COSTS, [True] * 4),
          method="ppo-history", seed=2)                                # the same run again
    table = make_board(tmp_path)
    row = _line(table, "| `ppo-history` |")
    success = np.array([0.0, 0.25, 0.5, 0.75])
    # with the reference's own costs, every survived episode scores 1: score = success rate
    agg = stats.aggregate(success)
    assert agg["iqm"] == pytest.approx(0.375)
    lo, hi = agg["iqm_ci"]
    assert 0.0 <= lo < 0.375 < hi <= 0.75
    assert row == (f"| `ppo-history` | 4 (0, 1, 2, 3) | 38 % [{100 * lo:.0f} %, {100 * hi:.0f} %] "
                   f"| 0.38 [{lo:.2f}, {hi:.2f}] |")
    assert "Counted once (the same method and seed again): ppo-again.json" in table
    assert "| `dlqr+kalman` |" not in table.split("| method |")[1]     # runs of no method: not here


def test_a_board_without_method_files_has_no_methods_table(tmp_path):
    _file(tmp_path, "ref.json", "dlqr+kalman", _rows(REF_COSTS, REF_OK))
    assert "| method |" not in make_board(tmp_path)


@pytest.mark.parametrize(("change", "message"), [
    (lambda d: d.__setitem__("seed", -1), "seed: expected a non-negative integer"),
    (lambda d: d["suites"]["lecture"].__setitem__("score_mean", "high"),
     "suites.lecture.score_mean: expected a finite number or null"),
])
def test_a_damaged_method_seed_row_or_score_is_one_line(tmp_path, change, message):
    _file(tmp_path, "a.json", "x", _rows(REF_COSTS, REF_OK), method="m", seed=1)
    doc = json.loads((tmp_path / "a.json").read_text())
    change(doc)
    (tmp_path / "a.json").write_text(json.dumps(doc))
    with pytest.raises(ConfigError, match="^board: .*a.json: " + message.replace("(", r"\(")):
        score_file(tmp_path / "a.json")


class _ZeroModel:
    """stable-baselines3's predict signature, always a zero action (no torch needed)."""

    def predict(self, observation, state=None, episode_start=None, deterministic=False):
        return np.zeros((observation.shape[0], 1)), state


def test_an_sb3_score_file_names_its_method_seed_model_hash_and_rl_versions(tmp_path, monkeypatch):
    import hashlib

    from pendulum_lqg.scoreboard import sb3
    from pendulum_lqg.scoreboard.score import score_entry

    model = tmp_path / "ppo-history-seed3.zip"
    model.write_bytes(b"not a real zip: the loader is stood in")
    record = {"algo": "PPO", "method": "ppo-history", "seed": 3, "frame_stack": 1,
              "obs_norm": None, "normalize_action": True, "env": {}}
    model.with_suffix(".json").write_text(json.dumps(record))
    monkeypatch.setattr(sb3, "load_model", lambda path, algo: _ZeroModel())
    doc = score_entry([load_suite("lecture").with_episodes(2)], agent=f"sb3:{model}")
    assert doc["method"] == "ppo-history" and doc["seed"] == 3
    assert doc["model_sha256"] == hashlib.sha256(model.read_bytes()).hexdigest()
    assert set(doc["versions"]) >= {"torch", "stable-baselines3", "sb3-contrib", "pendulum_lqg"}
    lecture = doc["suites"]["lecture"]
    assert lecture["success_rate"] == 0.0 and lecture["score_mean"] == 0.0   # zero force falls
    (tmp_path / "run.json").write_text(json.dumps(doc))
    assert score_file(tmp_path / "run.json")["method"] == "ppo-history"
