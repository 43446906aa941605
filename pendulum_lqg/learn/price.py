"""The price of not knowing the model: what closed-loop identification reaches with N logged steps.

::

    uv run python -m pendulum_lqg.learn.price run --out docs/leaderboard/price.csv
    uv run python -m pendulum_lqg.learn.price figure docs/leaderboard/price.csv \\
        --out docs/leaderboard/price.png --table docs/leaderboard/price.md

``run``: for every suite, data seed ``S`` and budget ``N`` (logged env steps), the controller of
:func:`~pendulum_lqg.learn.closed_loop.identify_closed_loop` (root seed ``500 000 + 1000·S``, the
``train`` command's) with that budget, scored on the suite's own episodes as ``pendulum-lqg
score`` scores it (:func:`~pendulum_lqg.scoreboard.linear.linear_rows`, the failure-aware score
against the suite reference's rows, the optimality gap ``J/J* − 1`` on the episodes both
survived), and on a suite with one fixed plant its exact stationary J and gap on the linearised
plant (:mod:`pendulum_lqg.scoreboard.exact`): one CSV row each (:data:`COLUMNS`), the file
rewritten atomically after every row, so a run stopped half-way keeps what it finished
(``--resume`` continues it).

``figure``: per suite, the failure-aware score and the gap against the logged env steps (log
axes; median and interquartile range over the seeds), the deep-RL methods' committed learning
curves (``METHOD-seedS-curve.csv`` of ``--curves``: their own 20 fixed lecture-like episodes, so
drawn on the ``lecture`` panel only) on the same axes, and the least-squares slope of
``log(median gap)`` against ``log(budget)`` over the budgets whose median gap is positive, beside
the ``1/N`` rate of certainty equivalence (Mania, Tu & Recht 2019), printed; where the CSV has
the exact gap, that gap of every stabilising run against its logged steps with the slope of
:func:`exact_slope` and its bootstrap interval over seeds, and the fraction of stabilising
controllers per budget (:func:`stabilising`). The x position of a
budget is the budget: it caps the logged steps (a run whose episodes fail early logs fewer, and
the CSV says how many).
"""

from __future__ import annotations

import argparse
import math
import re
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from pendulum_lqg.errors import ConfigError

BUDGETS = (5_000, 10_000, 15_000, 20_000, 50_000, 100_000, 200_000, 500_000)
SUITES = ("lecture", "mismatch")
SEEDS = (0, 1, 2, 3, 4)
COLUMNS = ("suite", "seed", "budget", "logged_steps", "stepped_steps", "success", "score", "J",
           "J_ref", "gap", "exact_J", "exact_J_opt", "exact_gap", "exact_episode_gap",
           "spectral_radius", "wall_seconds")
#: Ceiling of one budget [logged env steps]: the identification keeps every logged step's y and u
#: in memory and refits on them each round; 10⁷ is 20 × the largest budget the figure uses.
MAX_BUDGET = 10_000_000
#: Ceiling of the rows of one run (suites × seeds × budgets), each an identification and a score.
MAX_ROWS = 10_000
#: Bootstrap resamples over seeds of the exact gap's slope, and their seed.
SLOPE_RESAMPLES, SLOPE_SEED = 2000, 0
CURVE_FILE = re.compile(r"^(?P<method>.+)-seed(?P<seed>\d+)-curve\.csv$")


def run_root(seed: int) -> int:
    """The root seed of data seed ``seed`` (the ``train`` command's)."""
    return 500_000 + 1000 * seed


