"""Writing a recording: every episode's samples as columns, the static scene, the blueprint, the viewer."""

from __future__ import annotations

import collections
import contextlib
import errno
import sys
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.model.plant import CART_BODY, POLE_BODY, STATE_NAMES, Plant
from pendulum_lqg.util.files import replacing

if TYPE_CHECKING:
    from pendulum_lqg.core.scenario import Scenario
    from pendulum_lqg.core.trajectory import Trajectory
    from pendulum_lqg.policies.lqg import Policy
from pendulum_lqg.record.documents import config_markdown, outcome_markdown, summary_markdown
from pendulum_lqg.record.scene import (
    BAND_COLOR,
    EST_COLOR,
    GHOST_ALPHA,
    LIMIT_COLOR,
    MEAS_COLOR,
    SYMBOLS,
    TRUE_COLOR,
    UNITS,
    body_geoms,
    cart_translations,
    eye,
    geom_archetype,
    hinge_quaternions,
)

#: Name of the timeline every sample is logged on (seconds since the episode start).
TIMELINE = "sim_time"


#: Episodes that get their own tab in the blueprint (all are recorded regardless).
MAX_EPISODE_TABS = 12


#: Seconds to wait for a spawned viewer to take the data before giving up on it.
SPAWN_FLUSH_TIMEOUT = 10.0


#: Seconds to wait for a spawned viewer to listen on its port before writing only the file.
VIEWER_WAIT = 5.0


#: The port the spawned viewer listens on (Rerun's default).
VIEWER_PORT = 9876


def recording_path(path: str | Path) -> Path:
    """``path`` as the ``.rrd`` file a recording is written to; an empty name or an existing
    folder is a one-line :class:`ConfigError` (before any episode runs, when a caller checks
    first), not an error of Rerun's after the run."""
    if not str(path).strip():
        raise ConfigError(f"record: expected a file path for the recording (FILE.rrd), got "
                          f"{str(path)!r}")
    out = Path(path)
    if out.is_dir():
        raise ConfigError(f"record: {out} is a folder; expected a file path for the recording, "
                          f"e.g. {out / 'recording.rrd'}")
    return out


def _start_viewer(rec: Any) -> tuple[bool, str | None]:
    """Spawn a native Rerun viewer and wait (at most :data:`VIEWER_WAIT` s) until it listens.

    Returns ``(reachable, note)``; ``note`` says in one line why no viewer will get the data: no
    display on Linux (a viewer would never come up, so none is started), no ``rerun`` executable,
    or no viewer listening in time. Nothing here can block for longer than the wait.
    """
    import os
    import socket

    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY")
                                                 or os.environ.get("WAYLAND_DISPLAY")):
        return False, "no display (DISPLAY and WAYLAND_DISPLAY are unset), so no viewer was started"
    try:
        rec.spawn(port=VIEWER_PORT, connect=False)
    except (RuntimeError, OSError) as exc:
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        return False, f"cannot start the Rerun viewer ({first})"
    deadline = time.monotonic() + VIEWER_WAIT
    while time.monotonic() < deadline:
        try:
            with socket.create_connection(("127.0.0.1", VIEWER_PORT), timeout=0.5):
                return True, None
        except OSError:
            time.sleep(0.1)
    return False, f"no Rerun viewer listened on port {VIEWER_PORT} within {VIEWER_WAIT:g} s"


# ---- results --------------------------------------------------------------------------------
@dataclass(frozen=True)
class RecordingStats:
    """What :func:`record_episodes` did.

    Attributes
    ----------
    episodes : number of episodes recorded
    entities : number of entity paths with logged data (static or temporal)
    rows : temporal rows written (sum over entities of the samples sent)
    seconds : wall time of the whole call (building columns, sending, flushing, closing the sink)
    seconds_logging : wall time of the ``log`` / ``send_columns`` calls alone
    path : the ``.rrd`` file written (``None`` if only a viewer was spawned)
    bytes : size of that file (0 without a file)
    viewer_reached : with ``spawn``, whether the spawned viewer took all data (``None`` without)
    viewer_note : with ``spawn``, why no viewer got the data (one line), else ``None``
    """

    episodes: int
    entities: int
    rows: int
    seconds: float
    seconds_logging: float
    path: Path | None
    bytes: int
    viewer_reached: bool | None = None
    viewer_note: str | None = None


# ---- the recording --------------------------------------------------------------------------
def episode_prefix(episode: int, width: int = 4) -> str:
    """Entity prefix of an episode: ``/episode_0007``."""
    return f"/episode_{int(episode):0{width}d}"


