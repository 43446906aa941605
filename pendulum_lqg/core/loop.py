"""The one noisy closed loop: sample-and-hold control of a batch of cart-poles, a period at a time.

Every caller — ``pendulum-lqg run`` / ``bench`` / ``perf``, the Gymnasium envs and the Rerun
recordings — steps the plant through :class:`Simulator`. One control period ``n`` (``T = k·h``)
of each running row:

1. :meth:`Simulator.measure` — draw this period's unit normals from the episode's own generator
   (:class:`~pendulum_lqg.core.noise.NoiseStream`) and return ``y[n] = [p, θ] + v[n]`` (through
   the delay line and the sample losses, if any: :mod:`~pendulum_lqg.core.sensing`);
2. the policy turns ``y`` into a force (outside this module);
3. :meth:`Simulator.step` — the rules (:mod:`~pendulum_lqg.core.rules`) saturate the force; the
   actuator's delay line and lag, if any, shape it; a physics backend
   (:mod:`~pendulum_lqg.core.physics`) runs the k physics steps with it held, force noise
   entering through ``qfrc_applied``; the state noise jumps the state at the end of the period;
   the failure rule checks every physics step; the period's cost is integrated and streamed into
   the per-episode metrics (:class:`~pendulum_lqg.core.metrics.MetricsAccumulator`).

The plant is the cart-pole (MuJoCo or its linearisation) or a linear plant given as matrices
(:mod:`pendulum_lqg.model.lti`): its :class:`~pendulum_lqg.model.interface.Layout` says what
differs (the lengths and names of x and y, ``y = C x``, the initial state, the noise
covariances, the cost weights, the failure limits); the loop and its rules are the same.

The rows of one call may be any number, one included: the single Gymnasium env is a one-row
simulator (:meth:`Simulator.step_one` is :meth:`Simulator.step` without the metrics and the
:class:`StepResult`, through the same :meth:`Simulator._advance` and the same rules).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from pendulum_lqg.core import rules
from pendulum_lqg.core.metrics import MetricsAccumulator
from pendulum_lqg.core.noise import DRAW_LOCK, NoiseStream
from pendulum_lqg.core.period import PeriodBuffer, PeriodView, as_slice
from pendulum_lqg.core.physics import BACKENDS, Physics, make_physics, thread_count
from pendulum_lqg.core.scenario import Scenario
from pendulum_lqg.core.sensing import SensingActuation
from pendulum_lqg.errors import ConfigError, PendulumLQGError
from pendulum_lqg.model.interface import SimulatedPlant, steps_per_period


@dataclass
class StepResult:
    """What one control period returns for the running rows.

    Attributes
    ----------
    x : (n, n_x) true state at the end of the period (after state noise; the cart-pole's 4)
    cost : (n,) cost accumulated over the period
    failed : (n,) bool, the episode ended in this period (read-only, as ``reason``)
    reason : (n,) int failure codes (``rules.FAIL_*``)
    states : (n, k, n_x) physics-rate states over the period (a view, valid until the next step)
    requested : (n,) the requested force after saturation (before the actuator's delay line
        and lag): what a Gymnasium env reports as ``info["force"]``
    forces : (n, k) the force applied over each physics step (after saturation, actuator delay
        and lag; a view, valid until the next step)
    """

    x: np.ndarray
    cost: np.ndarray
    failed: np.ndarray
    reason: np.ndarray
    states: np.ndarray
    requested: np.ndarray
    forces: np.ndarray | None = None


class Simulator:
    """A batch of cart-pole episodes stepped one control period at a time.

    Parameters
    ----------
    plant : the simulated plant, any :class:`~pendulum_lqg.model.interface.SimulatedPlant` (the
        cart-pole, a plant file's MuJoCo model, a plant given as matrices)
    scenario : timing, noise, initial state, failure rule and cost
    backend : ``"rollout"`` (``mujoco.batch`` over the batch, several threads) or ``"step"``
        (a plain ``mj_step`` loop); a scenario with a linear ``plant`` uses the linear backend
    nthread : physics threads (default: the number of CPU cores, at most 8)
    streamed_metrics : keep the per-episode metric accumulators (:attr:`metrics`). ``False``
        computes only each period's cost (the same :func:`~pendulum_lqg.core.rules.period_integrals`)
        — what the Gymnasium envs need.

    Use as a context manager (or call :meth:`close`) to release the physics threads. A simulator
    pickles (the physics is made again on unpickling).
    """

    def __init__(self, plant: SimulatedPlant, scenario: Scenario, *,
                 backend: Literal["rollout", "step"] = "rollout", nthread: int | None = None,
                 streamed_metrics: bool = True) -> None:
        if backend not in BACKENDS:
            raise ConfigError(f"backend: expected one of {', '.join(BACKENDS)}, got {backend!r}")
        self.plant, self.scenario, self.backend = plant, scenario, backend
        self.h = plant.timestep
        self.k = steps_per_period(plant, scenario.control_period)
        self.dt = self.k * self.h
        self.n_periods = scenario.n_periods
        _, self.track, self.u_max = rules.limits(plant, scenario)     # the limits in force
        # what saturates u: u_max, or for an LTI plant of m inputs one limit per input (m,)
        self.u_limit: float | np.ndarray = self.u_max
        self.layout = lay = plant.layout(scenario)
        self.nx, self.m = lay.n, lay.m
        if self.m > 1:                          # one limit per input (the scenario's: for all)
            self.u_limit = np.broadcast_to(np.asarray(self.u_max, dtype=float), (self.m,)).copy()
            self.u_max = float(np.max(self.u_limit))
        self._C, self._state_limits = lay.C, lay.state_limits
        self.noise = NoiseStream(scenario.noise, steps_per_period=self.k, dt=self.dt, h=self.h,
                                 covariances=lay.covariances)
        # The cost weights h·[diag(Q), R]: a period's cost is Σ weights·z² over its physics steps.
        self.weights = rules.cost_weights(lay.cost_Q, lay.cost_R, self.h, matrix=lay.cost_matrix)
        self._period_cost = rules.period_cost_of(self.weights)     # step_one's, chosen once
        self._bounds = rules.failure_bounds(theta_max=scenario.theta_max, track_limit=self.track,
                                            u_max=self.u_limit, state_limits=lay.state_limits)
        self._force_noise = scenario.noise.process == "force" and self.noise.enabled
        self._state_noise = scenario.noise.process == "state" and self.noise.enabled
        self._nthread = thread_count(nthread)
        self._physics: Physics | None = None        # made for the batch's capacity
        self._period: PeriodBuffer | None = None
        self._closed = False
        self._capacity = 0
        self._streamed = bool(streamed_metrics)
        self._one_force = np.zeros(1)                      # step_one's force as a one-row array
        self.metrics: MetricsAccumulator | None = None
        self.sensing = SensingActuation(plant, scenario, self.k, outputs=lay.p,
                                        inputs=len(lay.inputs))
        # measure_one's own path: plain sensing of y = [p, θ] (else it is measure()'s first row)
        self._plain_one = self.sensing.plain_sensing and self._C is None
        self._theta_max = scenario.theta_max

    # ---- lifecycle ---------------------------------------------------------------------------
    def close(self) -> None:
        """Release the physics and its threads; a closed simulator cannot step."""
        self._closed = True
        self._physics = None

    def __enter__(self) -> Simulator:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __getstate__(self) -> dict[str, object]:
        return {**self.__dict__, "_physics": None}       # threads do not pickle: made again

    def __setstate__(self, state: dict[str, object]) -> None:
        self.__dict__.update(state)
        if self._capacity:
            self._make_physics()

    def _make_physics(self) -> None:
        if self._closed:
            return
        self._physics = make_physics(self.plant, plant_kind=self.scenario.plant,
                                     backend=self.backend, capacity=self._capacity,
                                     nthread=self._nthread, k=self.k)
        if self.sensing.row_models is not None:
            self._physics.set_models(self.sensing.row_models)

    def _ensure_capacity(self, n: int) -> None:
        if n <= self._capacity:
            return
        self._capacity = n
        self._make_physics()
        self._period = PeriodBuffer(n, self.k, self._bounds, inputs=self.m)

    # ---- episodes ----------------------------------------------------------------------------
    def reset(self, generators: list[np.random.Generator], *, ids: np.ndarray | None = None,
              rows: np.ndarray | None = None, initial_states: np.ndarray | None = None,
              private_generators: bool = False) -> np.ndarray:
        """Start episodes; returns the initial true states (n, n_x).

        Each generator first draws the initial state (n_x normals: the cart-pole's 4), then the
        noise blocks.

        Parameters
        ----------
        generators : one per episode
        ids : episode numbers for the metrics (default ``0..n-1``)
        rows : reset only these rows of the running batch (vector envs' autoreset); ``ids``
            must then be given for them too
        initial_states : (n, n_x) explicit initial states instead of the scenario's distribution
            (grids such as region-of-attraction maps); the n_x normals are drawn all the same so
            the noise that follows is unchanged
        private_generators : nothing draws from the generators after these episodes (a batch
            run), so the noise is drawn no further than the scenario's last period (the same
            numbers; see :meth:`NoiseStream.reset`'s ``horizon``). Not for Gymnasium envs, whose
            next episode continues the generator.
        """
        sc, lay, nx = self.scenario, self.layout, self.nx
        with DRAW_LOCK:                           # one draw per generator: see DRAW_LOCK
            z = np.array([g.standard_normal(nx) for g in generators]).reshape(-1, nx)
        x0 = lay.x0 + lay.x0_std * z
        if initial_states is not None:
            given = np.asarray(initial_states, dtype=float)
            if given.shape != x0.shape or not np.all(np.isfinite(given)):
                raise ConfigError(f"initial_states: expected finite values of shape {x0.shape}, "
                                  f"got shape {given.shape}")
            x0 = given.copy()
        if rows is None:
            n = len(generators)
            self._ensure_capacity(n)
            self.ids = np.arange(n) if ids is None else np.asarray(ids)
            self.x = x0
            self.t = np.zeros(n)
            self.period = np.zeros(n, dtype=np.int64)
            self.noise.reset(generators, horizon=self.n_periods if private_generators else None)
            if self._streamed:
                self.metrics = MetricsAccumulator(
                    self.ids.max(initial=-1) + 1, h=self.h, k=self.k, weights=self.weights, u_max=
                    self.u_limit, settle_band=sc.settle_band, layout=lay, skip=sc.burn_in_periods)
            self._proc_noise = np.zeros((n, self.noise.n_proc))     # w of the period, per row
        else:
            rows = np.asarray(rows)
            self.x[rows] = x0
            self.t[rows] = 0.0
            self.period[rows] = 0
            if ids is not None:
                self.ids[rows] = ids
            self.noise.reset(generators, rows)
            if self.metrics is not None:
                self.metrics.restart(self.ids[rows])
        self._id_index = as_slice(self.ids)
        self.sensing.reset(generators, rows, self._physics)
        if self.metrics is not None:
            self.metrics.start(self.ids if rows is None else self.ids[rows], x0)
        return x0.copy()

    @property
    def n(self) -> int:
        return self.x.shape[0]

    @property
    def nthread(self) -> int:
        """Physics threads (0 or 1: the calling thread)."""
        return self._nthread

    def measure(self, rows: np.ndarray | None = None) -> np.ndarray:
        """Draw this period's noise and return the measurement ``y = [p, θ] + v`` (n, 2) (an LTI
        plant's ``y = C x + v``, (n, p)).

        ``rows`` measures only those rows (len(rows), 2) and draws noise for them only — for vector
        envs, whose rows end and restart at different periods. Every row must be measured once
        before each :meth:`step`.
        """
        if rows is None:
            self._proc_noise, v = self.noise.draw()
            y = (self.x[:, :2] if self._C is None else self.x @ self._C.T) + v
            if self.sensing.plain_sensing:
                return y
            return self.sensing.sense(y, np.arange(self.n), self.period)
        rows = np.asarray(rows)
        w, v = self.noise.draw(rows)
        self._proc_noise = self._proc_noise.copy()             # it may be a view of the noise block
        self._proc_noise[rows] = w
        y = (self.x[rows, :2] if self._C is None else self.x[rows] @ self._C.T) + v
        return y if self.sensing.plain_sensing else self.sensing.sense(y, rows, self.period[rows])

    def measure_one(self) -> np.ndarray:
        """:meth:`measure` of a one-row simulator (the single Gymnasium env): ``y`` (2,), the
        same numbers as ``measure()[0]``."""
        if not self._plain_one:
            return self.measure()[0]
        self._proc_noise, v = self.noise.draw()
        return self.x[0, :2] + v[0]

    def step(self, u: np.ndarray, *, x_hat: np.ndarray | None = None) -> StepResult:
        """Advance every running episode by one control period with force ``u`` (n,) held.

        Parameters
        ----------
        u : (n,) requested forces [N], or (n, m) inputs of an LTI plant of m inputs (saturated
            here to the actuator range; a non-finite one ends its episode as ``diverged``)
        x_hat : (n, n_x) the estimate the controller used at this sample, for the estimation-error
            metric (optional)
        """
        u = _real_forces(u, self.m)
        if u.shape[0] != self.n:
            raise ConfigError(f"u: expected {self.n} forces, got {u.shape[0]}")
        bad = rules.nonfinite_forces(u)
        if bad is not None:                      # the physics of that row runs with 0 N
            u = np.where(bad if u.ndim == 1 else bad[:, None], 0.0, u)
        requested = rules.saturate(u, self.u_limit)
        v, command, reset = self._advance(requested)
        failed, reason, fail_step = rules.detect_failure(
            v, reset, self._theta_max, self.track, self._state_limits, bad_force=bad)
        return self._finish_period(v, command, requested, x_hat, failed, reason, fail_step)

    def step_one(self, u: float) -> tuple[float, int, float]:
        """One control period of a one-row simulator (the single Gymnasium env) with the force
        ``u`` [N] requested: :meth:`step` without the :class:`StepResult`. Returns the period's
        cost, the failure code (``FAIL_NONE`` while the episode runs) and the saturated force;
        ``x``, ``t`` and ``period`` advance as in :meth:`step` (in place)."""
        if len(self.x) != 1:                    # (len: .shape makes a tuple, every step)
            raise PendulumLQGError(f"step_one: needs a one-row simulator, this one has {self.n} rows")
        if self.metrics is not None or not math.isfinite(u):
            res = self.step(np.array([u]))
            return float(res.cost[0]), int(res.reason[0]), float(res.requested[0])
        u = rules.saturate(float(u), self.u_max)
        self._one_force[0] = u
        v, _, reset = self._advance(self._one_force)
        # (positional: binding keywords costs the env's every step more than the call's work)
        _, reason, fail_step = rules.detect_failure(v, reset, self._theta_max, self.track,
                                                    self._state_limits)
        if fail_step is None:                           # no row failed: the reason is FAIL_NONE
            # (read into a local: calling an instance's function attribute in place is a method
            # look-up on the class first, every step)
            period_cost = self._period_cost
            cost, code = period_cost(v.z, self.weights).item(), rules.FAIL_NONE
        else:
            cost = float(rules.period_integrals(v.z, fail_step, h=self.h, weights=self.weights)[2][0])
            code = int(reason[0])
        self.t[0] = self.t.item(0) + self.dt          # the float64 sum of t[0] += dt, in Python
        self.period[0] = self.period.item(0) + 1
        # The next period starts where this one ended: x becomes the buffer's start row itself,
        # which _advance then need not fill (the values as in step: a copy of the end state).
        v.start[...] = v.end
        self.x = v.start
        return cost, code, u

    def _advance(self, requested: np.ndarray) -> tuple[PeriodView, np.ndarray, np.ndarray | None]:
        """The period of every row with the saturated, finite forces ``requested`` (n,): actuation,
        physics and state noise into the period buffer. Returns its view, the command reaching
        the actuator (n,) and the rows MuJoCo reset (``None``: none)."""
        if self._physics is None or self._period is None:
            raise PendulumLQGError("simulator: closed (its physics threads were released by "
                                   "close()); make a new one")
        v = self._period.view(len(requested))            # its rows (len: no .shape tuple)
        steps = None
        command = requested
        if not self.sensing.plain_actuation:
            command, steps = self.sensing.actuate(requested, self.period)
        if self.x is not v.start:                     # step_one leaves x there (see step_one)
            v.start[...] = self.x
        forces = self.noise.forces(self._proc_noise) if self._force_noise else None
        reset = self._physics.advance(self.x, command if steps is None else steps, forces, v)
        if steps is None:                              # after the physics (see PeriodView.direct)
            v.u_by_step[...] = command
        else:
            v.u[...] = steps
        rules.end_of_period(v, self._proc_noise if self._state_noise else None)
        return v, command, reset

    def _finish_period(self, v: PeriodView, u: np.ndarray, requested: np.ndarray,
                       x_hat: np.ndarray | None, failed: np.ndarray, reason: np.ndarray,
                       fail_step: np.ndarray | None) -> StepResult:
        """Cost and metrics of the period in ``v``; advance time and state. ``u``: the command
        reaching the actuator of each row, ``requested`` the requested force after saturation."""
        if self.metrics is not None:
            x_fail = None if fail_step is None else v.buf[np.arange(v.n), fail_step + 1, :self.nx]
            cost = self.metrics.accumulate(self._id_index, v.z, u, x_hat, failed, reason,
                                           fail_step, self.t, x_fail)
        else:
            cost = rules.period_integrals(v.z, fail_step, h=self.h, weights=self.weights)[2]
        self.t = self.t + self.dt
        self.period = self.period + 1
        self.x = v.end.copy()
        return StepResult(x=self.x, cost=cost, failed=failed, reason=reason, states=v.states,
                          forces=v.u, requested=requested)

    def park(self, rows: np.ndarray) -> None:
        """Put rows whose episode ended, and that wait for a reset, at rest upright (x = 0, no
        process noise), so a step taken with the rest of the batch in between is harmless (vector
        envs in Gymnasium's NEXT_STEP autoreset mode); the rows' results are discarded."""
        self.x[rows] = 0.0
        self._proc_noise = self._proc_noise.copy()
        self._proc_noise[rows] = 0.0

    def select(self, rows: np.ndarray) -> None:
        """Keep only these rows (drop finished episodes from the batch)."""
        self.x, self.t, self.period = self.x[rows], self.t[rows], self.period[rows]
        self.ids = self.ids[rows]
        self._id_index = as_slice(self.ids)
        self._proc_noise = self._proc_noise[rows]
        self.noise.select(rows)
        self.sensing.select(rows, self._physics)


def _real_forces(u: object, m: int = 1) -> np.ndarray:
    """``u`` as a flat float64 array (n,), or (n, m) for a plant of ``m`` inputs; a complex force
    is refused (its imaginary part would be dropped silently)."""
    arr = np.asarray(u)
    if arr.dtype.kind == "c":
        raise PendulumLQGError(f"u: expected real forces [N], got complex values {arr.reshape(-1)[:3]!r}")
    if m == 1:
        return np.asarray(arr, dtype=float).reshape(-1)
    if arr.ndim != 2 or arr.shape[1] != m:
        raise PendulumLQGError(f"u: expected (n, {m}) inputs, got shape {arr.shape}")
    return np.asarray(arr, dtype=float)