def price_row(suite: Any, reference: list[dict[str, Any]], seed: int, budget: int,
              exact_reference: tuple[float, float] | None = None) -> dict[str, Any]:
    """One CSV row: identify on ``suite`` with ``budget`` logged steps, score the controller, and
    (``exact_reference``: :func:`~pendulum_lqg.scoreboard.exact.exact_reference` of a suite with
    one fixed plant, else ``None``) its exact stationary J and gap on the linearised plant."""
    from pendulum_lqg.learn.closed_loop import identify_closed_loop
    from pendulum_lqg.scoreboard.linear import controller_file, linear_rows
    from pendulum_lqg.scoreboard.score import optimality_gap, success_figures
    from pendulum_lqg.scoreboard.stats import failure_aware_figures

    t0 = time.perf_counter()
    final = identify_closed_loop(suite, root=run_root(seed), steps=budget)[-1]
    wall = time.perf_counter() - t0
    doc = controller_file("state_space", final.state_space, action_scale=1.0, env=suite.env,
                          method="sysid-lqg", seed=seed)
    rows = linear_rows(suite, doc, name=f"sysid-lqg seed {seed} ({budget:,} steps)", nthread=1)
    fig, ref = success_figures(rows), success_figures(reference)
    exact: dict[str, Any] = dict.fromkeys(COLUMNS[10:15])
    if exact_reference is not None:
        from pendulum_lqg.scoreboard.exact import exact_linear

        res = exact_linear(suite, doc, reference=exact_reference)
        exact = {"exact_J": res.J if res.stable else None, "exact_J_opt": res.J_opt,
                 "exact_gap": res.gap if res.stable else None,
                 "exact_episode_gap": res.episode_gap if res.stable else None,
                 "spectral_radius": res.spectral_radius}
    return {"suite": suite.name, "seed": seed, "budget": budget,
            "logged_steps": final.logged_steps, "stepped_steps": final.stepped_steps,
            "success": fig["success_rate"],
            "score": failure_aware_figures(rows, reference)["score_mean"],
            "J": fig["cost_mean"], "J_ref": ref["cost_mean"],
            "gap": optimality_gap(rows, reference)["optimality_gap"], **exact,
            "wall_seconds": round(wall, 1)}


def read_rows(path: Path, *, where: str) -> list[dict[str, Any]]:
    """The rows of a price CSV, read at the boundary (a regular file of at most
    :data:`~pendulum_lqg.util.limits.MAX_INPUT_BYTES`, UTF-8) and checked: the columns
    :data:`COLUMNS`, a suite name, a seed ≥ 0 and a budget ≥ 1 on every row, numbers or empty
    cells elsewhere; anything else is one line naming ``where``, the file, the line and the
    column."""
    import csv
    import io

    from pendulum_lqg.boundary import read_text

    text = read_text(path, where=where)
    try:
        table = list(csv.reader(io.StringIO(text, newline="")))
    except csv.Error as exc:
        raise ConfigError(f"{where}: {path} is not a CSV file ({exc})") from None
    if not table or tuple(table[0]) != COLUMNS:
        raise ConfigError(f"{where}: {path}: expected the columns {', '.join(COLUMNS)}"
                          + (f", got {', '.join(table[0])}" if table and table[0] else ""))
    rows = []
    for line, cells in enumerate(table[1:], start=2):
        if not cells:
            continue
        if len(cells) != len(COLUMNS):
            raise ConfigError(f"{where}: {path}: line {line}: expected {len(COLUMNS)} cells, "
                              f"got {len(cells)}")
        row: dict[str, Any] = {"suite": cells[0]}
        if not cells[0].strip():
            raise ConfigError(f"{where}: {path}: line {line}: suite: expected a suite name, "
                              "got ''")
        for key, cell in zip(COLUMNS[1:], cells[1:], strict=True):
            row[key] = _cell(where, path, line, key, cell)
        rows.append(row)
    return rows


def _cell(where: str, path: Path, line: int, key: str, cell: str) -> Any:
    """One checked cell: an integer (seed ≥ 0, budget ≥ 1, the step counts ≥ 0) or a number
    (empty: none, e.g. the gap of a controller that never survived)."""
    if key in ("seed", "budget", "logged_steps", "stepped_steps"):
        try:
            value = int(cell)
        except ValueError:
            raise ConfigError(f"{where}: {path}: line {line}: {key}: expected an integer, got "
                              f"{cell!r}") from None
        low = 1 if key == "budget" else 0
        if value < low:
            raise ConfigError(f"{where}: {path}: line {line}: {key}: expected an integer "
                              f"≥ {low}, got {cell!r}")
        return value
    if cell in ("", "None"):
        return None
    try:
        value_f = float(cell)
    except ValueError:
        raise ConfigError(f"{where}: {path}: line {line}: {key}: expected a number, got "
                          f"{cell!r}") from None
    if math.isnan(value_f):
        raise ConfigError(f"{where}: {path}: line {line}: {key}: expected a number, got "
                          f"{cell!r}")
    return value_f


