"""Rerun recordings of episodes: 3-D scene, time series, estimator internals and a blueprint.

:func:`record_episodes` turns the :class:`~pendulum_lqg.sim.Trajectory` objects that
``run_episodes(..., trajectory=True)`` returns into one Rerun recording (a ``.rrd`` file and/or a
spawned viewer). Nothing here runs the simulation: the closed loop stays in :mod:`pendulum_lqg.sim`,
and a run without ``--record`` never imports this module's heavy dependency (``rerun`` is imported
inside the functions that need it), so recording off costs nothing in the loop.

Every sample goes through ``RecordingStream.send_columns`` (one call per entity per episode); only the
static geometry, styles and text documents use ``log``.

Entity tree (one recording, each episode under its own prefix ``/episode_NNNN``; all times on the
``sim_time`` timeline, in seconds from the episode start):

=====================================  ==========================================================
``/config``                            the run: configuration, scenario, plant parameters, seed,
                                       gains and design poles (Markdown, static)
``/summary``                           one table row per recorded episode (Markdown, static)
``/episode_NNNN/outcome``              success or failure reason and time, cost and metrics
``/episode_NNNN/events``               a ``TextLog`` entry at the failure time
``…/world/<geom>``                     world geoms from the MJCF (floor, rail, rail stops)
``…/world/track_limits``               the failure limits ``±track_limit`` of the cart centre
``…/world/cart``                       cart body, translated by the true ``p`` (physics rate);
                                       its geoms below it
``…/world/cart/pole``                  pole body, rotated by the true ``θ`` about the hinge axis
``…/world/estimate[/pole]``            translucent ghost of the estimated pose ``x̂`` (control rate)
``…/world/failure``                    a labelled point where the episode failed
``…/state/<x>/true``                   true ``p, θ, ṗ, θ̇`` at the physics rate
``…/state/<x>/estimate``               ``x̂`` at the control rate (held between samples)
``…/state/<p|theta>/measured``         noisy measurements ``y`` (points)
``…/control/u``, ``…/control/limits``  applied force and the saturation limits ``±u_max``
``…/cost/J``                           running cost ``J(t)``, 0 at ``t = 0``
``…/estimation/error/<x>``             ``x̂ − x`` and, when the filter has a covariance, ``±2σ``
                                       from ``P`` (a-posteriori)
``…/estimation/innovation/<p|theta>``  innovations ``y − C x̄``
=====================================  ==========================================================

The estimate ghost and the ``estimation`` group are left out for the true-state "observer".

The blueprint sent with the recording has one tab per episode (the first :data:`MAX_EPISODE_TABS`):
the 3-D view above the outcome / configuration / event documents on the left, the four state plots
in the middle, control, cost and estimator plots on the right; plus an overview tab (θ and J of every
episode) and the episode table when more than one episode is recorded.
"""

from __future__ import annotations

import collections
import json
import subprocess
import sys
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import mujoco
import numpy as np

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.jsonio import plain
from pendulum_lqg.plant import CART_BODY, HINGE, POLE_BODY, SLIDER, STATE_NAMES, Plant

if TYPE_CHECKING:
    from pendulum_lqg.policy import Policy
    from pendulum_lqg.sim import Scenario, Trajectory

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


def _start_viewer(rec: Any) -> tuple[bool, str | None]:
    """Spawn a native Rerun viewer and wait (at most :data:`VIEWER_WAIT` s) until it listens.

    Returns ``(reachable, note)``; ``note`` says in one line why no viewer will get the data: no
    display on Linux (a viewer would never come up, so none is started), no ``rerun`` executable,
    or no viewer listening in time. Nothing here can block for longer than the wait.
    """
    import os
    import socket
    import sys

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

_SYMBOLS = {"p": "p", "theta": "θ", "p_dot": "ṗ", "theta_dot": "θ̇"}
_UNITS = {"p": "m", "theta": "rad", "p_dot": "m/s", "theta_dot": "rad/s"}
_TRUE_COLOR = (31, 119, 180)
_EST_COLOR = (255, 127, 14)
_MEAS_COLOR = (120, 120, 120)
_BAND_COLOR = (160, 160, 160)
_LIMIT_COLOR = (214, 39, 40)
_GHOST_ALPHA = 90


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