def physics_samples(tr: Trajectory, plant: Plant) -> tuple[np.ndarray, np.ndarray]:
    """Times (M,) and true states (M, 4) the recording logs at the physics rate.

    The initial state at ``t = 0`` followed by the physics-rate states, cut after the failing
    physics step of a failed episode (the simulator finishes the control period, but the episode
    ended at ``time_to_failure``).
    """
    t = np.concatenate([[0.0], np.asarray(tr.t_physics, dtype=float)])
    x = np.concatenate([np.asarray(tr.x[:1], dtype=float), np.asarray(tr.states, dtype=float)])
    ttf = float(tr.row.get("time_to_failure", np.nan))  # type: ignore[arg-type]
    if np.isfinite(ttf):
        keep = t <= ttf + 0.5 * plant.timestep
        t, x = t[keep], x[keep]
    return t, x


class _Writer:
    """Send helpers that time the calls and count rows / entities."""

    def __init__(self, rr: Any, rec: Any) -> None:
        self.rr, self.rec = rr, rec
        self.seconds = 0.0
        self.rows = 0
        self.entities: set[str] = set()

    def static(self, path: str, archetype: Any) -> None:
        t0 = time.perf_counter()
        self.rec.log(path, archetype, static=True)
        self.seconds += time.perf_counter() - t0
        self.entities.add(path)

    def log_at(self, path: str, t: float, archetype: Any) -> None:
        t0 = time.perf_counter()
        self.rec.set_time(TIMELINE, duration=float(t))
        self.rec.log(path, archetype)
        self.rec.reset_time()
        self.seconds += time.perf_counter() - t0
        self.entities.add(path)
        self.rows += 1

    def columns(self, path: str, t: np.ndarray, columns: Any) -> None:
        t0 = time.perf_counter()
        self.rec.send_columns(path, indexes=[self.rr.TimeColumn(TIMELINE, duration=t)],
                              columns=columns)
        self.seconds += time.perf_counter() - t0
        self.entities.add(path)
        self.rows += int(np.asarray(t).shape[0])

    def scalars(self, path: str, t: np.ndarray, values: np.ndarray) -> None:
        self.columns(path, t, self.rr.Scalars.columns(scalars=np.asarray(values, dtype=float)))


def _lines(rr: Any, names: Sequence[str], colors: Sequence[Sequence[int]],
           widths: Sequence[float], *, step: bool = False) -> Any:
    kw: dict[str, Any] = {}
    if step:
        kw["interpolation_mode"] = "StepAfter"
    return rr.SeriesLines(names=list(names), colors=[list(c) for c in colors],
                          widths=list(widths), **kw)


def _record_scene_static(w: _Writer, plant: Plant, pre: str, *, ghost: bool) -> None:
    rr = w.rr
    world = f"{pre}/world"
    for g in body_geoms(plant, 0):
        arch = geom_archetype(rr, g)
        if arch is not None:
            w.static(f"{world}/{g.name}", arch)
    L = plant.track_limit
    z = 0.25
    w.static(f"{world}/track_limits", rr.LineStrips3D(
        [[[-L, 0.0, -z], [-L, 0.0, z]], [[L, 0.0, -z], [L, 0.0, z]]],
        radii=0.006, colors=[LIMIT_COLOR], labels=[f"p = −{L:g} m", f"p = +{L:g} m"]))
    for g in body_geoms(plant, CART_BODY):
        arch = geom_archetype(rr, g)
        if arch is not None:
            w.static(f"{world}/cart/{g.name}", arch)
    for g in body_geoms(plant, POLE_BODY):
        arch = geom_archetype(rr, g)
        if arch is not None:
            w.static(f"{world}/cart/pole/{g.name}", arch)
    if ghost:
        for g in body_geoms(plant, CART_BODY):
            arch = geom_archetype(rr, g, alpha=GHOST_ALPHA)
            if arch is not None:
                w.static(f"{world}/estimate/{g.name}", arch)
        for g in body_geoms(plant, POLE_BODY):
            arch = geom_archetype(rr, g, alpha=GHOST_ALPHA)
            if arch is not None:
                w.static(f"{world}/estimate/pole/{g.name}", arch)


