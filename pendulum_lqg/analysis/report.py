"""``pendulum-lqg report RESULTS…``: a Markdown report with PNG figures, made from results folders.

The report is made from the data files only (``spec.json``, ``episodes.csv``, ``summary.json`` and
the studies' CSV files), never by re-running anything. What a folder gets depends on what it holds:

=====================  =========================================================================
results of             figures
=====================  =========================================================================
a grid over            success rate vs that variable with 95 % Wilson bands (one line per policy,
``noise_scale`` /      panels per value of any other swept variable); RMS estimation error per
``control_period`` /   state; cost distributions (successful episodes)
``theta0``
a mismatch grid        success and mean cost along pole mass and pole length (the other at ×1),
(``pole_*_scale``)     and the success over the whole (mass, length) grid per policy
a delay grid           success rate (95 % Wilson bands) and mean J vs the delay, one panel per
(``delay`` +           kind of delay, one line per policy; the largest delay each policy
``delay_kind``)        tolerates at ≥ 95 % success (:func:`tolerated_delays`)
``study = "margins"``  Nyquist plots of LQ vs LQG (and LTR) loops with the circle abs(1 + L) = 1;
                       LTR margins vs q; sampled-loop margins vs T
``study = "roa"``      (reads ``roa_map.csv``) noise-free recovery maps over (θ₀, θ̇₀); largest θ₀ per policy
=====================  =========================================================================

matplotlib is imported only when a report is made; the figures use its object API
(:class:`matplotlib.figure.Figure`, no ``pyplot``), drawn in a ``rc_context`` of the report's style, so
making a report changes no backend and no global style.
"""

from __future__ import annotations

from pathlib import Path

from pendulum_lqg.analysis.figures import SERIES_KEYS, delay_table, grid_figures, margins_figures, roa_figures
from pendulum_lqg.analysis.reading import REPORT_STYLE, Figures, field, read_json, read_rows
from pendulum_lqg.bench.results import check_name
from pendulum_lqg.errors import ConfigError


def _results_folders(paths: list[Path], out: Path) -> list[Path]:
    found: list[Path] = []
    for p in paths:
        if (p / "spec.json").is_file():
            found.append(p)
            continue
        subs = sorted(q for q in p.glob("*/spec.json")) if p.is_dir() else []
        subs = [q.parent for q in subs if q.parent.resolve() != out.resolve()]
        if not subs:
            raise ConfigError(f"results: {p} is not a results folder (no spec.json) and holds none")
        found += subs
    return found


def make_report(paths: list[Path], out: Path) -> Path:
    """Write ``out/report.md`` and ``out/*.png`` for the results folders ``paths``.

    Each path is a results folder (with ``spec.json``) or a folder of them. Returns the report path.
    """
    folders = _results_folders([Path(p) for p in paths], Path(out))
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    import matplotlib


    sections = ["# pendulum_lqg report", "",
                "Made by `pendulum-lqg report` from the data files of: "
                + ", ".join(f"`{f}`" for f in folders) + ".", ""]
    with matplotlib.rc_context(REPORT_STYLE):
        for folder in folders:
            sections += _folder_section(folder, out, Figures())
    from pendulum_lqg.bench.results import atomic_write

    report = out / "report.md"
    atomic_write(report, "\n".join(sections))
    return report


def _folder_section(folder: Path, out: Path, mk: Figures) -> list[str]:
    """The report's section of one results folder: its figures (written to ``out``) and tables."""
    spec_path = folder / "spec.json"
    spec = read_json(spec_path)
    src = field(spec, "spec", dict, spec_path, default={})
    name = field(spec, "name", str, spec_path, default=folder.name)
    try:
        check_name(name)
    except ConfigError:
        raise ConfigError(f"results: {spec_path}: key 'name': expected a plain name, got "
                          f"{name!r}") from None
    field(src, "description", str, spec_path, default="", where="spec.")
    field(src, "seed", int, spec_path, default=0, where="spec.")
    field(src, "study", str, spec_path, default=None, where="spec.")
    grid = field(src, "grid", dict, spec_path, default={}, where="spec.")
    for key in grid:
        field(grid, key, list, spec_path, where="spec.grid.")
    sections = [f"## {name}", "", str(src.get("description", "")), "",
                f"Seed {src.get('seed', 0)}; data: `{folder}`.", ""]
    if not (folder / "summary.md").is_file():
        return [*sections, "*(incomplete: no summary.md — finish the run with `--resume`)*", ""]
    study = src.get("study")
    if study == "margins":
        figs = margins_figures(folder, out, name, mk)
    elif study == "roa":
        figs = roa_figures(folder, out, name, mk)
    else:
        figs = grid_figures(folder, out, name, src, mk)
    for title, fname in figs:
        sections += [f"### {title}", "", f"![{title}]({fname})", ""]
    grid = src.get("grid", {})
    if study is None and "delay" in grid and "delay_kind" in grid:
        varying = [k for k in SERIES_KEYS if len(grid.get(k, [])) > 1] or ["config"]
        sections += delay_table(read_rows(folder), varying)
    sections += ["<details><summary>table</summary>", "",
                 (folder / "summary.md").read_text(), "</details>", ""]
    return sections
