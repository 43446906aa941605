"""The report's figures and tables, one function per kind of study (grids, delays, mismatch, margins, ROA)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from pendulum_lqg.analysis.reading import (
    NUMBER,
    Figures,
    field,
    numbers,
    read_json,
    read_rows,
    records,
    save,
)
from pendulum_lqg.core.metrics import mean_se, wilson_interval
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.util.files import save_figure

SWEEP_KEYS = ("noise_scale", "control_period", "theta0", "pole_mass_scale", "pole_length_scale",
              "cart_mass_scale", "duration")


SERIES_KEYS = ("policy", "controller", "observer", "discretization", "estimate0")


LOG_KEYS = ("noise_scale",)


LABELS = {"noise_scale": "noise scale (× lecture std)", "control_period": "control period T [s]",
          "theta0": "θ₀ [rad]", "pole_mass_scale": "pole mass × nominal",
          "pole_length_scale": "pole length × nominal", "cart_mass_scale": "cart mass × nominal",
          "duration": "duration [s]"}


#: The cart-pole's estimation-error columns and labels (a matrix plant's: :func:`est_states`).
EST_STATES = (("rms_est_err_p", "p [m]"), ("rms_est_err_theta", "θ [rad]"),
              ("rms_est_err_p_dot", "ṗ [m/s]"), ("rms_est_err_theta_dot", "θ̇ [rad/s]"))


def est_states(rows: list[dict[str, Any]]) -> tuple[tuple[str, str], ...]:
    """The estimation-error columns of these episode rows with their labels: the columns the
    rows hold (``rms_est_err_<state>``, the layout's state names), labelled as the cart-pole's
    where they are its, else by the state's name."""
    labels = dict(EST_STATES)
    cols = [k for k in (rows[0] if rows else {}) if k.startswith("rms_est_err_")]
    return tuple((c, labels.get(c, c.removeprefix("rms_est_err_"))) for c in cols)


def _has_estimate(rows: list[dict[str, Any]], columns: tuple[tuple[str, str], ...]) -> bool:
    """Whether any row has a finite, positive estimation error (a true-state policy has none)."""
    values = np.array([float(r[c]) for r in rows for c, _ in columns])
    return bool(np.any(np.isfinite(values) & (values > 0)))


def _group(rows: list[dict[str, Any]], keys: list[str]) -> dict[tuple, list[dict[str, Any]]]:
    out: dict[tuple, list[dict[str, Any]]] = {}
    for r in rows:
        out.setdefault(tuple(r[k] for k in keys), []).append(r)
    return out


def _success_curve(rows: list[dict[str, Any]], x: str) -> tuple[np.ndarray, ...]:
    by_x = _group(rows, [x])
    xs = np.array(sorted(k[0] for k in by_x), dtype=float)
    rate, lo, hi = [], [], []
    for xv in xs:
        grp = by_x[(xv,)] if (xv,) in by_x else by_x[(int(xv),)]
        s = sum(bool(r["success"]) for r in grp)
        a, b = wilson_interval(s, len(grp))
        rate.append(s / len(grp))
        lo.append(a)
        hi.append(b)
    return xs, np.array(rate), np.array(lo), np.array(hi)


def _metric_curve(rows: list[dict[str, Any]], x: str, metric: str, *, successes_only: bool,
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    by_x = _group(rows, [x])
    xs = np.array(sorted(k[0] for k in by_x), dtype=float)
    mean, se = [], []
    for xv in xs:
        grp = by_x.get((xv,)) or by_x[(int(xv),)]
        m, s = mean_se(np.array([float(r[metric]) for r in grp
                                 if not successes_only or bool(r["success"])]))
        mean.append(m)
        se.append(s)            # nan for one sample (no error bar), as in summary.json
    return xs, np.array(mean), np.array(se)


def _log_x(ax: Any, xs: list[float] | np.ndarray) -> None:
    """A log x axis that keeps a value of 0 visible (symlog, linear below the smallest positive
    value), so noise-free points sit at the left edge instead of vanishing."""
    xs = np.asarray(xs, dtype=float)
    positive = xs[xs > 0]
    if positive.size and np.all(xs > 0):
        ax.set_xscale("log")
    else:
        ax.set_xscale("symlog", linthresh=float(positive.min()) if positive.size else 1e-3,
                      linscale=0.5)


def _legend_outside(fig: Any, ax: Any) -> None:
    """The legend to the right of the axes, so the curves stay readable."""
    handles, labels = ax.get_legend_handles_labels()
    if handles:
        fig.legend(handles, labels, loc="center left", bbox_to_anchor=(1.0, 0.5), frameon=False)


#: Markers of the series, in order (a series past the last one takes a dashed line as well).
MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*")


@dataclass(frozen=True)
class _Sweep:
    """A grid's rows as the figures see them: curves against the sweep key ``x``, one panel per
    value of the other swept keys (``facets``), one curve per series."""

    rows: list[dict[str, Any]]
    x: str
    facets: list[str]
    series: list[str]

    @property
    def facet_values(self) -> list[tuple]:
        return sorted({tuple(r[k] for k in self.facets) for r in self.rows})

    def panel_rows(self, values: tuple) -> list[dict[str, Any]]:
        return [r for r in self.rows if tuple(r[k] for k in self.facets) == values]

    def panels(self, mk: Figures, **kw: Any) -> tuple[Any, Any]:
        """A figure with one axes per facet value, two columns at most; the spare ones hidden."""
        n = len(self.facet_values)
        ncol = min(n, 2)
        nrow = -(-n // ncol)
        fig, axes = mk.subplots(nrow, ncol, figsize=(6.0 * ncol, 4.2 * nrow), squeeze=False, **kw)
        for ax in list(axes.flat)[n:]:
            ax.set_visible(False)
        return fig, axes

    def title(self, values: tuple) -> str:
        return ", ".join(f"{k} = {v}" for k, v in zip(self.facets, values, strict=True))


def grid_figures(folder: Path, out: Path, name: str, src: dict[str, Any], mk: Figures,
                  ) -> list[tuple[str, str]]:
    """The figures of a grid's results folder: mismatch and delay grids have their own; a grid
    that sweeps a numeric key gets the success rate against it (and the cost against the control
    period, the estimation error against the noise scale); every grid its cost distributions."""
    rows = read_rows(folder)
    grid = src.get("grid", {})
    varying = [k for k, v in grid.items() if isinstance(v, list) and len(v) > 1]
    sweeps = [k for k in SWEEP_KEYS if k in varying]
    series = [k for k in SERIES_KEYS if k in varying] or ["config"]
    if {"pole_mass_scale", "pole_length_scale"} <= set(sweeps):
        return _mismatch_figures(rows, out, name, series, mk)
    if "delay" in grid and "delay_kind" in grid:
        return _delay_figures(rows, out, name, series, mk)
    if not sweeps:
        return [("cost distributions", _cost_boxes(rows, out, name, series, None, mk))]
    x = max(sweeps, key=lambda k: len(grid[k]))
    sweep = _Sweep(rows, x, [k for k in sweeps if k != x], series)
    figs = [(f"success rate vs {x}", _success_figure(sweep, out, name, mk))]
    if x == "control_period":
        figs.append(("cost vs control period", _cost_vs_period_figure(sweep, out, name, mk)))
    if _has_estimate(rows, est_states(rows)) and x == "noise_scale":
        figs.append(("estimation error per state", _estimation_error_figure(sweep, out, name, mk)))
    nominal = 1.0 if x == "noise_scale" else None
    figs.append(("cost distributions", _cost_boxes(rows, out, name, series + sweep.facets,
                                                   (x, nominal), mk)))
    return figs


def _success_figure(sweep: _Sweep, out: Path, name: str, mk: Figures) -> str:
    """Success rate against the sweep key with its 95 % Wilson band, a panel per facet value."""
    x = sweep.x
    fig, axes = sweep.panels(mk, sharey=True)
    for ax, fv in zip(axes.flat, sweep.facet_values, strict=False):
        sub = sweep.panel_rows(fv)
        for i, (key, grp) in enumerate(sorted(_group(sub, sweep.series).items())):
            xs, rate, lo, hi = _success_curve(grp, x)
            line, = ax.plot(xs, rate, marker=MARKERS[i % len(MARKERS)], ms=5,
                            ls=["-", "--", "-.", ":"][i // len(MARKERS) % 4] if i >= 4 else "-",
                            label=" ".join(map(str, key)))
            ax.fill_between(xs, lo, hi, color=line.get_color(), alpha=0.08, lw=0)
        ax.set_xlabel(LABELS.get(x, x))
        ax.set_ylim(-0.03, 1.03)
        if x in LOG_KEYS:
            _log_x(ax, [float(r[x]) for r in sub])
        if sweep.facets:
            ax.set_title(sweep.title(fv))
    return _finish_panels(fig, axes, "success rate\n(95 % Wilson band)",
                          f"{name}: success rate vs {x}", out, f"{name}_success_vs_{x}.png")


def _cost_vs_period_figure(sweep: _Sweep, out: Path, name: str, mk: Figures) -> str:
    """Mean cost of the successful episodes against the control period, a panel per facet."""
    x = sweep.x
    fig, axes = sweep.panels(mk)
    for ax, fv in zip(axes.flat, sweep.facet_values, strict=False):
        for i, (key, grp) in enumerate(sorted(_group(sweep.panel_rows(fv),
                                                     sweep.series).items())):
            xs, m, _ = _metric_curve(grp, x, "cost", successes_only=True)
            ax.plot(xs, m, marker=MARKERS[i % len(MARKERS)], ms=5, label=" ".join(map(str, key)))
        ax.set_yscale("log")
        ax.set_xlabel(LABELS[x])
        ax.set_title(sweep.title(fv))
    return _finish_panels(fig, axes, "mean cost J\n(successful episodes)",
                          f"{name}: cost vs control period", out, f"{name}_cost_vs_T.png")


def _finish_panels(fig: Any, axes: Any, ylabel: str, title: str, out: Path, file: str) -> str:
    """The y label on each row's first panel, the legend outside, the title; saved as ``file``."""
    for row in axes:
        row[0].set_ylabel(ylabel)
    _legend_outside(fig, axes.flat[0])
    fig.suptitle(title)
    return save(fig, out, file)


def _estimation_error_figure(sweep: _Sweep, out: Path, name: str, mk: Figures) -> str:
    """RMS estimation error of each state against the noise scale (all episodes, mean ± SE)."""
    x, rows = sweep.x, sweep.rows
    columns = est_states(rows)
    ncol = min(len(columns), 2)
    nrow = -(-len(columns) // ncol)
    fig, axes = mk.subplots(nrow, ncol, figsize=(6.0 * ncol, 4.0 * nrow), squeeze=False)
    for ax in list(axes.flat)[len(columns):]:
        ax.set_visible(False)
    for ax, (metric, label) in zip(axes.flat, columns, strict=False):
        for key, grp in sorted(_group(rows, sweep.series).items()):
            xs, m, se = _metric_curve(grp, x, metric, successes_only=False)
            if not np.any(m > 0):
                continue          # true-state policies have no estimation error
            ax.errorbar(xs, m, yerr=se, marker="o", ms=4, capsize=2,
                        label=" ".join(map(str, key)))
        _log_x(ax, [float(r[x]) for r in rows])
        ax.set_yscale("log")
        ax.set_xlabel(LABELS[x])
        ax.set_title(f"RMS estimation error, {label}")
    _legend_outside(fig, axes.flat[0])
    fig.suptitle(f"{name}: estimation error per state (all episodes, mean ± SE)")
    return save(fig, out, f"{name}_estimation_error.png")


#: The success rate a policy must reach to "tolerate" a delay.
TOLERANCE_LEVEL = 0.95


def tolerated_delays(rows: list[dict[str, Any]], series: list[str], *,
                     level: float = TOLERANCE_LEVEL) -> list[dict[str, Any]]:
    """The largest delay each policy tolerates, per kind of delay: the largest grid value ``d``
    with a success rate ≥ ``level`` at ``d`` and at every smaller delay of the grid (``nan`` if
    not even the smallest), with the success and its 95 % Wilson interval there."""
    out = []
    for (kind, *key), grp in sorted(_group(rows, ["delay_kind", *series]).items()):
        xs, rate, lo, hi = _success_curve(grp, "delay")
        ok = np.cumprod(rate >= level - 1e-12).astype(bool)
        i = int(np.nonzero(ok)[0][-1]) if ok.any() else None
        out.append({"policy": " ".join(map(str, key)), "delay_kind": kind,
                    "tolerated_delay": float(xs[i]) if i is not None else float("nan"),
                    "success": float(rate[i]) if i is not None else float("nan"),
                    "ci95": [float(lo[i]), float(hi[i])] if i is not None else [],
                    "next_delay": float(xs[i + 1]) if i is not None and i + 1 < xs.size
                    else float("nan"),
                    "next_success": float(rate[i + 1]) if i is not None and i + 1 < xs.size
                    else float("nan")})
    return out


def _delay_figures(rows: list[dict[str, Any]], out: Path, name: str, series: list[str],
                   mk: Figures) -> list[tuple[str, str]]:
    """Success (Wilson bands) and mean J vs delay, a column per kind of delay."""
    kinds = sorted({str(r["delay_kind"]) for r in rows}, reverse=True)   # measurement first
    fig, axes = mk.subplots(2, len(kinds), figsize=(5.4 * len(kinds), 6.6), squeeze=False,
                             sharex=True)
    for col, kind in enumerate(kinds):
        sub = [r for r in rows if r["delay_kind"] == kind]
        for key, grp in sorted(_group(sub, series).items()):
            xs, rate, lo, hi = _success_curve(grp, "delay")
            label = " ".join(map(str, key))
            line, = axes[0][col].plot(1e3 * xs, rate, marker="o", ms=3, label=label)
            axes[0][col].fill_between(1e3 * xs, lo, hi, color=line.get_color(), alpha=0.12, lw=0)
            xs, m, se = _metric_curve(grp, "delay", "cost", successes_only=True)
            axes[1][col].errorbar(1e3 * xs, m, yerr=se, marker="o", ms=3, capsize=2,
                                  color=line.get_color(), label=label)
        axes[0][col].axhline(TOLERANCE_LEVEL, color="k", ls=":", lw=0.8)
        axes[0][col].set_ylim(-0.03, 1.03)
        axes[0][col].set_title(f"{kind} delay")
        axes[1][col].set_yscale("log")
        axes[1][col].set_xlabel(f"{kind} delay [ms]")
    axes[0][0].set_ylabel("success rate (95 % Wilson band)")
    axes[1][0].set_ylabel("mean J of successful episodes (± SE)")
    axes[0][-1].legend(loc="lower left")
    fig.suptitle(f"{name}: success and cost vs delay (dotted: {TOLERANCE_LEVEL:.0%})")
    figs = [("success and cost vs delay", save(fig, out, f"{name}_success_vs_delay.png"))]
    figs.append(("cost distributions", _cost_boxes(rows, out, name, series, ("delay", 0.0), mk)))
    return figs


def delay_table(rows: list[dict[str, Any]], series: list[str]) -> list[str]:
    """Markdown table of :func:`tolerated_delays`."""
    lines = [f"Largest delay tolerated at ≥ {TOLERANCE_LEVEL:.0%} success (at that delay and every "
             "smaller one of the grid; 95 % Wilson interval):", "",
             "| policy | delay | largest delay [ms] | success there | next delay: success |",
             "|---|---|---|---|---|"]
    for t in tolerated_delays(rows, series):
        d = t["tolerated_delay"]
        if d != d:
            lines.append(f"| {t['policy']} | {t['delay_kind']} | none | – | – |")
            continue
        lo, hi = t["ci95"]
        nxt = ("–" if t["next_delay"] != t["next_delay"]
               else f"{1e3 * float(t['next_delay']):.0f} ms: {float(t['next_success']):.1%}")
        lines.append(f"| {t['policy']} | {t['delay_kind']} | {1e3 * float(d):.0f} | "
                     f"{float(t['success']):.1%} [{lo:.1%}, {hi:.1%}] | {nxt} |")
    return [*lines, ""]


#: The fewest successful episodes a cost box is drawn from: a box of fewer (2 of 200 survivors,
#: say) would show quartiles of nothing and look like the cheapest policy; its points are drawn
#: instead, and every box says its n (docs/analysis.md).
MIN_BOX_EPISODES = 10


def _cost_boxes(rows: list[dict[str, Any]], out: Path, name: str, series: list[str],
                at: tuple[str, float | None] | None, mk: Figures) -> str:
    """Box plots of the cost of successful episodes per series (per x value when there are few)."""
    groups = _group(rows, series)
    if at is not None:
        xk, xv = at
        xs = sorted({float(r[xk]) for r in rows})
        xs = ([xv] if xv is not None and xv in xs
              else xs if len(xs) <= 4 else [xs[0], xs[len(xs) // 2], xs[-1]])
    else:
        xk, xs = "", [None]  # type: ignore[list-item]   # one panel, no grid value
    fig, axes = mk.subplots(1, len(xs), figsize=(2.0 + 4.2 * len(xs), 1.2 + 0.36 * len(groups)),
                             squeeze=False, sharey=True)
    from matplotlib import ticker

    names = [k for k in series if k != "config"]
    for ax, xv in zip(axes[0], xs, strict=True):     # horizontal boxes: one readable line each
        data, labels = [], []
        for key, grp in sorted(groups.items(), reverse=True):
            c = [float(r["cost"]) for r in grp
                 if bool(r["success"]) and (xv is None or float(r[xk]) == xv)]
            data.append(c if c else [np.nan])
            labels.append(" ".join(f"{n} {v}" if n not in ("policy", "discretization") else str(v)
                                   for n, v in zip(names or series, key, strict=False)))
        boxed = [c if len(c) >= MIN_BOX_EPISODES else [np.nan] for c in data]
        ax.boxplot(boxed, orientation="horizontal", showfliers=True, flierprops={"ms": 2})
        for i, c in enumerate(data, start=1):
            n = sum(1 for v in c if v == v)
            if 0 < n < MIN_BOX_EPISODES:          # too few for quartiles: the points themselves
                ax.plot(c, [i] * len(c), ls="none", marker="x", ms=5, color="C3")
            ax.text(1.01, i, f"n = {n}" + ("" if n >= MIN_BOX_EPISODES or n == 0
                                           else f" < {MIN_BOX_EPISODES}: no box"),
                    transform=ax.get_yaxis_transform(), ha="left", va="center", fontsize=8,
                    clip_on=False)
        ax.set_yticks(range(1, len(labels) + 1), labels)
        ax.set_xscale("log")
        ax.xaxis.set_major_locator(ticker.LogLocator(subs=(1.0, 2.0, 5.0)))
        ax.xaxis.set_major_formatter(ticker.FuncFormatter(lambda v, _: f"{v:g}"))
        ax.xaxis.set_minor_formatter(ticker.NullFormatter())
        ax.set_xlabel("cost J (successful episodes)")
        if xv is not None:
            ax.set_title(f"{LABELS.get(xk, xk)} = {xv:g}")
    fig.suptitle(f"{name}: cost distributions (n successful episodes; a box needs "
                 f"n ≥ {MIN_BOX_EPISODES}, fewer are drawn as points)")
    return save(fig, out, f"{name}_cost_distribution.png")


def _mismatch_figures(rows: list[dict[str, Any]], out: Path, name: str, series: list[str],
                      mk: Figures) -> list[tuple[str, str]]:
    fig, axes = mk.subplots(2, 2, figsize=(10, 7))
    for col, (x, other) in enumerate((("pole_mass_scale", "pole_length_scale"),
                                      ("pole_length_scale", "pole_mass_scale"))):
        sub = [r for r in rows if float(r[other]) == 1.0]
        for key, grp in sorted(_group(sub, series).items()):
            xs, rate, lo, hi = _success_curve(grp, x)
            line, = axes[0][col].plot(xs, rate, marker="o", ms=3, label=" ".join(map(str, key)))
            axes[0][col].fill_between(xs, lo, hi, color=line.get_color(), alpha=0.08, lw=0)
            xs, m, se = _metric_curve(grp, x, "cost", successes_only=True)
            axes[1][col].errorbar(xs, m, yerr=se, marker="o", ms=3, capsize=2,
                                  color=line.get_color())
        for ax in axes[:, col]:
            ax.set_xscale("log", base=2)
            ax.set_xticks(xs, [f"{v:g}" for v in xs])
            ax.set_xlabel(f"{LABELS[x]} ({other} = 1)")
        axes[0][col].set_ylim(-0.03, 1.03)
        axes[1][col].set_yscale("log")
    axes[0][0].set_ylabel("success rate (95 % Wilson band)")
    axes[1][0].set_ylabel("mean cost J (successful episodes)")
    axes[0][1].legend(loc="best")
    fig.suptitle(f"{name}: the simulated pole differs from the design model")
    figs = [("mismatch curves", save(fig, out, f"{name}_curves.png"))]

    groups = sorted(_group(rows, series).items())
    ms = sorted({float(r["pole_mass_scale"]) for r in rows})
    ls = sorted({float(r["pole_length_scale"]) for r in rows})
    ncol = min(len(groups), 2)
    nrow = -(-len(groups) // ncol)
    fig, axes = mk.subplots(nrow, ncol, figsize=(5.2 * ncol, 4.4 * nrow), squeeze=False)
    for ax, (key, grp) in zip(axes.flat, groups, strict=False):
        Z = np.full((len(ls), len(ms)), np.nan)
        for (m, ln), cell in _group(grp, ["pole_mass_scale", "pole_length_scale"]).items():
            Z[ls.index(float(ln)), ms.index(float(m))] = np.mean([bool(r["success"]) for r in cell])
        im = ax.imshow(Z, origin="lower", vmin=0, vmax=1, cmap="RdYlGn", aspect="auto")
        ax.set_xticks(range(len(ms)), [f"{v:g}" for v in ms])
        ax.set_yticks(range(len(ls)), [f"{v:g}" for v in ls])
        ax.set_xlabel("pole mass × nominal")
        ax.set_ylabel("pole length × nominal")
        ax.set_title(" ".join(map(str, key)))
        ax.grid(False)
        for i in range(len(ls)):
            for j in range(len(ms)):
                ax.text(j, i, f"{Z[i, j]:.0%}", ha="center", va="center", fontsize=9)
    for ax in list(axes.flat)[len(groups):]:
        ax.set_visible(False)
    fig.subplots_adjust(top=0.9, wspace=0.45, hspace=0.4)
    fig.colorbar(im, ax=axes.ravel().tolist(), shrink=0.8, label="success rate")
    fig.suptitle(f"{name}: success over pole mass × length")
    save_figure(fig, out / f"{name}_success_grid.png", where="report", what="figure",
                bbox_inches="tight")
    figs.append(("success over pole mass × length", f"{name}_success_grid.png"))
    return figs


# ---- margins -------------------------------------------------------------------------------------
def margins_figures(folder: Path, out: Path, name: str, mk: Figures) -> list[tuple[str, str]]:
    """The margins study's figures: Nyquist plots, loop transfer recovery, and the sampled loops'
    margins against the control period."""
    from pendulum_lqg.bench.results import read_csv

    figs = [("Nyquist: LQ vs LQG", _nyquist_figure(read_csv(folder / "nyquist.csv"), out, name,
                                                    mk))]
    ltr = read_csv(folder / "ltr.csv")
    summ_path = folder / "summary.json"
    loops_all = records(read_json(summ_path), "loops", summ_path, {
        "loop": str, "phase_margin_deg": NUMBER, "min_return_difference": NUMBER,
        "disk_margin": NUMBER, "control_period": NUMBER})
    lq = next((r for r in loops_all if r["loop"].startswith("LQ (")), None)
    if lq is None:
        raise ConfigError(f"results: {summ_path}: key 'loops' has no 'LQ (…)' loop")
    figs.append(("loop transfer recovery", _ltr_figure(ltr, lq, out, name, mk)))
    loops: list[dict[str, Any]] = [r for r in loops_all if float(r["control_period"]) > 0]
    for i, r in enumerate(loops):
        field(r, "policy", str, summ_path, where=f"loops[{i}].")
        field(r, "closed_loop_stable", bool, summ_path, where=f"loops[{i}].")
        field(r, "discretization", str, summ_path, default="", where=f"loops[{i}].")
    if loops:
        figs.append(("sampled-loop margins vs T", _sampled_margins_figure(loops, out, name, mk)))
    return figs


def _nyquist_figure(nyq: list[dict[str, Any]], out: Path, name: str, mk: Figures) -> str:
    """Nyquist plots at the plant input, continuous loops beside sampled ones, with the unit
    circle about −1."""
    curves: dict[str, list[tuple[float, float]]] = {}
    for r in nyq:
        curves.setdefault(str(r["loop"]), []).append((float(r["re"]), float(r["im"])))
    t = np.linspace(0, 2 * np.pi, 400)
    fig, axes = mk.subplots(1, 2, figsize=(11, 5))
    cont = [k for k in curves if "continuous" in k or k.startswith("LTR")]
    disc = [k for k in curves if k not in cont]
    for ax, keys, title in ((axes[0], cont, "continuous loops (LTR: W = q²BBᵀ)"),
                            (axes[1], disc, "sampled loops at T (plant = exact ZOH)")):
        ax.plot(-1 + np.cos(t), np.sin(t), "k--", lw=1, label="abs(1 + L) = 1")
        ax.plot([-1], [0], "k+", ms=10)
        for k in keys:
            z = np.array(curves[k])
            style = {"lw": 2.2} if k.startswith("LQ (") else {"lw": 1.2}
            line, = ax.plot(z[:, 0], z[:, 1], label=k, **style)
            ax.plot(z[:, 0], -z[:, 1], color=line.get_color(), lw=0.6, alpha=0.5)
        ax.set_xlim(-4, 2)
        ax.set_ylim(-3, 3)
        ax.set_aspect("equal")
        ax.set_xlabel("Re L")
        ax.set_ylabel("Im L")
        ax.set_title(title)
        ax.legend(loc="lower left", fontsize=7)
    fig.suptitle(f"{name}: Nyquist plots at the plant input (ω > 0 bold, mirror thin)")
    return save(fig, out, f"{name}_nyquist.png")


def _ltr_figure(ltr: list[dict[str, Any]], lq: dict[str, Any], out: Path, name: str,
                mk: Figures) -> str:
    """Loop transfer recovery: phase margin, smallest return difference and disk margin against
    q, per measurement, beside the LQ loop's values."""
    fig, axes = mk.subplots(1, 3, figsize=(13, 3.6))
    keys = ("phase_margin_deg", "min_return_difference", "disk_margin")
    for meas in sorted({str(r["measurement"]) for r in ltr}):
        sub = [r for r in ltr if r["measurement"] == meas]
        q = np.array([float(r["q"]) for r in sub])
        for ax, key in zip(axes, keys, strict=True):
            ax.plot(q, [float(r[key]) for r in sub], marker="o", ms=3, label=meas)
    for ax, key, title in zip(axes, keys,
                              ("phase margin [deg]", "min abs(1 + L(jω))", "disk margin α"),
                              strict=True):
        ax.axhline(float(lq[key]), color="k", ls="--", lw=1, label="LQ loop")
        ax.set_xscale("log")
        ax.set_xlabel("q (W = q²BBᵀ)")
        ax.set_title(title)
    axes[1].set_yscale("log")
    axes[0].legend(loc="best")
    fig.suptitle(f"{name}: loop transfer recovery")
    return save(fig, out, f"{name}_ltr.png")


def _sampled_margins_figure(loops: list[dict[str, Any]], out: Path, name: str,
                            mk: Figures) -> str:
    """Phase and disk margins of the sampled loops against the control period, a curve per
    policy and discretisation (blank where the loop is unstable)."""
    fig, axes = mk.subplots(1, 2, figsize=(10, 3.6))

    def keyf(r: dict[str, Any]) -> tuple[str, str]:
        return str(r["policy"]), str(r.get("discretization", ""))

    for group in sorted({keyf(r) for r in loops}):
        members = sorted((r for r in loops if keyf(r) == group),
                         key=lambda r: float(r["control_period"]))
        T = [float(r["control_period"]) for r in members]
        for ax, m in zip(axes, ("phase_margin_deg", "disk_margin"), strict=True):
            vals = [float(r[m]) if r["closed_loop_stable"] else np.nan for r in members]
            ax.plot(T, vals, marker="o", ms=3, label=" ".join(group))
    for ax, title in zip(axes, ("phase margin [deg] (blank: unstable)", "disk margin α"),
                         strict=True):
        ax.set_xlabel("control period T [s]")
        ax.set_title(title)
    axes[1].legend(loc="best", fontsize=7)
    fig.suptitle(f"{name}: margins of the sampled loops")
    return save(fig, out, f"{name}_sampled.png")


# ---- region of attraction ------------------------------------------------------------------------
def roa_figures(folder: Path, out: Path, name: str, mk: Figures) -> list[tuple[str, str]]:
    summ_path = folder / "summary.json"
    summ = read_json(summ_path)
    prm = field(summ, "params", dict, summ_path)
    numbers(prm, "map_theta", summ_path, 3, "params.")
    numbers(prm, "map_theta_dot", summ_path, 3, "params.")
    field(prm, "level", NUMBER, summ_path, where="params.")
    field(summ, "episodes_per_batch", int, summ_path)
    cfgs = records(summ, "configurations", summ_path, {
        "index": int, "policy": str, "estimate0": str, "theta_star": NUMBER})
    policies = list(dict.fromkeys(c["policy"] for c in cfgs))
    est = list(dict.fromkeys(c["estimate0"] for c in cfgs))
    t_lo, t_hi, _ = prm["map_theta"]
    d_lo, d_hi, _ = prm["map_theta_dot"]
    fig, axes = mk.subplots(len(est), len(policies), figsize=(3.0 * len(policies),
                                                              2.8 * len(est)), squeeze=False)
    from pendulum_lqg.bench.results import read_csv

    cells = _group(read_csv(folder / "roa_map.csv"), ["config"])
    for c in cfgs:
        ax = axes[est.index(c["estimate0"])][policies.index(c["policy"])]
        mine = cells.get((c["index"],), [])
        if not mine:
            ax.set_visible(False)
            continue
        ths = sorted({float(r["theta0"]) for r in mine})
        tds = sorted({float(r["theta_dot0"]) for r in mine})
        Z = np.full((len(tds), len(ths)), np.nan)
        for r in mine:
            Z[tds.index(float(r["theta_dot0"])), ths.index(float(r["theta0"]))] = (
                (bool(r["survived"]) + bool(r["recovered"])) / 2)
        ax.imshow(Z, origin="lower", extent=(t_lo, t_hi, d_lo, d_hi),
                  aspect="auto", cmap="RdYlGn", vmin=0, vmax=1)
        star = float(c["theta_star"])
        for s in (-star, star):
            ax.axvline(s, color="k", ls="--", lw=0.8)
        ax.grid(False)
        ax.set_title(f"{c['policy']}, x̂₀ = {'0' if c['estimate0'] == 'zero' else 'x₀'}",
                     fontsize=8)
        ax.set_xlabel("θ₀ [rad]")
        ax.set_ylabel("θ̇₀ [rad/s]")
    fig.suptitle(f"{name}: noise-free recovery (green recovered, yellow survived unsettled, red "
                 f"failed); dashed: noisy θ* at ≥ {prm['level']:.0%}")
    figs = [("region of attraction maps", save(fig, out, f"{name}_maps.png"))]

    fig, ax = mk.subplots(figsize=(6.5, 3.4))
    width = 0.8 / max(1, len(est))
    for j, e in enumerate(est):
        vals = [next((float(c["theta_star"]) for c in cfgs
                      if c["policy"] == p and c["estimate0"] == e), np.nan) for p in policies]
        ax.bar(np.arange(len(policies)) + j * width, vals, width,
               label=f"x̂₀ = {'0' if e == 'zero' else 'x₀'}")
    ax.set_xticks(np.arange(len(policies)) + width * (len(est) - 1) / 2, policies, fontsize=8)
    ax.set_ylabel("largest θ₀ [rad]")
    ax.legend()
    ax.set_title(f"{name}: largest θ₀ with ≥ {prm['level']:.0%} of "
                 f"{summ['episodes_per_batch']} noisy episodes surviving")
    figs.append(("largest recoverable angle", save(fig, out, f"{name}_theta_star.png")))
    return figs
