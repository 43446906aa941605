"""Reading a results folder for the report: JSON and CSV files checked field by field, one-line errors."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from pendulum_lqg.errors import ConfigError

if TYPE_CHECKING:
    from matplotlib.typing import RcKeyType

MISSING = object()


NUMBER = (int, float)


def kind_name(kind: type | tuple[type, ...]) -> str:
    names = {dict: "an object", list: "a list", str: "a string", int: "an integer",
             float: "a number", bool: "true/false"}
    kinds = kind if isinstance(kind, tuple) else (kind,)
    if set(kinds) == {int, float}:
        return "a number"
    return " or ".join(names.get(k, k.__name__) for k in kinds)


def read_json(path: Path) -> dict[str, Any]:
    """A results JSON file as a dict, read through :func:`pendulum_lqg.boundary.read_json` (a
    regular file, size and nesting bounded); a missing, non-UTF-8, invalid or non-object file is
    one :class:`ConfigError` line naming the file."""
    from pendulum_lqg.boundary import read_json as read_boundary_json

    data = read_boundary_json(path, where="results")
    if not isinstance(data, dict):
        raise ConfigError(f"results: {path}: expected a JSON object, got {type(data).__name__}")
    return data


def field(data: dict[str, Any], key: str, kind: type | tuple[type, ...], path: Path, *,
          default: object = MISSING, where: str = "") -> Any:
    """``data[key]`` checked to be of ``kind`` (bools are not numbers); errors name the file."""
    value = data.get(key, default)
    label = f"{where}{key}"
    if value is MISSING:
        raise ConfigError(f"results: {path}: key {label!r} is missing")
    kinds = kind if isinstance(kind, tuple) else (kind,)
    if value is default and default is not MISSING:
        return value
    if (isinstance(value, bool) and bool not in kinds) or not isinstance(value, kinds):
        shown = repr(value)
        shown = shown if len(shown) <= 60 else shown[:57] + "..."
        raise ConfigError(f"results: {path}: key {label!r}: expected {kind_name(kind)}, got {shown}")
    return value


def records(data: dict[str, Any], key: str, path: Path,
            fields: dict[str, type | tuple[type, ...]]) -> list[dict[str, Any]]:
    """``data[key]``: a list of objects, each with ``fields`` of the given kinds."""
    rows = field(data, key, list, path)
    for i, row in enumerate(rows):
        if not isinstance(row, dict):
            raise ConfigError(f"results: {path}: key '{key}[{i}]': expected an object, got "
                              f"{type(row).__name__}")
        for name, kind in fields.items():
            field(row, name, kind, path, where=f"{key}[{i}].")
    return rows


def numbers(data: dict[str, Any], key: str, path: Path, n: int, where: str) -> list[float]:
    vals = field(data, key, list, path, where=where)
    if len(vals) != n or any(isinstance(v, bool) or not isinstance(v, NUMBER) for v in vals):
        raise ConfigError(f"results: {path}: key '{where}{key}': expected {n} numbers, got "
                          f"{vals!r}")
    return [float(v) for v in vals]


#: The report's style, readable at a documentation page's width (~1000–1600 px wide PNGs, 11 pt
#: text); applied with ``matplotlib.rc_context`` while a report is drawn, never globally.
REPORT_STYLE: dict[RcKeyType, Any] = {
    "figure.dpi": 110, "savefig.dpi": 110, "font.size": 11, "axes.titlesize": 11, "axes.labelsize": 11,
    "xtick.labelsize": 10, "ytick.labelsize": 10, "axes.grid": True, "grid.alpha": 0.3,
    "legend.fontsize": 9, "lines.linewidth": 1.6}


class Figures:
    """Makes the report's figures with matplotlib's object API (:class:`matplotlib.figure.Figure`,
    no ``pyplot``): a report changes no backend and keeps no figure alive after it is saved."""

    def subplots(self, nrows: int = 1, ncols: int = 1, *, figsize: tuple[float, float],
                 **kwargs: Any) -> tuple[Any, Any]:
        """A new figure and its axes, as ``Figure(figsize=…).subplots(nrows, ncols, **kwargs)``."""
        from matplotlib.figure import Figure

        fig = Figure(figsize=figsize)
        return fig, fig.subplots(nrows, ncols, **kwargs)


def save(fig: Any, out: Path, fname: str) -> str:
    """Write ``fig`` to ``out/fname`` under the output rule (replaced whole or not at all)."""
    from pendulum_lqg.util.files import save_figure

    fig.tight_layout()
    save_figure(fig, out / fname, where="report", what="figure", bbox_inches="tight")
    return fname


# ---- grids ---------------------------------------------------------------------------------------
def read_rows(folder: Path) -> list[dict[str, Any]]:
    from pendulum_lqg.bench.results import read_csv

    path = folder / "episodes.csv"
    if not path.is_file():
        raise ConfigError(f"results: {folder} has no episodes.csv")
    return read_csv(path)