def _record_episode(w: _Writer, plant: Plant, tr: Trajectory, pre: str, *, estimated: bool,
                    label: str | None, u_max: float) -> None:
    """Everything of one episode under its prefix ``pre``: the scene, the animation, the state
    plots, the force and the running cost, the estimator's internals and the outcome."""
    _record_scene_static(w, plant, pre, ghost=estimated)
    t_ph, x_ph = physics_samples(tr, plant)
    t = np.asarray(tr.t, dtype=float)
    _record_animation(w, plant, tr, pre, t_ph, x_ph, estimated=estimated)
    _record_states(w, tr, pre, t_ph, x_ph, estimated=estimated)
    _record_control_and_cost(w, tr, pre, t, t_end=float(t_ph[-1]), u_max=u_max)
    if estimated:
        _record_estimator(w, tr, pre, t)
    _record_outcome(w, plant, tr, pre, label, x_end=x_ph[-1], t_end=float(t_ph[-1]))


def _record_animation(w: _Writer, plant: Plant, tr: Trajectory, pre: str, t_ph: np.ndarray,
                      x_ph: np.ndarray, *, estimated: bool) -> None:
    """The 3-D cart-pole from the true state (physics rate) and, as a ghost, from the estimate
    (control rate, held)."""
    rr, world = w.rr, f"{pre}/world"
    w.columns(f"{world}/cart", t_ph,
              rr.Transform3D.columns(translation=cart_translations(plant, x_ph[:, 0])))
    w.columns(f"{world}/cart/pole", t_ph, rr.Transform3D.columns(
        translation=np.broadcast_to(plant.model.body(POLE_BODY).pos, (t_ph.size, 3)),
        quaternion=hinge_quaternions(plant, x_ph[:, 1])))
    if estimated:
        t = np.asarray(tr.t, dtype=float)
        w.columns(f"{world}/estimate", t,
                  rr.Transform3D.columns(translation=cart_translations(plant, tr.x_hat[:, 0])))
        w.columns(f"{world}/estimate/pole", t, rr.Transform3D.columns(
            translation=np.broadcast_to(plant.model.body(POLE_BODY).pos, (t.size, 3)),
            quaternion=hinge_quaternions(plant, tr.x_hat[:, 1])))


def _record_states(w: _Writer, tr: Trajectory, pre: str, t_ph: np.ndarray, x_ph: np.ndarray, *,
                   estimated: bool) -> None:
    """One plot per state: true (physics rate), estimate (held), measurement (points, p and θ)."""
    rr, ep, t = w.rr, tr.episode, np.asarray(tr.t, dtype=float)
    for i, name in enumerate(STATE_NAMES):
        sym, base = SYMBOLS[name], f"{pre}/state/{name}"
        w.static(f"{base}/true", _lines(rr, [f"{sym} true · ep {ep}"], [TRUE_COLOR], [1.5]))
        w.scalars(f"{base}/true", t_ph, x_ph[:, i])
        if estimated:
            w.static(f"{base}/estimate", _lines(rr, [f"{sym} estimate"], [EST_COLOR], [1.2],
                                                step=True))
            w.scalars(f"{base}/estimate", t, tr.x_hat[:, i])
        if i < 2:
            w.static(f"{base}/measured", rr.SeriesPoints(
                names=[f"{sym} measured"], colors=[MEAS_COLOR], markers=["circle"],
                marker_sizes=[1.5]))
            w.scalars(f"{base}/measured", t, tr.y[:, i])


def _record_control_and_cost(w: _Writer, tr: Trajectory, pre: str, t: np.ndarray, *,
                             t_end: float, u_max: float) -> None:
    """The applied force with its limits ±u_max, and the running cost J(t)."""
    rr = w.rr
    w.static(f"{pre}/control/u", _lines(rr, ["u applied"], [TRUE_COLOR], [1.5], step=True))
    w.scalars(f"{pre}/control/u", t, tr.u)
    w.static(f"{pre}/control/limits", _lines(rr, ["+u_max", "−u_max"],
                                             [LIMIT_COLOR, LIMIT_COLOR], [1.0, 1.0]))
    w.scalars(f"{pre}/control/limits", np.array([0.0, t_end]),
              np.array([[u_max, -u_max], [u_max, -u_max]]))
    # cost[n] is J at the end of period n: t[n] + T, or the failure time for the last one
    dt = float(t[1] - t[0]) if t.size > 1 else t_end
    t_cost = np.concatenate([[0.0], t + dt])
    t_cost[-1] = min(t_cost[-1], t_end)
    w.static(f"{pre}/cost/J", _lines(rr, [f"J · ep {tr.episode}"], [(44, 160, 44)], [1.5]))
    w.scalars(f"{pre}/cost/J", t_cost, np.concatenate([[0.0], tr.cost]))


