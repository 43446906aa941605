"""The cart-pole's MJCF geometry as Rerun archetypes: geoms, poses and the camera of the 3-D view."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from pendulum_lqg.model.plant import CART_BODY, HINGE, POLE_BODY, SLIDER, Plant

SYMBOLS = {"p": "p", "theta": "θ", "p_dot": "ṗ", "theta_dot": "θ̇"}


UNITS = {"p": "m", "theta": "rad", "p_dot": "m/s", "theta_dot": "rad/s"}


TRUE_COLOR = (31, 119, 180)


EST_COLOR = (255, 127, 14)


MEAS_COLOR = (120, 120, 120)


BAND_COLOR = (160, 160, 160)


LIMIT_COLOR = (214, 39, 40)


GHOST_ALPHA = 90


# ---- geometry from the MJCF -----------------------------------------------------------------
@dataclass(frozen=True)
class Geom:
    name: str
    type: int
    size: np.ndarray
    pos: np.ndarray
    quat_xyzw: np.ndarray
    rgba: np.ndarray


def body_geoms(plant: Plant, body: str | int) -> list[Geom]:
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
        out.append(Geom(name=g.name or f"geom_{gid}", type=int(g.type[0]),
                         size=np.array(g.size, dtype=float), pos=np.array(g.pos, dtype=float),
                         quat_xyzw=np.array([x, y, z, w]), rgba=rgba))
    return out


def rgba8(rgba: np.ndarray, alpha: int | None = None) -> list[int]:
    c = [round(255 * float(v)) for v in np.clip(rgba, 0.0, 1.0)]
    if alpha is not None:
        c[3] = alpha
    return c


def geom_archetype(rr: Any, g: Geom, alpha: int | None = None) -> Any | None:
    """A Rerun archetype drawing MuJoCo geom ``g`` in its body frame (None if unsupported)."""
    color = [rgba8(g.rgba, alpha)]
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


def hinge_quaternions(plant: Plant, theta: np.ndarray) -> np.ndarray:
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


def eye(plant: Plant, camera: str = "side") -> Any | None:
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


def cart_translations(plant: Plant, p: np.ndarray) -> np.ndarray:
    m = plant.model
    axis = np.asarray(m.joint(SLIDER).axis, dtype=float)
    return np.asarray(m.body(CART_BODY).pos, dtype=float)[None, :] + np.asarray(p)[:, None] * axis
