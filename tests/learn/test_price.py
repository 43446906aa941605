"""The price-of-not-knowing-the-model curve (pendulum_lqg.learn.price) from a synthetic CSV: the
fitted slope of a gap that falls as 1/N is −1, the figure is drawn, and the CLI keeps its contract
(one-line errors, exit 2, no output replaced without --force). Nothing is trained here."""

from __future__ import annotations

import numpy as np
import pytest

from pendulum_lqg.learn import price
from pendulum_lqg.util.files import atomic_write, rows_to_csv


def _rows(rate: float = 1.0) -> list[dict]:
    rows = []
    for suite in price.SUITES:
        for seed in range(5):
            for budget in (5_000, 10_000, 50_000, 500_000):
                steps = budget - 10 * seed
                rows.append({"suite": suite, "seed": seed, "budget": budget,
                             "logged_steps": steps, "stepped_steps": steps + 4000,
                             "success": 1.0, "score": 1.0 - 100.0 / steps,
                             "J": 34.0 * (1 + 100.0 * (1 + seed / 10) / steps ** rate),
                             "J_ref": 34.0, "gap": 100.0 * (1 + seed / 10) / steps ** rate,
                             "wall_seconds": 1.0})
    return rows


def test_a_gap_that_falls_as_one_over_n_has_slope_minus_one():
    slope, intercept, count = price.gap_slope(_rows(), "lecture")
    assert count == 4
    assert slope == pytest.approx(-1.0, abs=1e-3)
    assert np.exp(intercept) == pytest.approx(120.0, rel=1e-2)   # the median seed's 100·(1 + 0.2)
    assert price.gap_slope(_rows(0.5), "mismatch")[0] == pytest.approx(-0.5, abs=1e-3)


def test_the_figure_is_drawn_and_prints_the_slopes(tmp_path, capsys):
    csv = tmp_path / "price.csv"
    atomic_write(csv, rows_to_csv(_rows()))
    curves = tmp_path / "models"
    curves.mkdir()
    atomic_write(curves / "ppo-history-seed0-curve.csv",
                 "env_steps,wall_seconds,success_rate,score_mean,score_ci_lo,score_ci_hi\n"
                 "50000,1.0,0.0,0.0,0.0,0.0\n1000000,2.0,0.5,0.4,0.3,0.5\n")
    out = tmp_path / "price.png"
    assert price.main(["figure", str(csv), "--out", str(out), "--curves", str(curves)]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    printed = capsys.readouterr().out
    assert "lecture: gap slope -1.00 over 4 budgets" in printed
    # an existing output is kept unless --force
    before = out.read_bytes()
    assert price.main(["figure", str(csv), "--out", str(out)]) == 2
    assert out.read_bytes() == before
    err = capsys.readouterr().err
    assert err.startswith(f"error: --out: {out} exists; give --force")


def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys):
    assert price.main(["figure", str(tmp_path / "none.csv"), "--out",
                       str(tmp_path / "x.png")]) == 2
    assert capsys.readouterr().err.startswith("error: csv: ")
    assert price.main(["run", "--out", str(tmp_path / "p.csv"), "--budgets", "5000,x"]) == 2
    assert capsys.readouterr().err.strip() == ("error: --budgets: expected comma-separated "
                                               "integers, got '5000,x'")
    with pytest.raises(SystemExit) as exc:
        price.main(["run"])
    assert exc.value.code == 2


def test_the_table_gives_each_budgets_median_and_quartiles():
    """Three seeds at one budget: the table's cells are numpy's median and quartiles of them."""
    rows = [{"suite": "lecture", "seed": s, "budget": 10_000, "logged_steps": steps,
             "stepped_steps": steps, "success": ok, "score": score, "J": 1.0, "J_ref": 1.0,
             "gap": gap, "wall_seconds": 1.0}
            for s, (steps, ok, score, gap) in enumerate([(9_000, 1.0, 0.99, 0.01),
                                                          (8_000, 0.5, 0.40, 0.20),
                                                          (10_000, 1.0, 0.97, 0.03)])]
    lines = price.table_lines(rows)
    assert lines[2] == ("| lecture | 10,000 | 3 | 9,000 | 1.00 [0.75, 1.00] | 0.970 [0.685, 0.980] "
                        "| +0.0300 [+0.0200, +0.1150] |")
