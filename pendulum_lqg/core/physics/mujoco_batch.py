"""MuJoCo's batch (``mujoco.batch.Batch``, MuJoCo ≥ 4): one simulation per row, on threads."""

from __future__ import annotations

from typing import TYPE_CHECKING

import mujoco
import numpy as np
from mujoco.batch import Batch

from pendulum_lqg.core.period import as_slice
from pendulum_lqg.errors import ConfigError

if TYPE_CHECKING:
    from pendulum_lqg.core.period import PeriodView
    from pendulum_lqg.plant import Plant


class BatchPhysics:
    """The :class:`~pendulum_lqg.core.physics.base.Physics` of a batch of rows on ``mujoco.batch``.

    Each period starts every row from a freshly reset ``MjData`` state (``mj_resetData``'s values:
    time 0, no warm start) with the row's ``[p, θ, ṗ, θ̇]`` written in, exactly as the ``mj_step``
    backend does, so the two give bit-identical states. ``Batch.rollout`` then runs the k physics
    steps on the batch's threads (the calling thread among them, the GIL released) and records only
    ``qpos`` and ``qvel`` after each step — the failure rule and the cost need nothing else. A row
    whose MuJoCo warnings rise (an instability: MuJoCo resets its data) stops there and repeats its
    last record; its time then falls short of ``k·h``, which is how :meth:`advance` reports it.

    Parameters
    ----------
    plant : the nominal plant (its model is the batch's; rows may run other models of the same
        layout, :meth:`set_models`)
    capacity : rows; nthread : threads, the caller's included (0 or 1: the caller alone)
    k : physics steps per period
    aligned : record straight in the period buffer's layout (default: when the model allows it;
        ``False`` forces the general copy, for tests)
    """

    def __init__(self, plant: Plant, capacity: int, nthread: int, k: int, *,
                 aligned: bool | None = None) -> None:
        m = plant.model
        st = mujoco.mjtState
        self.model, self.capacity, self.k = m, capacity, k
        self.batch = Batch(m, capacity, nthread=max(1, nthread))
        spec = st.mjSTATE_INTEGRATION.value
        d = mujoco.MjData(m)
        mujoco.mj_resetData(m, d)
        #: the state row of a reset MjData: each period starts from it
        self.state0 = np.empty(self.batch.nstate)
        mujoco.mj_getState(m, d, self.state0, spec)

        def offset(component: int) -> int:      # the state vector is in component-bit order
            return int(mujoco.mj_stateSize(m, spec & (component - 1)))

        qpos0, qvel0 = offset(st.mjSTATE_QPOS.value), offset(st.mjSTATE_QVEL.value)
        self.ctrl_col = offset(st.mjSTATE_CTRL.value)
        # The columns a physics step changes — time, qpos, qvel, act, history and warm start — come
        # before the inputs (ctrl, applied forces, mocap, …), which it only reads; plugin state
        # (last) changes too, so a model with plugins resets its whole row.
        plugin = int(mujoco.mj_stateSize(m, st.mjSTATE_PLUGIN.value))
        self.dynamic = slice(0, self.batch.nstate if plugin else self.ctrl_col)
        self.state0_dynamic = self.state0[self.dynamic]
        self.x_cols = as_slice(np.concatenate([qpos0 + plant.qpos_index, qvel0 + plant.qvel_index]))
        # Aligned layout: when qpos and qvel are exactly [p, θ] and [ṗ, θ̇] (the shipped model),
        # each step is recorded as [time, p, θ, ṗ, θ̇] — five numbers like a row of the period buffer
        # [p, θ, ṗ, θ̇, u] one place later — so a row's k records are the buffer's numbers
        # 4 … 4+5k−1 of that row, copied as one run (see _store).
        can_align = (m.nq == 2 and m.nv == 2 and list(plant.qpos_index) == [0, 1]
                     and list(plant.qvel_index) == [0, 1])
        if aligned and not can_align:
            raise ConfigError("aligned: this model's qpos/qvel are not [p, θ], [ṗ, θ̇]")
        self.aligned = can_align if aligned is None else aligned
        if self.aligned:
            self.record_spec = int(st.mjSTATE_TIME | st.mjSTATE_QPOS | st.mjSTATE_QVEL)
            self.rec = np.empty((capacity, k, 5))
        else:
            self.record_spec = int(st.mjSTATE_QPOS | st.mjSTATE_QVEL)
            self.rec = np.empty((capacity, k, m.nq + m.nv))
        self.rec_cols = as_slice(np.concatenate([plant.qpos_index, m.nq + plant.qvel_index]))
        self.control_spec = int(st.mjSTATE_CTRL)
        self.force_control_spec = int(st.mjSTATE_CTRL | st.mjSTATE_QFRC_APPLIED)
        ncontrol = mujoco.mj_stateSize(m, self.force_control_spec)
        self.ctrl_buf = np.zeros((capacity, k, ncontrol))
        self.force_cols = 1 + plant.qvel_index             # qfrc_applied's columns in a control row
        self.reset_before = (k - 0.5) * plant.timestep
        self._ids: dict[int, np.ndarray | None] = {capacity: None}       # None: every simulation

    def set_models(self, models: list[mujoco.MjModel]) -> None:
        """Run row i on ``models[i]`` (randomised models); rows beyond them run the nominal one."""
        self.batch.set_models(list(models) + [self.model] * (self.capacity - len(models)))

    def advance(self, x: np.ndarray, u: np.ndarray, forces: np.ndarray | None,
                out: PeriodView) -> np.ndarray:
        """See :meth:`Physics.advance <pendulum_lqg.core.physics.base.Physics.advance>`."""
        n = out.n
        state = self.batch.state[:n]
        state[:, self.dynamic] = self.state0_dynamic         # mj_resetData's values
        state[:, self.x_cols] = x
        control, spec = None, self.control_spec
        if forces is not None:                              # per-step inputs: a control array
            control = self.ctrl_buf[:n]
            control[:, :, 0] = u[:, None] if u.ndim == 1 else u
            control[:, :, self.force_cols] = forces
            spec = self.force_control_spec
        elif u.ndim == 2:                                   # a force per step (actuator lag)
            control = u[:, :, None]
        else:
            state[:, self.ctrl_col] = u                     # held: set once in the state
        if n not in self._ids:
            self._ids[n] = np.arange(n, dtype=np.int32)
        ids = self._ids[n]
        buf = out.buf
        if self.aligned and n == 1 and buf.flags.c_contiguous:
            # one row: its k records are one C-contiguous run of the buffer — record into it
            direct = buf.reshape(-1)[4:4 + 5 * self.k].reshape(1, self.k, 5)
            self.batch.rollout(self.k, control, control_spec=spec, record=(self.record_spec,),
                               ids=ids, out={self.record_spec: direct})
        else:
            rec = self.rec[:n]
            self.batch.rollout(self.k, control, control_spec=spec, record=(self.record_spec,),
                               ids=ids, out={self.record_spec: rec})
            self._store(buf, rec)
        return state[:, 0] < self.reset_before

    def _store(self, buf: np.ndarray, rec: np.ndarray) -> None:
        """The k records of each row into rows 1 … k, columns 0 … 3, of the period buffer ``buf``.
        Aligned records go in as one run of 5k numbers per row starting at row 0's column 4, so
        column 4 of rows 0 … k−1 receives the times: the loop writes the forces there afterwards."""
        n, k = buf.shape[0], self.k
        if self.aligned:
            buf.reshape(n, -1)[:, 4:4 + 5 * k] = rec.reshape(n, -1)
        else:
            buf[:, 1:k + 1, :4] = rec[:, :, self.rec_cols]
