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
                             **_exact(suite, seed, budget, steps, rate), "wall_seconds": 1.0})
    return rows


def _exact(suite: str, seed: int, budget: int, steps: int, rate: float) -> dict:
    """The exact columns: none on mismatch (a randomised plant); on lecture a gap 200/N^rate of
    each run's logged steps N, seed 1's loop unstable at the smallest budget."""
    if suite == "mismatch":
        return dict.fromkeys(price.COLUMNS[10:15])
    if seed == 1 and budget == 5_000:
        return {"exact_J": None, "exact_J_opt": 34.0, "exact_gap": None,
                "exact_episode_gap": None, "spectral_radius": 1.002}
    gap = 200.0 / steps ** rate
    return {"exact_J": 34.0 * (1 + gap), "exact_J_opt": 34.0, "exact_gap": gap,
            "exact_episode_gap": gap, "spectral_radius": 0.995}


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
    assert "lecture: exact gap slope -1.00 [95 % over seeds: -1.00, -1.00] over 19 stabilising " \
        "runs of 5 seeds" in printed
    assert "mismatch: exact" not in printed
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
    for r, (gap, radius) in zip(rows, [(0.02, 0.99), (None, 1.01), (0.05, 0.98)], strict=True):
        r.update(exact_J=None, exact_J_opt=1.0, exact_gap=gap, exact_episode_gap=gap,
                 spectral_radius=radius)
    lines = price.table_lines(rows)
    # the exact gap's order statistics with the unstable seed's ∞: median 0.05, q25 0.02, q75 ∞
    assert lines[2] == ("| lecture | 10,000 | 3 | 9,000 | 1.00 [0.75, 1.00] | 0.970 [0.685, 0.980] "
                        "| +0.0300 [+0.0200, +0.1150] | +0.0500 [+0.0200, ∞] | 2/3 |")


def test_the_exact_slope_is_the_pooled_fit_and_its_interval_spans_the_seeds():
    """Exact gaps g = 200/N: the pooled least-squares slope of log g on log N is −1 and so is
    every bootstrap draw; a seed whose gap falls as N^−0.5 widens the interval around the pooled
    slope, which equals numpy's polyfit of all points; the unstable run counts against the
    stabilising fraction only."""
    rows = _rows()
    fit = price.exact_slope(rows, "lecture")
    assert fit["slope"] == pytest.approx(-1.0, abs=1e-12) and fit["runs"] == 19
    assert fit["ci"] == pytest.approx((-1.0, -1.0), abs=1e-9)
    for r in rows:                                    # seed 4 falls as N^−0.5
        if r["suite"] == "lecture" and r["seed"] == 4:
            r["exact_gap"] = 200.0 / r["logged_steps"] ** 0.5
    fit = price.exact_slope(rows, "lecture")
    pts = [(r["logged_steps"], r["exact_gap"]) for r in rows
           if r["suite"] == "lecture" and r["exact_gap"] is not None]
    x, y = np.log(np.array(pts, dtype=float)).T
    assert fit["slope"] == pytest.approx(np.polyfit(x, y, 1)[0], rel=1e-12)
    lo, hi = fit["ci"]
    assert -1.0 - 1e-9 <= lo < fit["slope"] < hi <= -0.5 + 1e-9
    budgets, frac, med, q25, q75 = price.stabilising(rows, "lecture")
    assert list(budgets) == [5_000, 10_000, 50_000, 500_000]
    assert list(frac) == [0.8, 1.0, 1.0, 1.0]
    # 10 000: seed 4's gap is 200/N^0.5, the others' 200/N: the order statistics of the five
    gaps = sorted([200.0 / (10_000 - 10 * k) for k in range(4)] + [200.0 / 9_960 ** 0.5])
    assert (med[1], q25[1], q75[1]) == pytest.approx((gaps[2], gaps[1], gaps[3]), rel=1e-12)
    assert np.isfinite(q75[0])                # one ∞ of five (seed 1) sits above the 75th
    assert price.exact_slope(rows, "mismatch") is None
    assert price.stabilising(rows, "mismatch")[0].size == 0


def test_a_fifo_among_the_curve_files_is_one_line_not_a_hang(tmp_path, capsys):
    """Issue 55 item 16: ``price figure --curves`` reads regular files only."""
    import os

    csv = tmp_path / "price.csv"
    atomic_write(csv, rows_to_csv(_rows()))
    curves = tmp_path / "models"
    curves.mkdir()
    os.mkfifo(curves / "ppo-history-seed0-curve.csv")
    assert price.main(["figure", str(csv), "--out", str(tmp_path / "p.png"), "--curves",
                       str(curves)]) == 2
    err = capsys.readouterr().err.strip()
    assert err == (f"error: --curves: {curves / 'ppo-history-seed0-curve.csv'} is a FIFO (named "
                   "pipe); expected a regular file")


@pytest.mark.parametrize(("argv", "message"), [
    (["run", "--out", "{tmp}/p.csv", "--suites", ""],
     "error: --suites: expected comma-separated suite names, got ''"),
    (["run", "--out", "{tmp}/p.csv", "--suites", " , "],
     "error: --suites: expected comma-separated suite names, got ' , '"),
    (["run", "--out", "{tmp}/p.csv", "--budgets", "10000001"],
     "error: --budgets: at most 10,000,000 logged steps a budget (the identification keeps every "
     "logged step in memory), got 10,000,001"),
    (["run", "--out", "{tmp}/p.csv", "--seeds", ",".join(map(str, range(2000)))],
     "error: --budgets: at most 10,000 runs (suites × seeds × budgets, each an identification "
     "and a score), got 32,000"),
    (["run", "--out", "{tmp}/bad.csv", "--resume"],
     "error: --resume: {tmp}/bad.csv: line 2: budget: expected an integer, got 'x'"),
    (["figure", "{tmp}/bad.csv", "--out", "{tmp}/p.png"],
     "error: csv: {tmp}/bad.csv: line 2: budget: expected an integer, got 'x'"),
    (["figure", "{tmp}/short.csv", "--out", "{tmp}/p.png"],
     "error: csv: {tmp}/short.csv: expected the columns " + ", ".join(price.COLUMNS)
     + ", got suite, seed"),
    (["run", "--out", "{tmp}/p.csv", "--bogus"], None),
])
def test_price_errors_are_one_line_and_exit_2(tmp_path, capsys, argv, message):
    """Issue 55 items 17 and 20: ceilings checked before any work, a damaged CSV through
    ``--resume`` and ``figure``, an empty ``--suites`` and argparse's own errors: one line, exit
    2, nothing written."""
    good = rows_to_csv(_rows()).splitlines()
    cells = good[1].split(",")
    cells[2] = "x"
    atomic_write(tmp_path / "bad.csv", "\n".join([good[0], ",".join(cells)]) + "\n")
    atomic_write(tmp_path / "short.csv", "suite,seed\nlecture,0\n")
    before = sorted(p.name for p in tmp_path.iterdir())
    try:
        status = price.main([a.replace("{tmp}", str(tmp_path)) for a in argv])
    except SystemExit as exc:                 # argparse's errors exit from the parser
        status = exc.code
    assert status == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and err.startswith("error: "), err
    if message is not None:
        assert err.strip() == message.replace("{tmp}", str(tmp_path))
    assert sorted(p.name for p in tmp_path.iterdir()) == before