def run(out: Path, *, suites: Sequence[str], seeds: Sequence[int], budgets: Sequence[int],
        resume: bool) -> list[dict[str, Any]]:
    """Every (suite, seed, budget) row not yet in ``out``, ``out`` rewritten atomically after
    each; seed by seed (a run stopped early has whole curves of its first seeds)."""
    from pendulum_lqg.scoreboard import episodes as ep
    from pendulum_lqg.scoreboard.suites import load_suite
    from pendulum_lqg.util.files import atomic_write, rows_to_csv

    rows = read_rows(out, where="--resume") if resume and out.exists() else []
    done = {(r["suite"], int(r["seed"]), int(r["budget"])) for r in rows}
    loaded = {name: load_suite(name) for name in suites}
    references: dict[str, list[dict[str, Any]]] = {}
    exact: dict[str, tuple[float, float] | None] = {}
    for seed in seeds:
        for budget in sorted(budgets):
            for name, suite in loaded.items():
                if (suite.name, seed, budget) in done:
                    continue
                if name not in references:
                    references[name] = ep.policy_rows(suite, suite.reference, nthread=1)
                if name not in exact:
                    exact[name] = _exact_reference(suite)
                row = price_row(suite, references[name], seed, budget, exact[name])
                rows.append(row)
                atomic_write(out, rows_to_csv(rows))
                print(f"{suite.name} seed {seed} budget {budget:,}: {row['logged_steps']:,} "
                      f"logged, success {row['success']:.2f}, score {row['score']:.3f}, gap "
                      f"{_fmt(row['gap'])} ({row['wall_seconds']} s)", file=sys.stderr, flush=True)
    return rows


def _exact_reference(suite: Any) -> tuple[float, float] | None:
    """The exact J* of a suite with one fixed plant; ``None`` where the theory has no single
    linear loop (a randomised plant: ``mismatch``)."""
    from pendulum_lqg.errors import PendulumLQGError
    from pendulum_lqg.scoreboard.exact import exact_reference

    try:
        return exact_reference(suite)
    except PendulumLQGError:
        return None


def _fmt(x: Any) -> str:
    return "—" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{x:+.4f}"


def _number(x: Any) -> float:
    return math.nan if x in (None, "", "None") else float(x)


