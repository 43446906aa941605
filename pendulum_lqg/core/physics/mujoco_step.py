"""A plain ``mj_step`` loop, one row after another: the reference the batch is tested against."""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np

if TYPE_CHECKING:
    from pendulum_lqg.core.period import PeriodView
    from pendulum_lqg.model.interface import MujocoPlant

#: MuJoCo's warnings for an unstable state (it then resets the data).
INSTABILITY_WARNINGS = tuple(int(w) for w in (mujoco.mjtWarning.mjWARN_BADQPOS,
                                              mujoco.mjtWarning.mjWARN_BADQVEL,
                                              mujoco.mjtWarning.mjWARN_BADQACC))


class StepPhysics:
    """The :class:`~pendulum_lqg.core.physics.base.Physics` of ``mujoco.mj_step`` on one ``MjData``.

    Each row starts from ``mj_resetData`` with its state written in, as :class:`BatchPhysics
    <pendulum_lqg.core.physics.mujoco_batch.BatchPhysics>` does, so both give bit-identical states;
    a row whose simulation becomes unstable stops and holds the state reached, as the batch does.
    """

    def __init__(self, plant: MujocoPlant, k: int) -> None:
        self.plant, self.k = plant, k
        self.data = mujoco.MjData(plant.model)
        self.models: list[mujoco.MjModel] | None = None

    def set_models(self, models: list[mujoco.MjModel]) -> None:
        self.models = list(models)

    def advance(self, x: np.ndarray, u: np.ndarray, forces: np.ndarray | None,
                out: PeriodView) -> np.ndarray | None:
        """See :meth:`Physics.advance <pendulum_lqg.core.physics.base.Physics.advance>`."""
        m, d, k = self.plant.model, self.data, self.k
        h = self.plant.timestep
        states = out.states
        n = out.n
        reset = np.zeros(n, dtype=bool)
        qi, vi = self.plant.qpos_index, self.plant.qvel_index
        nq = len(qi)
        # x is the deviation from the equilibrium q*; MuJoCo's qpos is q* + x[:nq]
        offset = self.plant.x_offset
        eq = 0.0 if offset is None else offset[:nq]
        if offset is not None:
            x = x + offset
        gear = self.plant.ctrl_gear                         # ctrl = u / gear (u in N or N·m)
        if gear != 1.0:
            u = u / gear
        per_step = u.ndim == 2                             # actuator lag: a force per step
        for r in range(n):
            if self.models is not None:
                m = self.models[r]
            mujoco.mj_resetData(m, d)
            d.qpos[qi] = x[r, :nq]
            d.qvel[vi] = x[r, nq:]
            d.ctrl[0] = u[r, 0] if per_step else u[r]
            for j in range(k):
                if per_step:
                    d.ctrl[0] = u[r, j]
                if forces is not None:
                    d.qfrc_applied[vi] = forces[r, j]
                mujoco.mj_step(m, d)
                states[r, j, :nq] = d.qpos[qi] - eq if offset is not None else d.qpos[qi]
                states[r, j, nq:] = d.qvel[vi]
                if any(d.warning[w].number for w in INSTABILITY_WARNINGS):
                    # MuJoCo reset the data after an instability: as the batch's rollout does, stop
                    # and hold the state reached for the rest of the period
                    states[r, j + 1:] = states[r, j]
                    reset[r] = True
                    break
            else:
                reset[r] = abs(d.time - k * h) > 0.5 * h
        return reset if reset.any() else None
