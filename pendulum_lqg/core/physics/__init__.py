"""Physics backends behind one interface (:class:`~pendulum_lqg.core.physics.base.Physics`).

====================  ==========================================================  ============
backend               what steps the plant                                        module
====================  ==========================================================  ============
``"rollout"``         ``mujoco.batch.Batch``, one simulation per row, on threads  mujoco_batch
``"step"``            a plain ``mj_step`` loop, one row after another             mujoco_step
``linear-zoh/euler``  the model's linearisation (``Scenario.plant``), numpy       linear
====================  ==========================================================  ============

================  ======================================================================
module            concept
================  ======================================================================
``base``          :class:`~pendulum_lqg.core.physics.base.Physics`, the interface
``mujoco_batch``  ``"rollout"``: MuJoCo's batch rollout
``mujoco_step``   ``"step"``: the plain ``mj_step`` loop
``linear``        the exact (or Euler) linear step
================  ======================================================================

All MuJoCo backends start each period from ``mj_resetData`` with the row's state written in, so
they give bit-identical states. A new backend is one class in one new file implementing
:class:`~pendulum_lqg.core.physics.base.Physics`, and a branch in :func:`make_physics`.
"""

from __future__ import annotations

import os
from typing import TYPE_CHECKING, cast

import numpy as np

from pendulum_lqg.core.physics.base import Physics
from pendulum_lqg.core.physics.linear import LinearPhysics
from pendulum_lqg.core.physics.mujoco_batch import BatchPhysics
from pendulum_lqg.core.physics.mujoco_step import StepPhysics
from pendulum_lqg.errors import ConfigError

if TYPE_CHECKING:
    from pendulum_lqg.model.interface import MujocoPlant, SimulatedPlant

#: The MuJoCo backends a simulator can be asked for (``Simulator(backend=…)``).
BACKENDS: tuple[str, ...] = ("rollout", "step")


def make_physics(plant: SimulatedPlant, *, plant_kind: str, backend: str, capacity: int, nthread: int,
                 k: int) -> Physics:
    """The backend for a scenario's ``plant`` (``"mujoco"`` or a linear kind) and a MuJoCo
    ``backend``, with room for ``capacity`` rows and ``nthread`` physics threads; a kind the
    plant cannot be stepped by (not in its ``simulators``) is refused, one line naming ``plant``."""
    if plant_kind not in plant.simulators:
        raise ConfigError(f"plant: expected one of {', '.join(plant.simulators)} for this plant, "
                          f"got {plant_kind!r}")
    if plant_kind != "mujoco":
        return LinearPhysics(plant, plant_kind, k)
    mj = cast("MujocoPlant", plant)            # its simulators name MuJoCo: a MuJoCo plant
    if backend == "rollout":
        return BatchPhysics(mj, capacity, nthread, k)
    if backend == "step":
        return StepPhysics(mj, k)
    raise ConfigError(f"backend: expected one of {', '.join(BACKENDS)}, got {backend!r}")


def thread_count(nthread: int | None) -> int:
    """Physics threads for a request: ``None`` → the CPU cores this process may use, at most 8;
    a number → itself, capped to those cores (more threads than cores only add hand-offs, and
    thousands of them can exhaust the process)."""
    if nthread is None:
        return min(8, _cpu_count())
    if isinstance(nthread, bool) or not isinstance(nthread, int | np.integer) or nthread < 0:
        raise ConfigError(f"nthread: expected a non-negative integer, got {nthread!r}")
    return min(int(nthread), _cpu_count())


def _cpu_count() -> int:
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - non-Linux
        return max(1, os.cpu_count() or 1)


__all__ = ["BACKENDS", "BatchPhysics", "LinearPhysics", "Physics", "StepPhysics", "make_physics",
           "thread_count"]