@dataclass(frozen=True)
class RecordingContents:
    """A recording read back from a ``.rrd`` file with Rerun's own reader (:func:`read_recording`).

    Attributes
    ----------
    application_ids : application id of each recording store in the file
    recording_ids : recording id of each recording store
    blueprints : number of blueprint stores in the file
    entity_paths : every entity path with data, sorted
    rows : temporal rows per entity path (summed over chunks)
    static : entity paths with static data
    timelines : names of the timelines seen
    """

    application_ids: list[str]
    recording_ids: list[str]
    blueprints: int
    entity_paths: list[str]
    rows: dict[str, int]
    static: set[str]
    timelines: set[str]
    _path: Path = field(repr=False, default=Path())


@dataclass(frozen=True)
class VerifyResult:
    """Outcome of ``rerun rrd verify``: ``ok`` iff the command exited with 0; its output."""

    ok: bool
    returncode: int
    output: str


# ---- episode selection ----------------------------------------------------------------------
def telling_episodes(rows: Sequence[Mapping[str, Any]]) -> dict[str, int]:
    """Pick the episodes worth recording from a sweep's episode rows.

    Among the successful episodes, the ``best`` (lowest cost), ``median`` (the lower median by
    cost) and ``worst`` (highest cost); among the failures, the ``first_failure`` (lowest episode
    number). Labels whose episode is missing are left out (e.g. no ``first_failure`` when all
    succeed); several labels may name the same episode.

    Parameters
    ----------
    rows : episode records with at least ``episode``, ``success`` and ``cost``
        (:data:`~pendulum_lqg.metrics.EPISODE_FIELDS`)

    Returns
    -------
    label → episode number, in the order best, median, worst, first_failure
    """
    for i, r in enumerate(rows):
        missing = [k for k in ("episode", "success", "cost") if k not in r]
        if missing:
            raise ConfigError(f"rows[{i}]: missing key {missing[0]!r}; telling_episodes needs "
                              "'episode', 'success' and 'cost'")
    ok = [r for r in rows if bool(r["success"]) and np.isfinite(float(r["cost"]))]
    ok.sort(key=lambda r: (float(r["cost"]), int(r["episode"])))
    out: dict[str, int] = {}
    if ok:
        out["best"] = int(ok[0]["episode"])
        out["median"] = int(ok[(len(ok) - 1) // 2]["episode"])
        out["worst"] = int(ok[-1]["episode"])
    failed = [int(r["episode"]) for r in rows if not bool(r["success"])]
    if failed:
        out["first_failure"] = min(failed)
    return out


# ---- geometry from the MJCF -----------------------------------------------------------------
@dataclass(frozen=True)
class _Geom:
    name: str
    type: int
    size: np.ndarray
    pos: np.ndarray
    quat_xyzw: np.ndarray
    rgba: np.ndarray


def _body_geoms(plant: Plant, body: str | int) -> list[_Geom]:
    m = plant.model
    bid = m.body(body).id
    out = []
    for gid in range(m.ngeom):
        g = m.geom(gid)
        if int(g.bodyid[0]) != bid:
            continue
        rgba = np.array(g.rgba, dtype=float)
        if int(g.matid[0]) >= 0:
            rgba = np.array(m.mat_rgba[int(g.matid[0])], dtype=float)
        if int(g.type[0]) == mujoco.mjtGeom.mjGEOM_PLANE:
            rgba = np.array([0.32, 0.32, 0.35, 1.0])   # MuJoCo textures it; a plain floor here
        w, x, y, z = g.quat
        out.append(_Geom(name=g.name or f"geom_{gid}", type=int(g.type[0]),
                         size=np.array(g.size, dtype=float), pos=np.array(g.pos, dtype=float),
                         quat_xyzw=np.array([x, y, z, w]), rgba=rgba))
    return out


def _rgba8(rgba: np.ndarray, alpha: int | None = None) -> list[int]:
    c = [round(255 * float(v)) for v in np.clip(rgba, 0.0, 1.0)]
    if alpha is not None:
        c[3] = alpha
    return c


def _geom_archetype(rr: Any, g: _Geom, alpha: int | None = None) -> Any | None:
    """A Rerun archetype drawing MuJoCo geom ``g`` in its body frame (None if unsupported)."""
    color = [_rgba8(g.rgba, alpha)]
    gt = mujoco.mjtGeom
    q = rr.Quaternion(xyzw=g.quat_xyzw)
    if g.type == gt.mjGEOM_BOX:
        return rr.Boxes3D(half_sizes=[g.size], centers=[g.pos], quaternions=[q], colors=color,
                          fill_mode="solid")
    if g.type == gt.mjGEOM_PLANE:
        half = [g.size[0] or 5.0, g.size[1] or 5.0, 1e-3]
        return rr.Boxes3D(half_sizes=[half], centers=[g.pos], quaternions=[q], colors=color,
                          fill_mode="solid")
    if g.type == gt.mjGEOM_CYLINDER:
        return rr.Cylinders3D(lengths=[2 * g.size[1]], radii=[g.size[0]], centers=[g.pos],
                              quaternions=[q], colors=color, fill_mode="solid")
    if g.type == gt.mjGEOM_CAPSULE:
        # Rerun's capsule runs from its origin along +z; MuJoCo's is centred on pos.
        rot = np.zeros(9)
        w, x, y, z = g.quat_xyzw[3], *g.quat_xyzw[:3]
        mujoco.mju_quat2Mat(rot, np.array([w, x, y, z]))
        start = g.pos - rot.reshape(3, 3) @ np.array([0.0, 0.0, g.size[1]])
        return rr.Capsules3D(lengths=[2 * g.size[1]], radii=[g.size[0]], translations=[start],
                             quaternions=[q], colors=color)
    if g.type in (gt.mjGEOM_SPHERE, gt.mjGEOM_ELLIPSOID):
        half = [g.size[0]] * 3 if g.type == gt.mjGEOM_SPHERE else list(g.size)
        return rr.Ellipsoids3D(half_sizes=[half], centers=[g.pos], quaternions=[q], colors=color,
                               fill_mode="solid")
    return None


def _hinge_quaternions(plant: Plant, theta: np.ndarray) -> np.ndarray:
    """(N, 4) xyzw quaternions of the pole body: its body quaternion, then θ about the hinge."""
    m = plant.model
    axis = np.asarray(m.joint(HINGE).axis, dtype=float)
    half = 0.5 * np.asarray(theta, dtype=float)
    qj = np.concatenate([np.sin(half)[:, None] * axis[None, :], np.cos(half)[:, None]], axis=1)
    w0, x0, y0, z0 = m.body(POLE_BODY).quat
    if np.allclose([w0, x0, y0, z0], [1, 0, 0, 0]):
        return qj
    # q_body ⊗ q_joint (Hamilton product, xyzw)
    v0 = np.array([x0, y0, z0])
    vj, wj = qj[:, :3], qj[:, 3]
    w = w0 * wj - vj @ v0
    v = w0 * vj + wj[:, None] * v0[None, :] + np.cross(np.broadcast_to(v0, vj.shape), vj)
    return np.concatenate([v, w[:, None]], axis=1)


def _eye(plant: Plant, camera: str = "side") -> Any | None:
    """Eye of the 3-D view from the MJCF camera ``camera`` (None if the model has none)."""
    import rerun.blueprint as rrb

    m = plant.model
    if mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_CAMERA, camera) < 0:
        return None
    cam = m.camera(camera)
    rot = np.asarray(cam.mat0, dtype=float).reshape(3, 3)   # columns: camera x, y, z in world
    pos = np.asarray(cam.pos0, dtype=float)
    forward, up = -rot[:, 2], rot[:, 1]
    dist = float(np.linalg.norm(pos)) or 1.0
    return rrb.EyeControls3D(kind=rrb.Eye3DKind.Orbital, position=pos,
                             look_target=pos + dist * forward, eye_up=up)


def _cart_translations(plant: Plant, p: np.ndarray) -> np.ndarray:
    m = plant.model
    axis = np.asarray(m.joint(SLIDER).axis, dtype=float)
    return np.asarray(m.body(CART_BODY).pos, dtype=float)[None, :] + np.asarray(p)[:, None] * axis


# ---- formatting -----------------------------------------------------------------------------
def _fmt(value: object) -> str:
    if isinstance(value, np.ndarray):
        if np.iscomplexobj(value):
            return "[" + ", ".join(_fmt(complex(v)) for v in value.ravel()) + "]"
        return np.array2string(value, separator=", ", max_line_width=100,
                               formatter={"float_kind": lambda v: f"{v:.6g}"})
    if isinstance(value, complex):
        if abs(value.imag) < 1e-12:
            return f"{value.real:.6g}"
        return f"{value.real:.6g}{value.imag:+.6g}j"
    if isinstance(value, float):
        return f"{value:.6g}"
    return str(value)


def _flatten(data: object, prefix: str = "") -> dict[str, Any]:
    """Nested mappings as ``{"a.b": value}`` (lists stay values)."""
    if not isinstance(data, Mapping):
        return {prefix: data}
    out: dict[str, Any] = {}
    for k, v in data.items():
        key = f"{prefix}.{k}" if prefix else str(k)
        if isinstance(v, Mapping) and v:
            out.update(_flatten(v, key))
        else:
            out[key] = v
    return out


def _config_markdown(plant: Plant, scenario: Scenario, policy: Policy,
                     config: Mapping[str, object]) -> str:
    info = policy.info
    lines = [f"# Run: {policy.name}", ""]
    if "seed" in config:
        lines.append(f"* **seed**: `{config['seed']}` (episode seeds: "
                     "`SeedSequence(seed, spawn_key=(episode,))`)")
    lines += [f"* **policy**: `{policy.name}`, u = sat(−K x̂), |u| ≤ {plant.u_max:g} N",
              f"* **control period**: {scenario.control_period:g} s, "
              f"physics step {plant.timestep:g} s", "", "## Gains and design poles", ""]
    for key, label in (("K", "controller gain K"), ("L", "observer gain L"),
                       ("controller_poles", "closed-loop controller poles (z)"),
                       ("observer_poles", "observer poles (z)"),
                       ("observer_poles_continuous", "observer poles (s)")):
        if key in info:
            lines += [f"**{label}**", "", "```", _fmt(np.asarray(info[key])), "```", ""]
    for title, data in (("Configuration", config), ("Scenario", scenario.to_dict())):
        lines += [f"## {title}", "", "| key | value |", "|---|---|"]
        lines += [f"| {k} | `{json.dumps(v, default=str)}` |"
                  for k, v in _flatten(plain(dict(data), nonfinite_as_string=True)).items()]
        lines.append("")
    lines += ["## Plant (read from the MJCF)", "", f"model: `{plant.path}`", "",
              "| parameter | value |", "|---|---|"]
    lines += [f"| {k} | {_fmt(v)} |" for k, v in plant.parameters().items()]
    return "\n".join(lines) + "\n"


def _outcome_title(tr: Trajectory) -> str:
    row = tr.row
    if bool(row.get("success", False)):
        return f"Episode {tr.episode}: success (cost J = {float(row['cost']):.4g})"  # type: ignore[arg-type]
    return (f"Episode {tr.episode}: FAILED, {row.get('failure_reason', '?')} at "
            f"t = {float(row.get('time_to_failure', np.nan)):.3f} s")  # type: ignore[arg-type]


def _outcome_markdown(tr: Trajectory, label: str | None) -> str:
    lines = [f"# {_outcome_title(tr)}", ""]
    if label:
        lines += [f"Recorded as: **{label}**", ""]
    lines += [f"* episode seed: `{tr.seed}`", "", "| metric | value |", "|---|---|"]
    lines += [f"| {k} | {_fmt(v)} |" for k, v in tr.row.items()]
    return "\n".join(lines) + "\n"


def _summary_markdown(trajectories: Sequence[Trajectory], labels: Mapping[int, str]) -> str:
    lines = ["# Recorded episodes", "",
             "| episode | label | seed | outcome | time to failure [s] | cost J |",
             "|---|---|---|---|---|---|"]
    for tr in trajectories:
        r = tr.row
        outcome = "success" if bool(r.get("success")) else f"failed: {r.get('failure_reason')}"
        lines.append(f"| {tr.episode} | {labels.get(tr.episode, '')} | {tr.seed} | {outcome} | "
                     f"{_fmt(float(r.get('time_to_failure', np.nan)))} | "  # type: ignore[arg-type]
                     f"{_fmt(float(r.get('cost', np.nan)))} |")  # type: ignore[arg-type]
    return "\n".join(lines) + "\n"


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
    for g in _body_geoms(plant, 0):
        arch = _geom_archetype(rr, g)
        if arch is not None:
            w.static(f"{world}/{g.name}", arch)
    L = plant.track_limit
    z = 0.25
    w.static(f"{world}/track_limits", rr.LineStrips3D(
        [[[-L, 0.0, -z], [-L, 0.0, z]], [[L, 0.0, -z], [L, 0.0, z]]],
        radii=0.006, colors=[_LIMIT_COLOR], labels=[f"p = −{L:g} m", f"p = +{L:g} m"]))
    for g in _body_geoms(plant, CART_BODY):
        arch = _geom_archetype(rr, g)
        if arch is not None:
            w.static(f"{world}/cart/{g.name}", arch)
    for g in _body_geoms(plant, POLE_BODY):
        arch = _geom_archetype(rr, g)
        if arch is not None:
            w.static(f"{world}/cart/pole/{g.name}", arch)
    if ghost:
        for g in _body_geoms(plant, CART_BODY):
            arch = _geom_archetype(rr, g, alpha=_GHOST_ALPHA)
            if arch is not None:
                w.static(f"{world}/estimate/{g.name}", arch)
        for g in _body_geoms(plant, POLE_BODY):
            arch = _geom_archetype(rr, g, alpha=_GHOST_ALPHA)
            if arch is not None:
                w.static(f"{world}/estimate/pole/{g.name}", arch)


def _record_episode(w: _Writer, plant: Plant, tr: Trajectory, pre: str, *, estimated: bool,
                    label: str | None, u_max: float) -> None:
    rr = w.rr
    ep = tr.episode
    world = f"{pre}/world"
    _record_scene_static(w, plant, pre, ghost=estimated)

    # --- 3-D animation from the true state (physics rate) and the estimate (control rate)
    t_ph, x_ph = physics_samples(tr, plant)
    w.columns(f"{world}/cart", t_ph,
              rr.Transform3D.columns(translation=_cart_translations(plant, x_ph[:, 0])))
    w.columns(f"{world}/cart/pole", t_ph, rr.Transform3D.columns(
        translation=np.broadcast_to(plant.model.body(POLE_BODY).pos, (t_ph.size, 3)),
        quaternion=_hinge_quaternions(plant, x_ph[:, 1])))
    t = np.asarray(tr.t, dtype=float)
    if estimated:
        w.columns(f"{world}/estimate", t,
                  rr.Transform3D.columns(translation=_cart_translations(plant, tr.x_hat[:, 0])))
        w.columns(f"{world}/estimate/pole", t, rr.Transform3D.columns(
            translation=np.broadcast_to(plant.model.body(POLE_BODY).pos, (t.size, 3)),
            quaternion=_hinge_quaternions(plant, tr.x_hat[:, 1])))

    # --- state plots: true (physics rate), estimate (held), measurements (points)
    for i, name in enumerate(STATE_NAMES):
        sym, base = _SYMBOLS[name], f"{pre}/state/{name}"
        w.static(f"{base}/true", _lines(rr, [f"{sym} true · ep {ep}"], [_TRUE_COLOR], [1.5]))
        w.scalars(f"{base}/true", t_ph, x_ph[:, i])
        if estimated:
            w.static(f"{base}/estimate", _lines(rr, [f"{sym} estimate"], [_EST_COLOR], [1.2],
                                                step=True))
            w.scalars(f"{base}/estimate", t, tr.x_hat[:, i])
        if i < 2:
            w.static(f"{base}/measured", rr.SeriesPoints(
                names=[f"{sym} measured"], colors=[_MEAS_COLOR], markers=["circle"],
                marker_sizes=[1.5]))
            w.scalars(f"{base}/measured", t, tr.y[:, i])

    # --- control with its limits; running cost
    w.static(f"{pre}/control/u", _lines(rr, ["u applied"], [_TRUE_COLOR], [1.5], step=True))
    w.scalars(f"{pre}/control/u", t, tr.u)
    t_end = float(t_ph[-1])
    w.static(f"{pre}/control/limits", _lines(rr, ["+u_max", "−u_max"],
                                             [_LIMIT_COLOR, _LIMIT_COLOR], [1.0, 1.0]))
    w.scalars(f"{pre}/control/limits", np.array([0.0, t_end]),
              np.array([[u_max, -u_max], [u_max, -u_max]]))
    # cost[n] is J at the end of period n: t[n] + T, or the failure time for the last one
    dt = float(t[1] - t[0]) if t.size > 1 else float(t_ph[-1])
    t_cost = np.concatenate([[0.0], t + dt])
    t_cost[-1] = min(t_cost[-1], t_end)
    w.static(f"{pre}/cost/J", _lines(rr, [f"J · ep {ep}"], [(44, 160, 44)], [1.5]))
    w.scalars(f"{pre}/cost/J", t_cost, np.concatenate([[0.0], tr.cost]))

    # --- estimator internals
    if estimated:
        err = tr.x_hat - tr.x
        P = np.asarray(tr.P, dtype=float)
        has_cov = bool(np.all(np.isfinite(P)))
        for i, name in enumerate(STATE_NAMES):
            sym, path = _SYMBOLS[name], f"{pre}/estimation/error/{name}"
            if has_cov:
                two_sigma = 2.0 * np.sqrt(np.clip(P[:, i, i], 0.0, None))
                w.static(path, _lines(rr, [f"{sym}̂ − {sym}", "+2σ", "−2σ"],
                                      [_EST_COLOR, _BAND_COLOR, _BAND_COLOR], [1.2, 1.0, 1.0]))
                w.scalars(path, t, np.stack([err[:, i], two_sigma, -two_sigma], axis=1))
            else:
                w.static(path, _lines(rr, [f"{sym}̂ − {sym}"], [_EST_COLOR], [1.2]))
                w.scalars(path, t, err[:, i])
        for i, name in enumerate(("p", "theta")):
            path = f"{pre}/estimation/innovation/{name}"
            w.static(path, _lines(rr, [f"ν_{_SYMBOLS[name]} [{_UNITS[name]}]"],
                                  [(148, 103, 189) if i else (23, 190, 207)], [1.0]))
            w.scalars(path, t, tr.innovation[:, i])

    # --- outcome
    w.static(f"{pre}/outcome", rr.TextDocument(_outcome_markdown(tr, label),
                                               media_type=rr.MediaType.MARKDOWN))
    ttf = float(tr.row.get("time_to_failure", np.nan))  # type: ignore[arg-type]
    if not bool(tr.row.get("success", False)) and np.isfinite(ttf):
        reason = str(tr.row.get("failure_reason", "failed"))
        w.log_at(f"{pre}/events", ttf, rr.TextLog(f"episode {ep} failed: {reason} at "
                                                  f"t = {ttf:.3f} s", level=rr.TextLogLevel.ERROR))
        x_f = x_ph[-1]
        w.log_at(f"{world}/failure", ttf, rr.Points3D(
            [_cart_translations(plant, x_f[:1])[0] + [0.0, 0.0, plant.pole_length + 0.2]],
            radii=[0.05],
            colors=[_LIMIT_COLOR], labels=[f"{reason} @ {ttf:.3f} s"], show_labels=True))
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
            rrb.TimeSeriesView(origin=f"{pre}/state/{n}", name=f"{_SYMBOLS[n]} [{_UNITS[n]}]")
            for n in STATE_NAMES])
        right_views: list[Any] = [
            rrb.TimeSeriesView(origin=f"{pre}/control", name="control u [N] and ±u_max"),
            rrb.TimeSeriesView(origin=f"{pre}/cost", name="running cost J(t)")]
        if estimated:
            err_name = "x̂ − x ± 2σ" if covariance else "x̂ − x"
            right_views.append(rrb.Tabs(
                rrb.Grid(*[rrb.TimeSeriesView(origin=f"{pre}/estimation/error/{n}",
                                              name=f"{err_name}: {_SYMBOLS[n]}")
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

    t_start = time.perf_counter()
    import rerun as rr

    estimated = not policy.needs_state
    covariance = estimated and all(bool(np.all(np.isfinite(tr.P))) for tr in trajectories)
    width = max(4, len(str(max(episodes))))
    prefixes = [(episode_prefix(tr.episode, width), tr, by_episode.get(int(tr.episode)))
                for tr in trajectories]
    blueprint = _blueprint(prefixes, estimated=estimated, covariance=covariance, eye=_eye(plant))

    rec = rr.RecordingStream(application_id)
    out_path = Path(path) if path is not None else None
    if out_path is not None:
        out_path.parent.mkdir(parents=True, exist_ok=True)
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
    rec.send_recording_name(f"{policy.name}: {len(trajectories)} episode(s)")

    w = _Writer(rr, rec)
    w.static("/config", rr.TextDocument(_config_markdown(plant, scenario, policy, config),
                                        media_type=rr.MediaType.MARKDOWN))
    w.static("/summary", rr.TextDocument(_summary_markdown(trajectories, by_episode),
                                         media_type=rr.MediaType.MARKDOWN))
    for pre, tr, label in prefixes:
        _record_episode(w, plant, tr, pre, estimated=estimated, label=label, u_max=plant.u_max)
    viewer_reached: bool | None = None if not spawn else viewer
    if viewer:
        # a viewer that accepted the connection but stalls must not block an unbounded flush
        try:
            rec.flush(timeout_sec=SPAWN_FLUSH_TIMEOUT)
        except RuntimeError as exc:
            viewer_reached = False
            viewer_note = (f"the Rerun viewer did not take the recording within "
                           f"{SPAWN_FLUSH_TIMEOUT:g} s ({' '.join(str(exc).split())[:120]})")
    else:
        rec.flush()
    rec.disconnect()
    seconds = time.perf_counter() - t_start
    size = out_path.stat().st_size if out_path is not None and out_path.exists() else 0
    return RecordingStats(episodes=len(trajectories), entities=len(w.entities), rows=w.rows,
                          seconds=seconds, seconds_logging=w.seconds, path=out_path, bytes=size,
                          viewer_reached=viewer_reached, viewer_note=viewer_note)


# ---- reading back and verifying -------------------------------------------------------------
def read_recording(path: str | Path) -> RecordingContents:
    """Read a ``.rrd`` file back with ``rerun.chunk.RrdReader``: stores, entities, row counts.

    Rows are counted per entity over the temporal chunks (a batch may span several chunks);
    static chunks are listed in ``static``.
    """
    from rerun.chunk import RrdReader

    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"path: no recording at {path}")
    reader = RrdReader(str(path))
    recs = reader.recordings()
    rows: collections.Counter[str] = collections.Counter()
    static: set[str] = set()
    timelines: set[str] = set()
    entities: set[str] = set()
    for chunk in reader.stream():
        entities.add(chunk.entity_path)
        if chunk.is_static:
            static.add(chunk.entity_path)
        else:
            rows[chunk.entity_path] += int(chunk.num_rows)
            timelines.update(chunk.timeline_names)
    return RecordingContents(
        application_ids=[r.application_id for r in recs], recording_ids=[r.recording_id for r in recs],
        blueprints=len(reader.blueprints()), entity_paths=sorted(entities), rows=dict(rows),
        static=static, timelines=timelines, _path=path)


def read_column(path: str | Path, entity: str, component: str = "Scalars:scalars",
                ) -> tuple[np.ndarray, np.ndarray]:
    """Times [s] (M,) and values of one component of one entity, read back from a ``.rrd``.

    Values come back as an (M, k) float array for list components (``Scalars`` with k series);
    rows are sorted by time. Text components come back as an object array of strings.
    """
    from rerun.chunk import RrdReader

    times: list[np.ndarray] = []
    values: list[Any] = []
    for chunk in RrdReader(str(path)).stream():
        if chunk.entity_path != entity:
            continue
        rb = chunk.to_record_batch()
        names = rb.schema.names
        col = next((n for n in names if n == component or n.endswith(":" + component)), None)
        if col is None:
            continue
        vals = rb.column(col).to_pylist()
        if TIMELINE in names:
            t = rb.column(TIMELINE).cast("int64").to_numpy(zero_copy_only=False) * 1e-9
        else:
            t = np.full(len(vals), np.nan)
        times.append(np.asarray(t, dtype=float))
        values.extend(vals)
    if not times:
        raise ConfigError(f"entity: no component {component!r} for {entity!r} in {path}")
    t_all = np.concatenate(times)
    order = np.argsort(t_all, kind="stable")
    first = next((v for v in values if v is not None), None)
    if isinstance(first, list) and first and not isinstance(first[0], str):
        arr = np.array([v for v in values], dtype=float)
    else:
        arr = np.array([v[0] if isinstance(v, list) and len(v) == 1 else v for v in values],
                       dtype=object)
    return t_all[order], arr[order]


def rerun_executable() -> Path:
    """The ``rerun`` command installed with rerun-sdk (next to the running interpreter)."""
    exe = Path(sys.executable).parent / ("rerun.exe" if sys.platform == "win32" else "rerun")
    if not exe.is_file():
        raise ConfigError(f"rerun: the rerun CLI is not installed next to {sys.executable}")
    return exe


def verify_recording(path: str | Path, *, timeout: float = 120.0) -> VerifyResult:
    """Run ``rerun rrd verify PATH`` (Rerun's own consistency check of a recording file)."""
    proc = subprocess.run([str(rerun_executable()), "rrd", "verify", str(path)],
                          capture_output=True, text=True, timeout=timeout, check=False)
    return VerifyResult(ok=proc.returncode == 0, returncode=proc.returncode,
                        output=(proc.stdout + proc.stderr).strip())