def _record_estimator(w: _Writer, tr: Trajectory, pre: str, t: np.ndarray) -> None:
    """The estimation error per state (with the filter's ±2σ when it has a covariance) and the
    innovations of p and θ."""
    rr = w.rr
    err = tr.x_hat - tr.x
    P = np.asarray(tr.P, dtype=float)
    has_cov = bool(np.all(np.isfinite(P)))
    for i, name in enumerate(STATE_NAMES):
        sym, path = SYMBOLS[name], f"{pre}/estimation/error/{name}"
        if has_cov:
            two_sigma = 2.0 * np.sqrt(np.clip(P[:, i, i], 0.0, None))
            w.static(path, _lines(rr, [f"{sym}̂ − {sym}", "+2σ", "−2σ"],
                                  [EST_COLOR, BAND_COLOR, BAND_COLOR], [1.2, 1.0, 1.0]))
            w.scalars(path, t, np.stack([err[:, i], two_sigma, -two_sigma], axis=1))
        else:
            w.static(path, _lines(rr, [f"{sym}̂ − {sym}"], [EST_COLOR], [1.2]))
            w.scalars(path, t, err[:, i])
    for i, name in enumerate(("p", "theta")):
        path = f"{pre}/estimation/innovation/{name}"
        w.static(path, _lines(rr, [f"ν_{SYMBOLS[name]} [{UNITS[name]}]"],
                              [(148, 103, 189) if i else (23, 190, 207)], [1.0]))
        w.scalars(path, t, tr.innovation[:, i])


def _record_outcome(w: _Writer, plant: Plant, tr: Trajectory, pre: str, label: str | None, *,
                    x_end: np.ndarray, t_end: float) -> None:
    """The outcome document, and an event at the end: the failure (with a marker over the cart
    in the scene) or the success and its J."""
    rr, ep = w.rr, tr.episode
    w.static(f"{pre}/outcome", rr.TextDocument(outcome_markdown(tr, label),
                                               media_type=rr.MediaType.MARKDOWN))
    ttf = float(tr.row.get("time_to_failure", np.nan))  # type: ignore[arg-type]
    if not bool(tr.row.get("success", False)) and np.isfinite(ttf):
        reason = str(tr.row.get("failure_reason", "failed"))
        w.log_at(f"{pre}/events", ttf, rr.TextLog(f"episode {ep} failed: {reason} at "
                                                  f"t = {ttf:.3f} s", level=rr.TextLogLevel.ERROR))
        w.log_at(f"{pre}/world/failure", ttf, rr.Points3D(
            [cart_translations(plant, x_end[:1])[0] + [0.0, 0.0, plant.pole_length + 0.2]],
            radii=[0.05],
            colors=[LIMIT_COLOR], labels=[f"{reason} @ {ttf:.3f} s"], show_labels=True))
    else:
        w.log_at(f"{pre}/events", t_end, rr.TextLog(f"episode {ep} succeeded, J = "
                                                    f"{float(tr.row.get('cost', np.nan)):.4g}",  # type: ignore[arg-type]
                                                    level=rr.TextLogLevel.INFO))


