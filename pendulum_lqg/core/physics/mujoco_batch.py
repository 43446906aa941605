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
    from pendulum_lqg.model.interface import MujocoPlant


#: Whether a held-force period calls ``Batch.rollout``'s C++ core (``batch._b.rollout``) directly:
#: only on the MuJoCo release whose wrapper was read (4.0), where the wrapper does nothing for our
#: arguments but check them — and they are valid by construction (ids 0 … n−1 or None, one
#: C-contiguous float64 record array of the shape the call fills, no control array). This is the
#: package's one private API, kept because it is worth more than 3 % of ``env.step``:
#: ``benchmarks/env_benchmark.py`` measures the two calls paired and prints the ratio, and
#: ``docs/performance.md`` records it. On any other release the public method runs.
DIRECT_CALL: bool = mujoco.__version__.startswith("4.0.")


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

    def __init__(self, plant: MujocoPlant, capacity: int, nthread: int, k: int, *,
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
        # x is the deviation from the equilibrium q* (x_offset = [q*, 0], None at q* = 0) and u is
        # in physical units: MuJoCo's ctrl is u / gear
        self.offset = plant.x_offset
        self.nq, self.nx = len(plant.qpos_index), 2 * len(plant.qpos_index)
        self.gear = plant.ctrl_gear
        self._cache: dict[int, _Rows] = {}
        #: Call the batch's C++ core for held forces (see :data:`DIRECT_CALL`); ``False``: always
        #: the public ``Batch.rollout`` (the benchmark that justifies the direct call flips it).
        self.direct_call = DIRECT_CALL

    def set_models(self, models: list[mujoco.MjModel]) -> None:
        """Run row i on ``models[i]`` (randomised models); rows beyond them run the nominal one."""
        self.batch.set_models(list(models) + [self.model] * (self.capacity - len(models)))

    def advance(self, x: np.ndarray, u: np.ndarray, forces: np.ndarray | None,
                out: PeriodView) -> np.ndarray | None:
        """See :meth:`Physics.advance <pendulum_lqg.core.physics.base.Physics.advance>`."""
        rows = self._rows(out)
        rows.dynamic[...] = self.state0_dynamic              # mj_resetData's values,
        rows.warning.fill(0)                                 # its warnings too (see _Rows)
        if self.offset is not None:
            x = x + self.offset
        if self.gear != 1.0:
            u = u / self.gear
        if rows.x is not None:
            rows.x[...] = x
        else:                                               # x's columns are not consecutive
            rows.state[:, self.x_cols] = x
        control, spec = None, self.control_spec
        if forces is not None:                              # per-step inputs: a control array
            control = rows.control
            control[:, :, 0] = u[:, None] if u.ndim == 1 else u
            control[:, :, self.force_cols] = forces
            spec = self.force_control_spec
        elif u.ndim == 2:                                   # a force per step (actuator lag)
            control = u[:, :, None]
        else:
            rows.ctrl[...] = u                              # held: set once in the state
        if control is None and self.direct_call:
            nfail = self.batch._b.rollout(rows.ids, self.k, None, spec, rows.records)
            if nfail:
                self.batch._check(rows.ids, nfail)           # raises mujoco.batch.SimulationError
        else:
            self.batch.rollout(self.k, control, control_spec=spec, record=(self.record_spec,),
                               ids=rows.ids, out=rows.out)
        if not rows.in_place:
            self._store(out.buf, rows.rec)
        if rows.one:                                        # one float compared, no array made
            return None if rows.time.item(0) >= self.reset_before else rows.time < self.reset_before
        reset = rows.time < self.reset_before
        return reset if np.count_nonzero(reset) else None

    def _rows(self, view: PeriodView) -> _Rows:
        """The views of the batch's first ``view.n`` simulations, made once per period view."""
        rows = self._cache.get(view.n)
        if rows is None or rows.view is not view:
            rows = self._cache[view.n] = _Rows(self, view)
        return rows

    def _store(self, buf: np.ndarray, rec: np.ndarray) -> None:
        """The k records of each row into rows 1 … k, columns 0 … 3, of the period buffer ``buf``.
        Aligned records go in as one run of 5k numbers per row starting at row 0's column 4, so
        column 4 of rows 0 … k−1 receives the times: the loop writes the forces there afterwards."""
        n, k = buf.shape[0], self.k
        if self.aligned:
            buf.reshape(n, -1)[:, 4:4 + 5 * k] = rec.reshape(n, -1)
        else:
            buf[:, 1:k + 1, :self.nx] = rec[:, :, self.rec_cols]
            if self.offset is not None:
                buf[:, 1:k + 1, :self.nq] -= self.offset[:self.nq]


class _Rows:
    """What :meth:`BatchPhysics.advance` writes and passes for the first ``n`` simulations of the
    batch, recording into the period view ``view`` — views made once, since slicing costs as much
    as the small copies made through the slices.

    * ``state``: the state rows; ``dynamic``, ``x``, ``ctrl``, ``time``: their columns reset each
      period, the ``[p, θ, ṗ, θ̇]`` columns (``None`` when not consecutive: no view addresses
      them), the held control and the time;
    * ``warning``: the simulations' warning counters, zeroed each period as ``mj_resetData``
      zeroes them. The batch stops a simulation (and :meth:`BatchPhysics.advance` reports its
      reset) when a counter rises; a counter left at 1 by an earlier instability would not rise
      when MuJoCo resets the data again, and the reset state would pass for a cart at rest;
    * ``one``: a single row, whose reset :meth:`BatchPhysics.advance` tells by one float;
    * ``control``: the per-step control buffer; ``ids``: the simulations 0 … n−1 for
      ``Batch.rollout`` (``None`` when they are all of the batch's);
    * ``rec``, ``out``, ``records``: where the rollout records, as the public call and the C++ core
      take it — in place into the period buffer (``in_place``: aligned layout and one row,
      ``view.direct``), else into scratch that :meth:`BatchPhysics._store` copies.
    """

    def __init__(self, physics: BatchPhysics, view: PeriodView) -> None:
        n = view.n
        state = physics.batch.state[:n]
        self.view, self.state, self.one = view, state, n == 1
        self.dynamic = state[:, physics.dynamic]
        cols = physics.x_cols
        self.x = state[:, cols] if isinstance(cols, slice) else None     # a view, or no view
        self.ctrl, self.time = state[:, physics.ctrl_col], state[:, 0]
        self.warning = physics.batch.warning[:n]
        self.control = physics.ctrl_buf[:n]
        self.ids = None if n == physics.capacity else np.arange(n, dtype=np.int32)
        direct = view.direct if physics.aligned else None
        self.in_place = direct is not None
        self.rec: np.ndarray = physics.rec[:n] if direct is None else direct
        self.out = {physics.record_spec: self.rec}
        self.records = [(None, physics.record_spec, self.rec)]     # the C++ core's form of out
