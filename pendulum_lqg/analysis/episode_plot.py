"""A static figure of one episode: the states with their estimates, the measurement and the force.

:func:`plot_episode` draws one :class:`~pendulum_lqg.core.trajectory.Trajectory` (from
``run_episodes(..., trajectory=True)``) the way a lecture shows a closed loop:

* one panel per state (p, θ, ṗ, θ̇ for the cart-pole): the true state, the estimate x̂ the policy
  acted on and, where the estimator has a covariance (the Kalman filters), the band
  x̂ ± 2σ with σ = √diag(P), P the a-posteriori covariance of x̂ − x at each sample (the
  filter's covariance over the episode from its start, ``Trajectory.P``; see
  :meth:`~pendulum_lqg.policies.estimators.Estimator.error_covariances`);
* the measurement y, every channel;
* the force u held over each control period, with the saturation ±u_max and, where it differs,
  the force the policy asked for before saturation;
* the failure limits (±track on p, ±θ_max on θ) when they are finite, and the failure time.

Only matplotlib's object API is used (:class:`matplotlib.figure.Figure`, no ``pyplot``): the
function changes no backend and no style, so it is safe inside a library, a script or Jupyter.
The figure shows inline in Jupyter as a cell's value even where ``pyplot`` was never imported (it
renders itself as PNG, ``_repr_png_``). matplotlib is imported when a figure is made.
"""

from __future__ import annotations

import functools
import io
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.model.lti import LTIPlant

if TYPE_CHECKING:
    from matplotlib.figure import Figure
    from matplotlib.typing import RcKeyType

    from pendulum_lqg.core.scenario import Scenario
    from pendulum_lqg.core.trajectory import Trajectory
    from pendulum_lqg.model.plant import Plant

#: Panel labels of the cart-pole's state ``[p, θ, ṗ, θ̇]`` (units in brackets).
STATE_LABELS = ("p [m]", "θ [rad]", "ṗ [m/s]", "θ̇ [rad/s]")

#: Labels of the cart-pole's measurement channels ``y = [p, θ]``.
MEASUREMENT_LABELS = ("p", "θ")

#: File types :func:`save_episode_plot` writes (by the file's suffix).
PLOT_SUFFIXES = (".png", ".svg", ".pdf")

# readable on a slide or a documentation page (~1100 px wide at 100 dpi); applied with
# rc_context around the drawing only, never to the caller's matplotlib state
_STYLE: dict[RcKeyType, Any] = {
    "font.size": 10, "axes.titlesize": 10, "axes.labelsize": 10, "legend.fontsize": 8,
    "axes.grid": True, "grid.alpha": 0.3, "lines.linewidth": 1.3}


def state_labels(n: int) -> tuple[str, ...]:
    """Panel labels of an ``n``-state trajectory: the cart-pole's names for 4 states, else x₁ … xₙ."""
    return STATE_LABELS if n == 4 else tuple(f"x{i + 1}" for i in range(n))


def plot_episode(trajectory: Trajectory, *, plant: Plant | LTIPlant | None = None,
                 scenario: Scenario | None = None, title: str | None = None) -> Figure:
    """A figure of one episode: a panel per state, then the measurement y and the force u (a plant
    given as matrices: a panel per state, per output and per input, named by its file).

    Parameters
    ----------
    trajectory : one episode of ``run_episodes(..., trajectory=True).trajectories``
    plant : gives the track half-length (drawn on p) and the force limit ±u_max (drawn on u);
        without it neither is drawn
    scenario : gives θ_max (drawn on θ) and the control period; without it θ_max is not drawn
    title : the figure's title (default: episode, seed and outcome)

    Returns
    -------
    matplotlib.figure.Figure
        ``n + 2`` axes in reading order, ``n`` the number of states: ``fig.axes[i]`` is state
        ``i`` (y-label from :func:`state_labels`), then ``"y"`` and ``"u [N]"``; for an
        :class:`~pendulum_lqg.model.lti.LTIPlant` ``n + p + m`` axes labelled with its state,
        output and input names (:func:`_plot_lti`). Save it with :func:`save_episode_plot`; in
        Jupyter it shows inline as the cell's value.
    """
    t = np.asarray(trajectory.t, dtype=float)
    x = np.asarray(trajectory.x, dtype=float)
    if t.ndim != 1 or t.size == 0 or x.shape[0] != t.size:
        raise ConfigError(f"trajectory: expected sample times t (N,) and states x (N, n) with "
                          f"N ≥ 1, got t {t.shape} and x {x.shape}")
    return _figure(plant, trajectory, scenario, title)