def _blueprint(prefixes: Sequence[tuple[str, Trajectory, str | None]], *, estimated: bool,
               covariance: bool, eye: Any | None) -> Any:
    import rerun.blueprint as rrb

    tabs = []
    for pre, tr, label in prefixes[:MAX_EPISODE_TABS]:
        left = rrb.Vertical(
            rrb.Spatial3DView(origin=f"{pre}/world", name="cart-pole (true; ghost = estimate)",
                              eye_controls=eye, line_grid=rrb.LineGrid3D(visible=False)),
            rrb.Tabs(rrb.TextDocumentView(origin=f"{pre}/outcome", name="outcome"),
                     rrb.TextDocumentView(origin="/config", name="configuration"),
                     rrb.TextLogView(origin=f"{pre}/events", name="events")),
            row_shares=[3, 2])
        middle = rrb.Vertical(*[
            rrb.TimeSeriesView(origin=f"{pre}/state/{n}", name=f"{SYMBOLS[n]} [{UNITS[n]}]")
            for n in STATE_NAMES])
        right_views: list[Any] = [
            rrb.TimeSeriesView(origin=f"{pre}/control", name="control u [N] and ±u_max"),
            rrb.TimeSeriesView(origin=f"{pre}/cost", name="running cost J(t)")]
        if estimated:
            err_name = "x̂ − x ± 2σ" if covariance else "x̂ − x"
            right_views.append(rrb.Tabs(
                rrb.Grid(*[rrb.TimeSeriesView(origin=f"{pre}/estimation/error/{n}",
                                              name=f"{err_name}: {SYMBOLS[n]}")
                           for n in STATE_NAMES], grid_columns=2, name="estimation error"),
                rrb.TimeSeriesView(origin=f"{pre}/estimation/innovation",
                                   name="innovations y − C x̄"),
                name="estimator"))
        right = rrb.Vertical(*right_views, row_shares=[1, 1, 2][: len(right_views)])
        name = f"episode {tr.episode}" + (f" ({label})" if label else "")
        tabs.append(rrb.Horizontal(left, middle, right, column_shares=[4, 3, 3], name=name))
    if len(prefixes) > 1:
        tabs.append(rrb.Horizontal(
            rrb.Vertical(
                rrb.TimeSeriesView(origin="/", name="θ of every episode [rad]",
                                   contents=[f"{pre}/state/theta/true" for pre, _, _ in prefixes]),
                rrb.TimeSeriesView(origin="/", name="J(t) of every episode",
                                   contents=[f"{pre}/cost/J" for pre, _, _ in prefixes])),
            rrb.Tabs(rrb.TextDocumentView(origin="/summary", name="episodes"),
                     rrb.TextDocumentView(origin="/config", name="configuration")),
            column_shares=[3, 2], name="overview"))
    return rrb.Blueprint(rrb.Tabs(*tabs), rrb.BlueprintPanel(state="collapsed"),
                         rrb.SelectionPanel(state="collapsed"), rrb.TimePanel(state="collapsed"))


def record_episodes(trajectories: Sequence[Trajectory], *, plant: Plant, scenario: Scenario,
                    policy: Policy, config: Mapping[str, object],
                    path: str | Path | None = None, spawn: bool = False,
                    application_id: str = "pendulum_lqg",
                    labels: Mapping[str, int] | None = None) -> RecordingStats:
    """Write the episodes as one Rerun recording (a ``.rrd`` file and/or a spawned viewer).

    Each episode lives under its own entity prefix (:func:`episode_prefix`), so episodes are
    distinguishable in one recording and share its blueprint (one tab per episode); every
    episode's samples start at ``sim_time = 0``. See the module docstring for the entity tree.

    Parameters
    ----------
    trajectories : from ``run_episodes(..., trajectory=True).trajectories`` (episode numbers
        must be distinct)
    plant : the simulated plant (its MJCF geometry and limits are drawn)
    scenario : the scenario the episodes ran in
    policy : the policy that ran them (name, gains and poles from ``policy.info``)
    config : the run's configuration as plain data (shown verbatim; ``config["seed"]`` is
        reported as the run's seed if present)
    path : ``.rrd`` file to write (parent directories are created)
    spawn : also start a native Rerun viewer and stream to it
    application_id : Rerun application id (the viewer keys stored blueprints on it)
    labels : optional label → episode number (e.g. :func:`telling_episodes`), shown in the tab
        names, the outcome documents and the episode table

    Returns
    -------
    RecordingStats : time spent, rows and entities written, file size
    """
    if path is None and not spawn:
        raise ConfigError("record: give a path to write and/or spawn=True")
    trajectories, by_episode = _checked_trajectories(trajectories, labels)
    t_start = time.perf_counter()
    import rerun as rr

    estimated = not policy.needs_state
    covariance = estimated and all(bool(np.all(np.isfinite(tr.P))) for tr in trajectories)
    prefixes = _prefixes(trajectories, by_episode)
    blueprint = _blueprint(prefixes, estimated=estimated, covariance=covariance, eye=eye(plant))
    rec = rr.RecordingStream(application_id)
    out_path = recording_path(path) if path is not None else None
    with _file_target(out_path) as tmp:
        viewer, viewer_note = _open_sinks(rr, rec, tmp, spawn=spawn, blueprint=blueprint)
        rec.send_recording_name(f"{policy.name}: {len(trajectories)} episode(s)")
        w = _Writer(rr, rec)
        for entity, text in (("/config", config_markdown(plant, scenario, policy, config)),
                             ("/summary", summary_markdown(trajectories, by_episode))):
            w.static(entity, rr.TextDocument(text, media_type=rr.MediaType.MARKDOWN))
        for pre, tr, label in prefixes:
            _record_episode(w, plant, tr, pre, estimated=estimated, label=label,
                            u_max=plant.u_max)
        note = _flush(rec, viewer)
    viewer_reached: bool | None = None if not spawn else (viewer and note is None)
    viewer_note = note if note is not None else viewer_note
    seconds = time.perf_counter() - t_start
    size = out_path.stat().st_size if out_path is not None and out_path.exists() else 0
    return RecordingStats(episodes=len(trajectories), entities=len(w.entities), rows=w.rows,
                          seconds=seconds, seconds_logging=w.seconds, path=out_path, bytes=size,
                          viewer_reached=viewer_reached, viewer_note=viewer_note)