def summary(rows: list[dict[str, Any]], suite: str, key: str,
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(budgets, median, q25, q75)`` of ``key`` over the seeds, per budget (a budget caps the
    logged steps; a run whose episodes fail early logs fewer)."""
    budgets = sorted({int(r["budget"]) for r in rows if r["suite"] == suite})
    out = np.full((3, len(budgets)), np.nan)
    for i, b in enumerate(budgets):
        values = np.array([_number(r[key]) for r in rows
                           if r["suite"] == suite and int(r["budget"]) == b])
        if np.isfinite(values).any():
            out[:, i] = np.nanpercentile(values, [50, 25, 75])
    return np.array(budgets, dtype=float), out[0], out[1], out[2]


def gap_slope(rows: list[dict[str, Any]], suite: str) -> tuple[float, float, int]:
    """``(slope, intercept, budgets)`` of the least-squares line through ``log median gap``
    against ``log budget``, over the budgets whose median gap is positive."""
    steps, med, _, _ = summary(rows, suite, "gap")
    keep = np.isfinite(med) & (med > 0)
    if keep.sum() < 2:
        return math.nan, math.nan, int(keep.sum())
    slope, intercept = np.polyfit(np.log(steps[keep]), np.log(med[keep]), 1)
    return float(slope), float(intercept), int(keep.sum())


def exact_values(rows: list[dict[str, Any]], suite: str) -> list[dict[str, Any]]:
    """The runs of ``suite`` the exact theory judged (a spectral radius in the row): ``{"seed",
    "budget", "steps", "stable", "gap"}``, ``gap`` = ∞ where the loop is unstable."""
    out = []
    for r in rows:
        if r["suite"] != suite or r.get("spectral_radius") in (None, "", "None"):
            continue
        gap = _number(r["exact_gap"])
        stable = float(r["spectral_radius"]) < 1.0 and math.isfinite(gap)
        out.append({"seed": int(r["seed"]), "budget": int(r["budget"]),
                    "steps": int(r["logged_steps"]), "stable": stable,
                    "gap": gap if stable else math.inf})
    return out


def stabilising(rows: list[dict[str, Any]], suite: str,
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(budgets, fraction stabilising, median exact gap, q25, q75)`` per budget over the seeds
    (an unstable loop's gap is ∞, so a median above half the seeds unstable is ∞)."""
    judged = exact_values(rows, suite)
    budgets = sorted({v["budget"] for v in judged})
    frac, q = np.zeros(len(budgets)), np.full((3, len(budgets)), np.nan)
    for i, b in enumerate(budgets):
        at = [v for v in judged if v["budget"] == b]
        frac[i] = sum(v["stable"] for v in at) / len(at)
        # order statistics (the inverted CDF): defined with ∞ entries, linear interpolation not
        q[:, i] = np.percentile([v["gap"] for v in at], [50, 25, 75], method="inverted_cdf")
    return np.array(budgets, dtype=float), frac, q[0], q[1], q[2]


def exact_slope(rows: list[dict[str, Any]], suite: str, *, resamples: int = SLOPE_RESAMPLES,
                seed: int = SLOPE_SEED) -> dict[str, Any] | None:
    """The least-squares slope of ``log exact gap`` against ``log logged steps`` over every
    stabilising run of ``suite`` (pooled over seeds; the logged steps are the samples the fit
    had, which a budget only caps), and its bootstrap 95 % interval over seeds: the seeds drawn
    with replacement, each with all its runs, and the line refitted (``resamples`` times, numpy
    generator ``seed``; a draw with fewer than two distinct step counts is skipped). ``None``
    without two such runs. ``{"slope", "intercept", "ci", "runs", "seeds"}``."""
    pts = [v for v in exact_values(rows, suite) if v["stable"] and v["gap"] > 0]

    def fit(sample: list[dict[str, Any]]) -> tuple[float, float] | None:
        x = np.log([v["steps"] for v in sample])
        if len(set(x.tolist())) < 2:
            return None
        slope, intercept = np.polyfit(x, np.log([v["gap"] for v in sample]), 1)
        return float(slope), float(intercept)

    best = fit(pts) if pts else None
    if best is None:
        return None
    seeds = sorted({v["seed"] for v in pts})
    by_seed = {s: [v for v in pts if v["seed"] == s] for s in seeds}
    rng = np.random.default_rng(seed)
    draws = [fit([v for k in rng.choice(seeds, size=len(seeds)) for v in by_seed[int(k)]])
             for _ in range(resamples)]
    slopes = [d[0] for d in draws if d is not None]
    lo, hi = np.percentile(slopes, [2.5, 97.5]) if slopes else (math.nan, math.nan)
    return {"slope": best[0], "intercept": best[1], "ci": (float(lo), float(hi)),
            "runs": len(pts), "seeds": len(seeds)}


def read_curves(folder: Path) -> dict[str, list[dict[str, np.ndarray]]]:
    """``{method: [run columns]}`` of the model-free methods' ``METHOD-seedS-curve.csv`` files in
    ``folder``: the SB3 methods and ARS from zero, trained at the suite's own noise (the noise
    ladder's runs, ``METHOD-noiseX``, play another problem; the identification and clone runs are
    the model-based side this figure draws on its own)."""
    import csv
    import io

    from pendulum_lqg.boundary import read_text
    from pendulum_lqg.learn.methods import METHODS

    model_free = {name for name, m in METHODS.items() if m.extra} | {"ars-history"}
    out: dict[str, list[dict[str, np.ndarray]]] = {}
    for path in sorted(folder.glob("*-curve.csv")):
        match = CURVE_FILE.match(path.name)
        # read at the boundary: a regular file of bounded size (a FIFO or a device is refused)
        rows = list(csv.DictReader(io.StringIO(read_text(path, where="--curves"), newline=""))) \
            if match and match["method"] in model_free else []
        if rows and {"env_steps", "score_mean"} <= set(rows[0]):
            try:
                cols = {k: np.array([_number(r[k]) for r in rows])
                        for k in ("env_steps", "score_mean")}
            except (TypeError, ValueError):
                raise ConfigError(f"--curves: {path}: env_steps, score_mean: expected numbers "
                                  "on every row") from None
            out.setdefault(match["method"] if match else "", []).append(cols)
    return out


def _rl_curve(ax: Any, method: str, runs: list[dict[str, np.ndarray]]) -> None:
    """Median and IQR across runs of the score against env steps, each run interpolated (in
    log steps) inside its own range."""
    lo = max(min(r["env_steps"].min() for r in runs), 1.0)
    grid = np.geomspace(lo, max(r["env_steps"].max() for r in runs), 60)
    table = np.array([np.where((grid >= r["env_steps"].min()) & (grid <= r["env_steps"].max()),
                               np.interp(np.log(grid), np.log(np.maximum(r["env_steps"], 1.0)),
                                         r["score_mean"]), np.nan) for r in runs])
    seen = np.isfinite(table).sum(axis=0) >= 1
    q = np.nanpercentile(table[:, seen], [50, 25, 75], axis=0)
    line, = ax.plot(grid[seen], q[0], lw=1, ls="--", label=f"{method} ({len(runs)} seeds)")
    ax.fill_between(grid[seen], q[1], q[2], color=line.get_color(), alpha=0.1)


def draw(rows: list[dict[str, Any]], curves: dict[str, list[dict[str, np.ndarray]]],
         path: Path) -> dict[str, tuple[float, float, int]]:
    """The figure (module docstring) to ``path``; each suite's gap slope."""
    from matplotlib.figure import Figure

    suites = [s for s in SUITES if any(r["suite"] == s for r in rows)] or \
        sorted({str(r["suite"]) for r in rows})
    fig = Figure(figsize=(5.0 * len(suites), 15.0), layout="constrained")
    axes = np.array(fig.subplots(4, len(suites), squeeze=False))
    slopes = {}
    for col, suite in enumerate(suites):
        steps, med, q25, q75 = summary(rows, suite, "score")
        top, bottom = axes[0, col], axes[1, col]
        top.plot(steps, med, "o-", color="k", label="sysid-lqg (closed loop)")
        top.fill_between(steps, q25, q75, color="k", alpha=0.15)
        if suite == "lecture":
            for method, runs in sorted(curves.items()):
                _rl_curve(top, method, runs)
        top.axhline(1.0, color="grey", lw=0.8)
        top.set_xlim(left=steps.min() / 1.5)     # a curve's point at 0 steps is its start
        top.set(xscale="log", ylim=(-0.02, 1.08), title=suite, ylabel="failure-aware score",
                xlabel="logged env steps (sysid-lqg: the budget; RL: env steps)")
        top.legend(fontsize=7, loc="lower right")
        steps, med, q25, q75 = summary(rows, suite, "gap")
        slope, intercept, count = slopes[suite] = gap_slope(rows, suite)
        pos = np.isfinite(med) & (med > 0)
        bottom.plot(steps[pos], med[pos], "o-", color="k", label="median gap J/J* − 1")
        band = np.isfinite(q25) & (q25 > 0)
        bottom.fill_between(steps[band], q25[band], q75[band], color="k", alpha=0.15)
        if count >= 2:
            x = steps[pos]
            bottom.plot(x, np.exp(intercept) * x ** slope, color="C3",
                        label=f"fit: slope {slope:.2f}")
            bottom.plot(x, med[pos][0] * (x / x[0]) ** -1.0, color="C0", ls=":", label="1/N")
        bottom.set(xscale="log", yscale="log", ylabel="gap J/J* − 1 (positive part)",
                   xlabel="logged env-step budget")
        bottom.legend(fontsize=7)
        _exact_panels(axes[2, col], axes[3, col], rows, suite)
    fig.suptitle("The price of not knowing the model: closed-loop identification + LQG\n"
                 "(Monte Carlo: median and IQR over data seeds of each suite's 100 episodes; "
                 "exact: the linearised plant's stationary J)", fontsize=10)
    from pendulum_lqg.util.files import save_figure

    save_figure(fig, path, where="--out", what="figure", dpi=120)
    return slopes


def _exact_panels(gap_ax: Any, frac_ax: Any, rows: list[dict[str, Any]], suite: str) -> None:
    """The exact gap of every stabilising run against its logged steps (each seed, the median
    per budget, the fit of :func:`exact_slope` and a 1/N line through its middle), and the
    fraction of stabilising controllers against the budget."""
    judged = exact_values(rows, suite)
    if not judged:
        for ax in (gap_ax, frac_ax):
            ax.text(0.5, 0.5, f"{suite}: no exact gap\n(no single linear loop: e.g. a plant "
                    "randomised per episode)", ha="center", va="center", transform=ax.transAxes,
                    fontsize=8)
            ax.set_axis_off()
        return
    for seed in sorted({v["seed"] for v in judged}):
        pts = sorted((v["steps"], v["gap"]) for v in judged if v["seed"] == seed and v["stable"])
        gap_ax.plot(*np.array(pts).T, ".-", lw=0.5, alpha=0.5, label=f"seed {seed}")
    budgets, frac, med, _, _ = stabilising(rows, suite)
    steps = np.array([np.median([v["steps"] for v in judged if v["budget"] == b]) for b in budgets])
    ok = np.isfinite(med)
    gap_ax.plot(steps[ok], med[ok], "o", color="k", label="median over seeds (at median steps)")
    fit = exact_slope(rows, suite)
    if fit is not None:
        x = np.geomspace(steps[ok].min(), steps[ok].max(), 20)
        lo, hi = fit["ci"]
        gap_ax.plot(x, np.exp(fit["intercept"]) * x ** fit["slope"], color="C3",
                    label=f"fit: slope {fit['slope']:.2f} [95 %: {lo:.2f}, {hi:.2f}]")
        mid = math.sqrt(x[0] * x[-1])
        gap_ax.plot(x, np.exp(fit["intercept"]) * mid ** fit["slope"] * mid / x, color="C0",
                    ls=":", label="1/N")
    gap_ax.set(xscale="log", yscale="log", ylabel="exact gap J/J* − 1 (stationary)",
               xlabel="logged env steps (each run's own)")
    gap_ax.legend(fontsize=6)
    frac_ax.plot(budgets, frac, "s-", color="k")
    frac_ax.set(xscale="log", ylim=(-0.05, 1.05), xlabel="logged env-step budget",
                ylabel="fraction of seeds stabilising (ρ < 1)")


def table_lines(rows: list[dict[str, Any]]) -> list[str]:
    """The figure's numbers as a Markdown table: per suite and budget, the seeds' runs, the median
    logged steps, and the median [IQR] of the success rate, the failure-aware score and the gap."""
    out = ["| suite | budget | runs | logged steps (median) | success | failure-aware score "
           "| gap J/J* − 1 | exact gap (stationary) | stabilising |",
           "|---|---|---|---|---|---|---|---|---|"]

    def cell(med: float, lo: float, hi: float, fmt: str) -> str:
        return "–" if not np.isfinite(med) else f"{med:{fmt}} [{lo:{fmt}}, {hi:{fmt}}]"

    def exact_cell(med: float, lo: float, hi: float) -> str:
        return " [".join(f"{v:+.4f}" if np.isfinite(v) else "∞" for v in (med, lo)) + \
            (f", {hi:+.4f}]" if np.isfinite(hi) else ", ∞]")

    for suite in sorted({str(r["suite"]) for r in rows}, key=lambda s: (s not in SUITES, s)):
        stats = {k: summary(rows, suite, k) for k in ("success", "score", "gap", "logged_steps")}
        exact = stabilising(rows, suite)
        for i, budget in enumerate(stats["score"][0]):
            runs = sum(1 for r in rows if r["suite"] == suite and int(r["budget"]) == budget)
            j = np.flatnonzero(exact[0] == budget)
            judged = [v["stable"] for v in exact_values(rows, suite) if v["budget"] == budget]
            tail = ("– | –" if not j.size else
                    f"{exact_cell(exact[2][j[0]], exact[3][j[0]], exact[4][j[0]])} | "
                    f"{sum(judged)}/{len(judged)}")
            out.append(f"| {suite} | {int(budget):,} | {runs} | {stats['logged_steps'][1][i]:,.0f} | "
                       + " | ".join(cell(stats[k][1][i], stats[k][2][i], stats[k][3][i], f)
                                    for k, f in (("success", ".2f"), ("score", ".3f"),
                                                 ("gap", "+.4f"))) + f" | {tail} |")
    return out


def _int_list(text: str, what: str) -> list[int]:
    try:
        values = [int(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise ConfigError(f"--{what}: expected comma-separated integers, got {text!r}") from None
    if not values or min(values) < 0:
        raise ConfigError(f"--{what}: expected non-negative integers, got {text!r}")
    return values


def _suite_list(text: str) -> list[str]:
    """``--suites``: comma-separated names, each a suite that loads (checked before any work)."""
    from pendulum_lqg.errors import PendulumLQGError
    from pendulum_lqg.scoreboard.suites import load_suite

    names = [s.strip() for s in text.split(",") if s.strip()]
    if not names:
        raise ConfigError(f"--suites: expected comma-separated suite names, got {text!r}")
    for name in names:
        try:
            load_suite(name)
        except PendulumLQGError as exc:
            raise ConfigError(f"--suites: {exc}") from None
    return list(dict.fromkeys(names))


def _parser() -> argparse.ArgumentParser:
    from pendulum_lqg.util.scripts import ScriptParser

    ap = ScriptParser(prog="python -m pendulum_lqg.learn.price",
                      description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="identify and score every suite × seed × budget → CSV")
    r.add_argument("--out", type=Path, required=True, help="the CSV to write")
    r.add_argument("--suites", default=",".join(SUITES), help="comma-separated suite names")
    r.add_argument("--seeds", default=",".join(map(str, SEEDS)), help="comma-separated seeds")
    r.add_argument("--budgets", default=",".join(map(str, BUDGETS)),
                   help="comma-separated budgets [logged env steps]")
    how = r.add_mutually_exclusive_group()
    how.add_argument("--force", action="store_true", help="replace an existing --out")
    how.add_argument("--resume", action="store_true", help="keep --out's rows, add the missing")
    f = sub.add_parser("figure", help="the figure of a price CSV → PNG; prints the gap slopes")
    f.add_argument("csv", type=Path)
    f.add_argument("--out", type=Path, required=True, help="the PNG to write")
    f.add_argument("--curves", type=Path, default=Path("experiments/agents/models"),
                   help="folder of the deep-RL methods' METHOD-seedS-curve.csv")
    f.add_argument("--table", type=Path, default=None,
                   help="also write the printed table (Markdown) to this file")
    f.add_argument("--force", action="store_true", help="replace an existing --out or --table")
    return ap


def _main(args: argparse.Namespace) -> int:
    from pendulum_lqg.util.files import output_file

    out = output_file("--out", args.out)
    if out.exists() and not args.force and not getattr(args, "resume", False):
        raise ConfigError(f"--out: {out} exists; give --force to replace it"
                          + (" or --resume to continue it" if args.command == "run" else ""))
    if args.command == "run":
        budgets = _int_list(args.budgets, "budgets")
        if min(budgets) < 1:
            raise ConfigError(f"--budgets: expected positive integers, got {args.budgets!r}")
        if max(budgets) > MAX_BUDGET:
            raise ConfigError(f"--budgets: at most {MAX_BUDGET:,} logged steps a budget (the "
                              "identification keeps every logged step in memory), got "
                              f"{max(budgets):,}")
        suites = _suite_list(args.suites)
        seeds = _int_list(args.seeds, "seeds")
        count = len(set(suites)) * len(set(seeds)) * len(set(budgets))
        if count > MAX_ROWS:
            raise ConfigError(f"--budgets: at most {MAX_ROWS:,} runs (suites × seeds × budgets, "
                              f"each an identification and a score), got {count:,}")
        rows = run(out, suites=suites, seeds=seeds, budgets=budgets, resume=args.resume)
        print(f"wrote {out} ({len(rows)} rows)")
        return 0
    rows = read_rows(args.csv, where="csv")
    if not rows:
        raise ConfigError(f"csv: {args.csv}: no rows")
    table = None if args.table is None else output_file("--table", args.table)
    if table is not None and table.exists() and not args.force:
        raise ConfigError(f"--table: {table} exists; give --force to replace it")
    curves = read_curves(args.curves) if args.curves.is_dir() else {}
    lines = table_lines(rows)
    print("\n".join(lines))
    if table is not None:
        from pendulum_lqg.util.files import atomic_write

        atomic_write(table, "\n".join(lines) + "\n")
    for suite, (slope, _, count) in draw(rows, curves, out).items():
        print(f"{suite}: gap slope {slope:.2f} over {count} budgets (1/N: −1)")
        fit = exact_slope(rows, suite)
        if fit is not None:
            print(f"{suite}: exact gap slope {fit['slope']:.2f} [95 % over seeds: "
                  f"{fit['ci'][0]:.2f}, {fit['ci'][1]:.2f}] over {fit['runs']} stabilising runs "
                  f"of {fit['seeds']} seeds (1/N: −1)")
    print(f"wrote {out}")
    return 0


def main(argv: list[str] | None = None) -> int:
    from pendulum_lqg.util.scripts import script_status

    args = _parser().parse_args(argv)
    return script_status(lambda: _main(args))


if __name__ == "__main__":
    raise SystemExit(main())