@functools.singledispatch
def _figure(plant: Any, trajectory: Trajectory, scenario: Scenario | None,
            title: str | None) -> Figure:
    """The figure of the cart-pole's episode (or of a trajectory without a plant); a plant given
    as matrices has its own (:func:`_plot_lti`, registered below)."""
    import matplotlib

    x = np.asarray(trajectory.x, dtype=float)
    n = x.shape[1]
    labels = state_labels(n)
    limits, u_max = _limits(plant, scenario, n)
    ncol = 2
    nrow = -(-(n + 2) // ncol)
    with matplotlib.rc_context(_STYLE):
        fig = _inline_figure_class()(figsize=(11.0, 2.3 * nrow + 0.6), layout="constrained")
        grid = fig.subplots(nrow, ncol, sharex=True, squeeze=False)
        axes = list(grid.flat)
        for i in range(n):
            _state_panel(axes[i], trajectory, i, labels[i], limits.get(i))
        _measurement_panel(axes[n], trajectory, labels)
        _force_panel(axes[n + 1], trajectory, u_max)
        for ax in axes[n + 2:]:
            fig.delaxes(ax)
        for ax in axes[n:n + 2]:          # the bottom panels of their columns
            ax.xaxis.set_tick_params(labelbottom=True)
            ax.set_xlabel("t [s]")
        end = _failure_time(trajectory)
        if end is not None:
            for ax in axes[:n + 2]:
                ax.axvline(end, color="tab:red", lw=0.8, ls=":")
        fig.suptitle(title if title is not None else episode_title(trajectory))
        axes[0].legend(loc="upper right")
    return fig


@functools.cache
def _inline_figure_class() -> type[Figure]:
    """:class:`~matplotlib.figure.Figure` that Jupyter can show without ``pyplot``: IPython shows a
    plain ``Figure`` as PNG only after ``pyplot`` registered its formatter, else as text."""
    from matplotlib.figure import Figure

    class InlineFigure(Figure):
        def _repr_png_(self) -> bytes:
            buf = io.BytesIO()
            self.savefig(buf, format="png", dpi=100)
            return buf.getvalue()

    return InlineFigure


def save_episode_plot(fig: Figure, path: str | Path) -> Path:
    """Write ``fig`` to ``path`` (``.png``, ``.svg`` or ``.pdf``, by the suffix) under the output
    rule (:func:`~pendulum_lqg.util.files.save_figure`: temporary file and rename); returns the
    path. A suffix of another kind, or a path that exists and is not a regular file, is a
    :class:`ConfigError` naming ``--plot``."""
    from pendulum_lqg.util.files import save_figure

    # replaced whole or not at all: a failed write (a full disk, a file-size limit) keeps the old
    # picture
    return save_figure(fig, check_plot_path(path), where="--plot", what="picture", dpi=110)


def check_plot_path(path: str | Path) -> Path:
    """``path`` checked before anything runs: a known suffix, and a target that
    :func:`~pendulum_lqg.util.files.output_file` accepts (a new path or a regular file, never a device,
    a FIFO or a folder; its folder created and writable)."""
    from pendulum_lqg.util.files import output_file

    if Path(path).suffix.lower() not in PLOT_SUFFIXES:
        raise ConfigError(f"--plot: expected a file name ending in {', '.join(PLOT_SUFFIXES)}, got "
                          f"{str(path)!r}")
    return output_file("--plot", path, what="picture")


def _limits(plant: Plant | None, scenario: Scenario | None, n: int) -> tuple[dict[int, float], float | None]:
    """The limits in force, as drawn: the failure limit of each state panel (track on p, θ_max on
    θ) and the force limit on u, finite ones only. With both the plant and the scenario they are
    the core's (:func:`~pendulum_lqg.core.rules.limits`: a scenario's limit overrides the
    model's, ``inf`` switches one off); with one of them, what that one says."""
    from pendulum_lqg.core.rules import limits

    theta_max = track = u_max = math.inf
    if plant is not None and scenario is not None:
        theta_max, track, u_max = limits(plant, scenario)
    elif plant is not None:
        track, u_max = plant.track_limit, plant.u_max
    elif scenario is not None:
        theta_max = scenario.theta_max
    states = {i: float(v) for i, v in ((0, track), (1, theta_max)) if math.isfinite(v)} \
        if n == 4 else {}
    return states, (float(u_max) if math.isfinite(u_max) else None)


def _state_panel(ax: Any, tr: Trajectory, i: int, label: str, limit: float | None) -> None:
    t = np.asarray(tr.t, dtype=float)
    ax.plot(t, np.asarray(tr.x)[:, i], color="k", label="x (true)")
    x_hat = np.asarray(tr.x_hat, dtype=float)
    if x_hat.ndim == 2 and x_hat.shape[1] > i and np.isfinite(x_hat[:, i]).any():
        ax.plot(t, x_hat[:, i], color="tab:blue", ls="--", label="x̂ (estimate)")
        P = np.asarray(tr.P, dtype=float)
        if P.ndim == 3 and P.shape[1] > i and np.isfinite(P[:, i, i]).all():
            two_sigma = 2.0 * np.sqrt(np.maximum(P[:, i, i], 0.0))     # σ = √P_ii of x̂ − x
            ax.fill_between(t, x_hat[:, i] - two_sigma, x_hat[:, i] + two_sigma,
                            color="tab:blue", alpha=0.2, lw=0, label="x̂ ± 2σ")
    if limit is not None:
        for s in (-limit, limit):
            ax.axhline(s, color="tab:red", lw=0.9, ls="--",
                       label="failure limit" if s > 0 else None)
    ax.set_ylabel(label)


def _measurement_panel(ax: Any, tr: Trajectory, state_names: tuple[str, ...]) -> None:
    t = np.asarray(tr.t, dtype=float)
    y = np.asarray(tr.y, dtype=float).reshape(t.size, -1)
    names = (MEASUREMENT_LABELS if y.shape[1] == 2 and len(state_names) == 4
             else tuple(f"y{j + 1}" for j in range(y.shape[1])))
    units = ("m", "rad") if names == MEASUREMENT_LABELS else ("",) * y.shape[1]
    for j in range(y.shape[1]):
        unit = f" [{units[j]}]" if units[j] else ""
        ax.plot(t, y[:, j], marker=".", ms=2, lw=0.5, label=f"{names[j]}{unit}")
    ax.set_ylabel("y")
    ax.legend(loc="upper right")


def _force_panel(ax: Any, tr: Trajectory, u_max: float | None) -> None:
    t = np.asarray(tr.t, dtype=float)
    u = np.asarray(tr.u, dtype=float)
    asked = getattr(tr, "u_policy", None)
    if asked is not None and not np.allclose(np.asarray(asked, dtype=float), u):
        ax.step(t, asked, where="post", color="tab:gray", lw=0.8,
                label="u asked by the policy")
    ax.step(t, u, where="post", color="tab:green", label="u applied")   # held over each period
    if u_max is not None and np.isfinite(u_max):
        for s in (-u_max, u_max):
            ax.axhline(s, color="tab:red", lw=0.9, ls="--", label="saturation" if s > 0 else None)
    ax.set_ylabel("u [N]")
    ax.legend(loc="upper right")


def _failure_time(tr: Trajectory) -> float | None:
    row = tr.row or {}
    if row.get("success", True):
        return None
    t_fail = row.get("time_to_failure")
    return float(t_fail) if isinstance(t_fail, int | float) and np.isfinite(t_fail) else None


def episode_title(tr: Trajectory) -> str:
    """``"episode K (seed S): success"`` or ``"… failed (reason) at t = … s"``."""
    row = tr.row or {}
    if row.get("success", True):
        outcome = "success"
    else:
        outcome = f"failed ({row.get('failure_reason', '')})"
        t_fail = _failure_time(tr)
        if t_fail is not None:
            outcome += f" at t = {t_fail:.3g} s"
    return f"episode {tr.episode} (seed {tr.seed}): {outcome}"


@_figure.register(LTIPlant)
def _plot_lti(plant: LTIPlant, tr: Trajectory, scenario: Scenario | None,
              title: str | None) -> Figure:
    """The figure of an LTI plant's episode: ``n`` state panels (x, x̂ ± 2σ, the state's failure
    limit), ``p`` output panels (y and the noise-free ``C x``), ``m`` input panels (u applied, u
    asked where it differs, the input's limit in force), two columns, each labelled with the
    plant's names."""
    import matplotlib

    from pendulum_lqg.core.rules import limits

    t = np.asarray(tr.t, dtype=float)
    names = plant.state_names, plant.output_names, plant.input_names
    n, p, m = (len(v) for v in names)
    u_max = (limits(plant, scenario)[2] if scenario is not None else plant.u_max)
    u_lim = np.broadcast_to(np.asarray(u_max, dtype=float), (m,))
    s_lim = (np.full(n, math.inf) if plant.state_limits is None
             else np.asarray(plant.state_limits, dtype=float))
    y = np.asarray(tr.y, dtype=float).reshape(t.size, -1)
    y_true = np.asarray(tr.y_true, dtype=float).reshape(t.size, -1)
    u = np.asarray(tr.u, dtype=float).reshape(t.size, -1)
    asked = getattr(tr, "u_policy", None)
    asked = None if asked is None else np.asarray(asked, dtype=float).reshape(t.size, -1)
    ncol = 2 if n + p + m > 3 else 1
    nrow = -(-(n + p + m) // ncol)
    with matplotlib.rc_context(_STYLE):
        fig = _inline_figure_class()(figsize=(11.0 if ncol == 2 else 7.0, 2.0 * nrow + 0.6),
                                     layout="constrained")
        axes = list(fig.subplots(nrow, ncol, sharex=True, squeeze=False).flat)
        for i in range(n):
            lim = float(s_lim[i])
            _state_panel(axes[i], tr, i, names[0][i], lim if math.isfinite(lim) else None)
        for j in range(p):
            ax = axes[n + j]
            ax.plot(t, y[:, j], marker=".", ms=2, lw=0.5, color="tab:orange", label="y (measured)")
            ax.plot(t, y_true[:, j], color="k", lw=0.9, label="C x (noise-free)")
            ax.set_ylabel(names[1][j])
            ax.legend(loc="upper right")
        for j in range(m):
            ax = axes[n + p + j]
            if asked is not None and not np.allclose(asked[:, j], u[:, j]):
                ax.step(t, asked[:, j], where="post", color="tab:gray", lw=0.8,
                        label="u asked by the policy")
            ax.step(t, u[:, j], where="post", color="tab:green", label="u applied")
            if math.isfinite(u_lim[j]):
                for sgn in (-1.0, 1.0):
                    ax.axhline(sgn * u_lim[j], color="tab:red", lw=0.9, ls="--",
                               label="saturation" if sgn > 0 else None)
            ax.set_ylabel(names[2][j])
            ax.legend(loc="upper right")
        _finish_axes(fig, axes, n + p + m, ncol, tr)
        fig.suptitle(title if title is not None else episode_title(tr))
        axes[0].legend(loc="upper right")
    return fig


def _finish_axes(fig: Figure, axes: list[Any], used: int, ncol: int, tr: Trajectory) -> None:
    """Remove the unused axes, put the time axis under the bottom panel of each column and mark
    the failure time on every panel."""
    for ax in axes[used:]:
        fig.delaxes(ax)
    for ax in axes[max(used - ncol, 0):used]:
        ax.xaxis.set_tick_params(labelbottom=True)
        ax.set_xlabel("t [s]")
    end = _failure_time(tr)
    if end is not None:
        for ax in axes[:used]:
            ax.axvline(end, color="tab:red", lw=0.8, ls=":")