def _file_target(out_path: Path | None) -> contextlib.AbstractContextManager[Path | None]:
    """The file the stream is written to: none, or a temporary file beside ``out_path`` renamed
    over it once flushed (:func:`~pendulum_lqg.util.files.replacing`) — a failed write keeps the
    old recording whole, and only a new path or a regular file is replaced. Its folder is made."""
    if out_path is None:
        return contextlib.nullcontext(None)
    out_path.parent.mkdir(parents=True, exist_ok=True)
    return replacing(out_path, where="record", what="recording")


def _prefixes(trajectories: list[Trajectory], by_episode: dict[int, str],
              ) -> list[tuple[str, Trajectory, str | None]]:
    """Each trajectory with its entity prefix (episode numbers of one width, at least four digits)
    and its label."""
    width = max(4, len(str(max(int(tr.episode) for tr in trajectories))))
    return [(episode_prefix(tr.episode, width), tr, by_episode.get(int(tr.episode)))
            for tr in trajectories]


def _checked_trajectories(trajectories: Sequence[Trajectory], labels: Mapping[str, int] | None,
                          ) -> tuple[list[Trajectory], dict[int, str]]:
    """The trajectories as a list (at least one, episode numbers distinct) and the labels per
    episode (``"worst, first failing"`` when an episode has several)."""
    trajectories = list(trajectories)
    if not trajectories:
        raise ConfigError("trajectories: expected at least one trajectory, got none")
    episodes = [int(tr.episode) for tr in trajectories]
    dup = [e for e, c in collections.Counter(episodes).items() if c > 1]
    if dup:
        raise ConfigError(f"trajectories: episode {dup[0]} appears more than once")
    by_episode: dict[int, str] = {}
    for lab, e in (labels or {}).items():
        by_episode[int(e)] = f"{by_episode[int(e)]}, {lab}" if int(e) in by_episode else str(lab)
    return trajectories, by_episode


def _open_sinks(rr: Any, rec: Any, out_path: Path | None, *, spawn: bool, blueprint: Any,
                ) -> tuple[bool, str | None]:
    """Point ``rec`` at the file ``out_path`` and, with ``spawn``, at a viewer it starts:
    ``(viewer reached, why not)``. Without a file, a viewer that cannot start is an error."""
    viewer_note: str | None = None
    viewer = False
    if spawn:
        viewer, viewer_note = _start_viewer(rec)
        if not viewer and out_path is None:
            raise ConfigError(f"spawn: {viewer_note}; give a path to write the recording to")
    if viewer:
        sinks: list[Any] = [rr.GrpcSink(f"rerun+http://127.0.0.1:{VIEWER_PORT}/proxy")]
        if out_path is not None:
            sinks.append(rr.FileSink(str(out_path)))
        rec.set_sinks(*sinks, default_blueprint=blueprint)
    else:
        assert out_path is not None
        rec.save(str(out_path), default_blueprint=blueprint)
    return viewer, viewer_note


def _flush(rec: Any, viewer: bool) -> str | None:
    """Flush and close the stream: ``None``, or why a spawned viewer did not take the data. To a
    viewer within :data:`SPAWN_FLUSH_TIMEOUT` s: one that accepted the connection but stalls
    must not block an unbounded flush."""
    note = None
    if viewer:
        try:
            rec.flush(timeout_sec=SPAWN_FLUSH_TIMEOUT)
        except RuntimeError as exc:
            note = (f"the Rerun viewer did not take the recording within "
                    f"{SPAWN_FLUSH_TIMEOUT:g} s ({' '.join(str(exc).split())[:120]})")
    else:
        try:
            rec.flush()
        except RuntimeError as exc:     # its file sink stopped: a full disk, a file-size limit
            raise OSError(errno.EIO, "Rerun could not write the recording "
                          f"({' '.join(str(exc).split())})") from exc
    rec.disconnect()
    return note
