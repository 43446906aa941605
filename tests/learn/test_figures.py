"""pendulum_lqg.learn.figures on synthetic score files and curves: the performance profile and the
probability of improvement are the statistics module's on the method's runs × suites, and the
learning curves' median and interquartile range are those of the seeds, by hand; a FIFO among the
inputs is never opened and a FIFO as an output is refused."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from pendulum_lqg.learn import figures
from pendulum_lqg.scoreboard import stats

ROOT = Path(__file__).resolve().parents[2]
FINGERPRINTS = {"lecture": "a" * 64, "lossy": "b" * 64, "full-state": "c" * 64}


@pytest.fixture(scope="module")
def rl_figures():
    return figures


def _entry(suite, score, applicable=True):
    if not applicable:
        return {"applicable": False, "reason": "observes x", "episodes": 4, "version": 1,
                "fingerprint": FINGERPRINTS[suite]}
    figures = {"success_rate": 1.0, "cost_mean": 2.0}
    return {"applicable": True, "fingerprint": FINGERPRINTS[suite], "episodes": 4,
            "success_rate": min(score, 1.0), "success_ci": [0.0, 1.0], "cost_mean": 2.0,
            "cost_se": 0.1, "optimality_gap": None, "gap_ci": [None, None], "gap_episodes": 0,
            "score_mean": score, "score_ci": [score, score], "version": 1,
            "reference": {"policy": "dlqr+kalman", **figures},
            "full_state_bound": {"policy": "dlqr+none", **figures},
            "rows": [{"episode": i, "seed": i, "success": True, "failure_reason": "",
                      "cost": 2.0} for i in range(4)]}


def _write(folder, name, policy, scores, **top):
    suites = {s: _entry(s, v) for s, v in scores.items()}
    suites["full-state"] = _entry("full-state", 0.0, applicable=False)
    doc = {"policy": policy, "kind": "agent", "score_version": 1, "versions": {}, **top,
           "suites": suites}
    (folder / f"{name}.json").write_text(json.dumps(doc), encoding="utf-8")


def test_profile_and_improvement_are_the_statistics_of_the_runs(rl_figures, tmp_path):
    a = np.array([[0.2, 0.1], [0.6, 0.4], [0.9, 0.3]])          # method a: 3 runs × 2 suites
    b = np.array([[0.5, 0.5], [0.7, 0.0]])
    for k, row in enumerate(a):
        _write(tmp_path, f"a{k}", f"sb3:a{k}.zip", dict(zip(("lecture", "lossy"), row, strict=True)),
               method="a", seed=k)
    for k, row in enumerate(b):
        _write(tmp_path, f"b{k}", f"sb3:b{k}.zip", dict(zip(("lecture", "lossy"), row, strict=True)),
               method="b", seed=k)
    _write(tmp_path, "ref", "dlqr+kalman", {"lecture": 1.0, "lossy": 0.93})
    _write(tmp_path, "full", "sb3:full.zip", {}, method="full-state-only", seed=0)
    suites, scores = rl_figures.method_scores(tmp_path, ["dlqr+kalman"])
    assert suites == ["lecture", "lossy"] and sorted(scores) == ["a", "b", "dlqr+kalman"]
    np.testing.assert_array_equal(scores["a"], a)
    np.testing.assert_array_equal(scores["dlqr+kalman"], [[1.0, 0.93]])
    table = rl_figures.improvement_table(scores, suites)
    row = next(line for line in table.splitlines() if line.startswith("| `a` |"))
    p = stats.probability_of_improvement(a, b)
    # per suite, a's runs beat b's runs: lecture 3 of 6 pairs, lossy (0.1,0.4,0.3 vs 0.5,0) 3 of 6
    assert p == pytest.approx(0.5)
    lo, hi = stats.probability_of_improvement_ci(a, b)
    assert f"| `a` | – | {p:.2f} [{lo:.2f}, {hi:.2f}] | 0.00 [0.00, 0.00] |" == row
    rl_figures.draw_profile(scores, suites, tmp_path / "profile.png")
    assert (tmp_path / "profile.png").stat().st_size > 10_000


def test_curves_give_the_median_and_quartiles_of_the_seeds(rl_figures, tmp_path):
    header = "env_steps,wall_seconds,success_rate,score_mean,score_ci_lo,score_ci_hi\n"
    for seed, final in enumerate((0.2, 0.4, 0.9)):
        (tmp_path / f"ppo-history-seed{seed}-curve.csv").write_text(
            header + f"50000,100.0,0.0,0.0,0,0\n100000,200.0,{final},{final / 2},0,0\n",
            encoding="utf-8")
    (tmp_path / "sac-history-seed0-curve.csv").write_text(
        header + "50000,400.0,0.1,,0,0\n", encoding="utf-8")               # a score of None
    curves = rl_figures.read_curves(tmp_path)
    assert sorted(curves) == ["ppo-history", "sac-history"] and len(curves["ppo-history"]) == 3
    grid, med, q25, q75 = rl_figures.median_iqr(curves["ppo-history"], "env_steps",
                                                "success_rate")
    end = grid.size - 1
    assert grid[end] == 100_000 and med[end] == pytest.approx(0.4)
    assert (q25[end], q75[end]) == pytest.approx((0.3, 0.65))   # numpy's linear quartiles
    assert np.isnan(med[0])                                     # before every run's first point
    rl_figures.draw_curves(curves, tmp_path / "curves.png")
    assert (tmp_path / "curves.png").stat().st_size > 10_000


def test_budget_sums_wall_seconds_times_threads_per_method(rl_figures, tmp_path):
    def sb3(method, seed, wall, threads=1):
        (tmp_path / f"{method}-seed{seed}.json").write_text(json.dumps(
            {"method": method, "budget": {"steps": 1000, "wall_seconds": wall, "threads": threads}}))

    sb3("ppo-history", 0, 1800.0)
    sb3("ppo-history", 1, 3600.0, threads=2)
    (tmp_path / "ars-history-seed0.json").write_text(json.dumps(
        {"method": "ars-history", "training": {"budget": {"steps": 500}, "wall_seconds": 360.0}}))
    (tmp_path / "ppo-history-seed0-curve.csv").write_text("env_steps\n1\n")   # not a record
    budgets = rl_figures.read_budgets(tmp_path)
    assert budgets == {"ars-history": [(500, 360.0, 1)],
                       "ppo-history": [(1000, 1800.0, 1), (1000, 3600.0, 2)]}
    table = rl_figures.budget_table(budgets)
    # 1800 s × 1 + 3600 s × 2 = 2.5 CPU-hours; 360 s = 0.1; all 2.6
    assert "| `ppo-history` | 2 | 1,000 | 2700 s | 2.50 |" in table
    assert "| `ars-history` | 1 | 500 | 360 s | 0.10 |" in table
    assert table.rstrip().endswith("| all | 3 | | | 2.60 |")


def _curves(folder):
    header = "env_steps,wall_seconds,success_rate,score_mean,score_ci_lo,score_ci_hi\n"
    for seed in (0, 1):
        (folder / f"ppo-history-seed{seed}-curve.csv").write_text(
            header + "50000,100.0,0.5,0.25,0,0\n", encoding="utf-8")
        (folder / f"ppo-history-seed{seed}.json").write_text(json.dumps(
            {"method": "ppo-history", "budget": {"steps": 50000, "wall_seconds": 100.0,
                                                 "threads": 1}}))


def test_rl_figures_refuses_a_fifo(tmp_path, capsys):
    """A FIFO named like a curve or a record is skipped (not opened: no hang); a FIFO as an
    output is one line, exit 2."""
    import os

    _curves(tmp_path)
    os.mkfifo(tmp_path / "ppo-history-seed2-curve.csv")
    os.mkfifo(tmp_path / "ppo-history-seed2.json")
    assert len(figures.read_curves(tmp_path)["ppo-history"]) == 2
    assert figures.read_budgets(tmp_path) == {"ppo-history": [(50000, 100.0, 1)] * 2}
    out = tmp_path / "out"
    out.mkdir()
    os.mkfifo(out / "budget.md")
    assert figures.main(["budget", str(tmp_path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: --out: ") and "is a FIFO" in err and len(err.splitlines()) == 1
    assert figures.main(["curves", str(tmp_path), "--out", str(out)]) == 0
    assert (out / "curves.png").stat().st_size > 10_000


def test_rl_figures_replace_outputs_only_with_force(tmp_path, capsys):
    _curves(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    (out / "budget.md").write_text("mine")
    assert figures.main(["budget", str(tmp_path), "--out", str(out)]) == 2
    assert "give --force" in capsys.readouterr().err and (out / "budget.md").read_text() == "mine"
    assert figures.main(["budget", str(tmp_path), "--out", str(out), "--force"]) == 0
    assert "| `ppo-history` | 2 | 50,000 | 100 s | 0.06 |" in (out / "budget.md").read_text()


def test_rl_figures_on_a_folder_without_curves_is_one_line(tmp_path, capsys):
    assert figures.main(["curves", str(tmp_path), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and "no METHOD-seedS-curve.csv" in err
