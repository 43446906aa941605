"""Offscreen frames of a plant for the environments' ``render()``: the cart-pole from its side
camera, any other MuJoCo plant from a camera tracking its first body."""

from __future__ import annotations

import os
from typing import Any

import mujoco
import numpy as np

from pendulum_lqg.envs.config import positive_int
from pendulum_lqg.errors import ConfigError, PendulumLQGError
from pendulum_lqg.model.plant import CART_BODY, Plant

#: Rendering camera: tracks the cart from the side (the view of the XML's ``side`` camera, but
#: close enough to frame cart and pole), at this many pole lengths away.
CAMERA_DISTANCE_POLE_LENGTHS = 3.0


class Frames:
    """Offscreen frames of the cart-pole at given states: a side view tracking the cart."""

    def __init__(self, plant: Any, width: int, height: int) -> None:
        self.plant, self.width, self.height = plant, width, height
        self._renderer: mujoco.Renderer | None = None
        self._data: mujoco.MjData | None = None
        self._camera: mujoco.MjvCamera | None = None

    def frame(self, x: np.ndarray) -> np.ndarray:
        """An RGB image (height, width, 3) uint8 of the plant's state ``x``."""
        model = self.plant.model
        cartpole = isinstance(self.plant, Plant)
        if self._renderer is None:
            self._renderer = make_renderer(model, self.height, self.width)
            self._data = mujoco.MjData(model)
            cam = mujoco.MjvCamera()
            cam.type = mujoco.mjtCamera.mjCAMERA_TRACKING
            if cartpole:
                cam.trackbodyid = model.body(CART_BODY).id
                cam.distance = CAMERA_DISTANCE_POLE_LENGTHS * self.plant.pole_length
            else:               # the first body below the world, the model's extent away
                cam.trackbodyid = 1 if model.nbody > 1 else 0
                cam.distance = 2.0 * float(model.stat.extent)
            cam.azimuth, cam.elevation = 90.0, -10.0      # from −y, x to the right: a side view
            self._camera = cam
        assert self._data is not None
        if cartpole:
            self.plant.set_state(self._data, x)
        else:                       # x = [q − q*, q̇] of the plant's joints
            nq = len(self.plant.qpos_index)
            self._data.qpos[self.plant.qpos_index] = self.plant.joints.qpos_eq + x[:nq]
            self._data.qvel[self.plant.qvel_index] = x[nq:]
            mujoco.mj_forward(model, self._data)
        self._renderer.update_scene(self._data, camera=self._camera)
        return self._renderer.render()

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
        self._renderer = self._data = self._camera = None

    def __getstate__(self) -> dict[str, Any]:
        # GL resources (and the camera, which does not pickle) are made again on demand
        return {**self.__dict__, "_renderer": None, "_data": None, "_camera": None}


def make_renderer(model: mujoco.MjModel, height: int, width: int) -> mujoco.Renderer:
    """``mujoco.Renderer``, or a one-line error that says which OpenGL backend to choose."""
    try:
        return mujoco.Renderer(model, height, width)
    except Exception as exc:
        backend = os.environ.get("MUJOCO_GL", "glfw (the default)")
        detail = " ".join(str(exc).split())[:160]
        raise PendulumLQGError(
            f"render: MuJoCo could not create an OpenGL context with MUJOCO_GL={backend} "
            f"({type(exc).__name__}: {detail}); on a machine without a display set MUJOCO_GL=egl "
            "(or osmesa) before mujoco is first imported (pendulum_lqg does this itself when it "
            "is imported first)") from exc


def check_renderable(plant: Any, render_mode: str | None) -> None:
    """Refuse ``render_mode="rgb_array"`` for a plant without a MuJoCo model (one line)."""
    if render_mode is not None and getattr(plant, "model", None) is None:
        raise ConfigError(f"render_mode: the plant {plant.name!r} is given as matrices and has "
                          f"no scene to draw; use render_mode=None")


def image_size(plant: Any, width: int, height: int) -> tuple[int, int]:
    width, height = positive_int("width", width), positive_int("height", height)
    if getattr(plant, "model", None) is None:        # a plant given as matrices: nothing to draw
        return width, height
    vis = plant.model.vis.global_
    for name, value, limit, attr in (("width", width, vis.offwidth, "offwidth"),
                                     ("height", height, vis.offheight, "offheight")):
        if value > limit:           # name the one that is too large (both: the width first)
            raise ConfigError(f"{name}: at most {limit} pixels (the model's offscreen buffer, "
                              f"<visual><global {attr}>), got {value}")
    return width, height
