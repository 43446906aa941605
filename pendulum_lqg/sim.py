"""The one noisy closed loop: sample-and-hold control over MuJoCo physics, batched.

Every caller — ``pendulum-lqg run`` / ``bench`` / ``perf``, the gymnasium environments and the Rerun
recordings — steps the plant through :class:`Simulator`; no other module steps MuJoCo.

One control period ``n`` (``T = k·h``) for each running episode:

1. draw this period's unit normals from the episode's own generator (:class:`~.noise.NoiseStream`);
2. measure ``y[n] = [p, θ] + v[n]`` (:meth:`Simulator.measure`);
3. the policy returns a force; it is saturated to the actuator ``ctrlrange``;
4. ``k`` physics steps with the force held (MuJoCo 4's ``mujoco.batch.Batch`` for a batch, one
   simulation per row, see :class:`BatchPhysics`; or a plain ``mj_step`` loop — both paths give
   bit-identical states); force noise, if chosen, enters through ``qfrc_applied`` at every
   physics step;
5. state noise, if chosen, is added to the state at the end of the period: ``x ← x + δx``;
6. failure detection at every physics step and metrics streamed into per-episode accumulators
   (:class:`~pendulum_lqg.metrics.MetricsAccumulator`); trajectories are kept only on request.

Realistic sensing and actuation (``Scenario`` fields, all off by default and then bit-identical to
the plain loop): a measurement delay line and random sample losses (nan rows) in step 2, an
actuator delay line and a first-order force lag (a force per physics step) in steps 3–4, and
per-episode randomised models (the batch runs one model per row). Delay lines are ring
buffers of shape (n, d, ·) indexed by each row's own period, emptied when a row (re)starts. The
metrics' ``u`` (RMS, max, saturation) is the command reaching the actuator (after the delay); J
integrates the force actually applied (after the lag).

Failure rule (documented in the README): ``|θ| > theta_max`` (default 0.5 rad), or the cart reaching
the end of the track ``|p| ≥ track_limit`` (the slider ``range`` in the XML), or a non-finite / runaway
state (``|x_i| > 10⁶`` or MuJoCo resetting the data after an instability), reason ``diverged``.
A failed episode stops; the rest of the batch continues.
"""

from __future__ import annotations

import copy
import dataclasses
import math
import threading
import time
from collections.abc import Iterable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any, Literal

import mujoco
import numpy as np
from mujoco.batch import Batch

from pendulum_lqg._config import config_vector, positive_number
from pendulum_lqg.errors import ConfigError, PendulumLQGError
from pendulum_lqg.limits import MAX_DELAY_PERIODS, check_duration
from pendulum_lqg.metrics import (
    FAIL_DIVERGED,
    FAIL_POLE,
    FAIL_TRACK,
    MetricsAccumulator,
    period_cost,
    period_integrals,
)
from pendulum_lqg.names import PLANTS
from pendulum_lqg.noise import DRAW_LOCK, NoiseModel, NoiseStream, UniformStream
from pendulum_lqg.plant import ModelOverrides, Plant, Randomization, load_plant, steps_per_period
from pendulum_lqg.seeding import (  # noqa: F401 - episode_seed: public here too
    child_generator,
    episode_generators,
    episode_seed,
    episode_seeds,
)

#: Any state component beyond this magnitude counts as divergence.
RUNAWAY = 1e6
#: A one-row period that did not fail (read-only: shared by every step of the single-row path).
_NOT_FAILED = np.zeros(1, dtype=bool)
_NOT_FAILED.flags.writeable = False
_NO_REASON = np.zeros(1, dtype=np.int8)
_NO_REASON.flags.writeable = False
#: MuJoCo's warnings for an unstable state (it then resets the data; the batch's rollout stops).
_INSTABILITY_WARNINGS = tuple(int(w) for w in (mujoco.mjtWarning.mjWARN_BADQPOS,
                                               mujoco.mjtWarning.mjWARN_BADQVEL,
                                               mujoco.mjtWarning.mjWARN_BADQACC))


@dataclass(frozen=True)
class Scenario:
    """The control problem every policy faces: timing, noise, initial state, failure rule, cost.

    Attributes
    ----------
    control_period : T [s], an integer multiple of the model's physics step
    duration : episode length [s] (rounded to whole control periods)
    noise : process / measurement noise model (``noise.scale`` scales both std devs)
    x0 : mean initial state ``[p, θ, ṗ, θ̇]``
    x0_std : standard deviation of the initial state around ``x0`` (drawn per episode)
    estimate0 : initial estimate, ``"zero"`` (x̂₀ = 0) or ``"true"`` (x̂₀ = x₀)
    theta_max : failure when ``|θ|`` exceeds this [rad]
    settle_band : settling time is the last time ``|θ|`` was above this band [rad]
    cost_Q, cost_R : weights of ``J = ∫ xᵀ diag(Q) x + R u² dt``
    overrides : model changes of the *simulated* plant (mismatch studies); designs use the
        nominal model unless told otherwise
    plant : how the plant is simulated — ``"mujoco"`` (default), or the MJCF model's
        linearisation about the upright: ``"linear-zoh"`` (exact discretisation) or
        ``"linear-euler"`` (the lecture's own ``x ← x + T·(A x + B u) + δx`` per control period);
        same noise streams, failure rule, metrics and policies
    measurement_delay : age of the measurement the policy receives [s], a whole number of control
        periods ``d``: at sample n it gets the sample taken at n − d (NaN for n < d, when no
        sample has arrived yet)
    actuator_delay : delay of the force [s], a whole number of control periods ``d``: the force
        requested at sample n acts over period n + d (0 N over the first d periods)
    dropout : probability that a measurement sample is lost; the policy then receives
        ``[nan, nan]`` for it (the built-in estimators run their prediction only)
    actuator_tau : time constant of a first-order lag of the force [s] (0: none), at the physics
        rate: over physics step j the actuator applies the lag's exact response at the end of
        that step, ``f_j = u + (f_{j−1} − u)·e^{−h/τ}``
    randomize : per-episode parameter randomisation of the simulated plant
        (:class:`~pendulum_lqg.plant.Randomization`; a mapping such as
        ``{"pole_mass_scale": (0.8, 1.2)}`` is accepted)
    """

    control_period: float = 0.01
    duration: float = 10.0
    noise: NoiseModel = field(default_factory=NoiseModel.lecture)
    x0: tuple[float, ...] = (0.0, 0.1, 0.0, 0.0)
    x0_std: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0)
    estimate0: Literal["zero", "true"] = "zero"
    theta_max: float = 0.5
    settle_band: float = 0.02
    cost_Q: tuple[float, ...] = (1.0, 1.0, 1.0, 1.0)
    cost_R: float = 1.0
    overrides: ModelOverrides = field(default_factory=ModelOverrides)
    plant: str = "mujoco"
    measurement_delay: float = 0.0
    actuator_delay: float = 0.0
    dropout: float = 0.0
    actuator_tau: float = 0.0
    randomize: Randomization = field(default_factory=Randomization)

    def __post_init__(self) -> None:
        for name in ("control_period", "duration", "theta_max", "settle_band", "cost_R"):
            object.__setattr__(self, name, positive_number(name, getattr(self, name)))
        check_duration(self.duration, self.control_period)     # at most MAX_PERIODS periods
        object.__setattr__(self, "x0", config_vector("x0", self.x0, 4))
        object.__setattr__(self, "x0_std", config_vector("x0_std", self.x0_std, 4, nonneg=True))
        object.__setattr__(self, "cost_Q", config_vector("cost_Q", self.cost_Q, 4, nonneg=True))
        if self.estimate0 not in ("zero", "true"):
            raise ConfigError(f"estimate0: expected 'zero' or 'true', got {self.estimate0!r}")
        if not isinstance(self.noise, NoiseModel):
            raise ConfigError("noise: expected a NoiseModel")
        if not isinstance(self.overrides, ModelOverrides):
            raise ConfigError("overrides: expected a ModelOverrides")
        self._check_sensing_and_actuation()
        if self.plant not in PLANTS:
            raise ConfigError(f"plant: expected one of {', '.join(PLANTS)}, got {self.plant!r}")
        if self.plant != "mujoco" and self.noise.process == "force":
            raise ConfigError(f"plant: {self.plant!r} takes process noise on the state (the "
                              "lecture model); force noise needs plant = 'mujoco'")
        if self.plant != "mujoco" and self.actuator_tau > 0:
            raise ConfigError(f"actuator_tau: the lag acts at the physics rate, which the plant "
                              f"{self.plant!r} does not have; use plant = 'mujoco'")

    def _check_sensing_and_actuation(self) -> None:
        """Validate the delay, dropout, lag and randomisation fields (all off by default)."""
        for name in ("measurement_delay", "actuator_delay", "dropout", "actuator_tau"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float) \
                    or not np.isfinite(value) or value < 0:
                raise ConfigError(f"{name}: expected a finite number ≥ 0, got {value!r}")
            object.__setattr__(self, name, float(value))
        for name in ("measurement_delay", "actuator_delay"):
            periods = getattr(self, name) / self.control_period
            if not periods <= MAX_DELAY_PERIODS:
                raise ConfigError(f"{name}: expected at most {MAX_DELAY_PERIODS:,} control "
                                  f"periods (the ceiling; each is a ring-buffer slot per "
                                  f"episode), got {getattr(self, name)!r} s")
            if abs(periods - round(periods)) > 1e-9 * max(1.0, periods):
                raise ConfigError(f"{name}: expected a whole number of control periods "
                                  f"(T = {self.control_period:g} s), got {getattr(self, name)!r} s")
        if self.dropout >= 1:
            raise ConfigError(f"dropout: expected a probability in [0, 1), got {self.dropout!r}")
        object.__setattr__(self, "randomize", Randomization.from_mapping(self.randomize))

    @property
    def measurement_delay_periods(self) -> int:
        """The measurement delay in control periods."""
        return round(self.measurement_delay / self.control_period)

    @property
    def actuator_delay_periods(self) -> int:
        """The actuator delay in control periods."""
        return round(self.actuator_delay / self.control_period)

    @property
    def n_periods(self) -> int:
        return max(1, round(self.duration / self.control_period))

    def replace(self, **changes: object) -> Scenario:
        return dataclasses.replace(self, **changes)  # type: ignore[arg-type]

    def to_dict(self) -> dict[str, object]:
        d = dataclasses.asdict(self)
        d["overrides"] = {k: v for k, v in d["overrides"].items() if v is not None}
        d["randomize"] = {k: list(v) for k, v in d["randomize"].items() if v is not None}
        return d


@dataclass
class StepResult:
    """What one control period returns for the running rows.

    Attributes
    ----------
    x : (n, 4) true state at the end of the period (after state noise)
    cost : (n,) cost accumulated over the period
    failed : (n,) bool, the episode ended in this period
    reason : (n,) int failure codes (``metrics.FAIL_*``)
    states : (n, k, 4) physics-rate states over the period (always available; cheap views)
    requested : (n,) the requested force after saturation (before the actuator's delay line
        and lag): what a gymnasium env reports as ``info["force"]``
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
    plant : the simulated plant
    scenario : timing, noise, initial state, failure rule and cost
    backend : ``"rollout"`` (a ``mujoco.batch`` rollout over the batch, several threads) or ``"step"``
        (plain ``mj_step`` loop, the single-episode path)
    nthread : physics threads (default: the number of CPU cores, at most 8)
    streamed_metrics : keep the per-episode metric accumulators (:attr:`metrics`). ``False``
        computes only each period's cost (the same :func:`~pendulum_lqg.metrics.period_integrals`)
        — what the gymnasium environments need, at a lower cost per step.

    Use as a context manager (or call :meth:`close`) to stop the rollout thread pool. A simulator
    pickles (the thread pool is recreated on unpickling).
    """

    def __init__(self, plant: Plant, scenario: Scenario, *,
                 backend: Literal["rollout", "step"] = "rollout", nthread: int | None = None,
                 streamed_metrics: bool = True) -> None:
        if backend not in ("rollout", "step"):
            raise ConfigError(f"backend: expected 'rollout' or 'step', got {backend!r}")
        self.plant, self.scenario, self.backend = plant, scenario, backend
        self.model = plant.model
        self.h = plant.timestep
        self.k = steps_per_period(plant, scenario.control_period)
        self.dt = self.k * self.h
        self.n_periods = scenario.n_periods
        self.u_max = plant.u_max
        self.track = plant.track_limit
        self.noise = NoiseStream(scenario.noise, steps_per_period=self.k, dt=self.dt, h=self.h)
        #: h·[diag(Q), R]: the cost of a period is Σ weights·z² over its physics steps, z = [x, u]
        self.weights = self.h * np.append(scenario.cost_Q, scenario.cost_R)
        #: [track, theta_max, RUNAWAY, RUNAWAY, 2·u_max]: the failure check's fast path bounds
        #: every row of a period buffer (a saturated force passes it; a nan one does not)
        self._limits_row = np.array([self.track, scenario.theta_max, RUNAWAY, RUNAWAY,
                                     2.0 * self.u_max])
        self._force_noise = scenario.noise.process == "force" and self.noise.enabled
        self._state_noise = scenario.noise.process == "state" and self.noise.enabled
        st = mujoco.mjtState
        self._control_spec = st.mjSTATE_CTRL.value | (
            st.mjSTATE_QFRC_APPLIED.value if self._force_noise else 0)
        self._ncontrol = mujoco.mj_stateSize(self.model, self._control_spec)
        self._nthread = thread_count(nthread)
        self._physics: BatchPhysics | None = None        # made for the batch's capacity
        self._closed = False
        self._data = mujoco.MjData(self.model)
        self._linear = _LinearPlant(plant, scenario.plant, self.h, self.k) \
            if scenario.plant != "mujoco" else None
        self._capacity = 0
        self._streamed = bool(streamed_metrics)
        self.metrics: MetricsAccumulator | None = None
        self._init_sensing_and_actuation()

    def _init_sensing_and_actuation(self) -> None:
        """Delay lines, dropouts, actuator lag and randomised models (all off by default)."""
        sc = self.scenario
        self._dm, self._da = sc.measurement_delay_periods, sc.actuator_delay_periods
        self._dropout = sc.dropout
        self._randomized = not sc.randomize.is_empty()
        self._drops = UniformStream() if self._dropout > 0 else None
        #: e^{−(j+1)h/τ}, j = 0 … k−1: the lag's decay over the physics steps of a period
        self._lag_decay = (np.exp(-np.arange(1, self.k + 1) * self.h / sc.actuator_tau)
                           if sc.actuator_tau > 0 else None)
        self._plain_sensing = not (self._dm or self._drops is not None)
        self._plain_actuation = not (self._da or self._lag_decay is not None)
        self._row_models: list[mujoco.MjModel] | None = None
        #: one row steps through :meth:`_step_single` (same physics call, failure rule and cost)
        self._single_row_path = (self.backend == "rollout" and self._linear is None
                                 and self._plain_sensing and self._plain_actuation
                                 and not self._randomized)

    # ---- lifecycle ---------------------------------------------------------------------------
    def close(self) -> None:
        """Release the physics batch and its threads; a closed simulator cannot step."""
        self._closed = True
        self._physics = None

    def __enter__(self) -> Simulator:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __getstate__(self) -> dict[str, object]:
        state = self.__dict__.copy()
        state["_physics"] = None                 # a thread pool does not pickle
        for name in ("_row0", "_views"):         # views: pickled, they would become copies
            state.pop(name, None)
        return state

    def __setstate__(self, state: dict[str, object]) -> None:
        self.__dict__.update(state)
        if self._capacity:
            self._row0 = self._views = _PeriodViews(self, 1)
            self._make_physics()

    def _make_physics(self) -> None:
        if self.backend == "rollout" and not self._closed:
            self._physics = BatchPhysics(self.plant, self._capacity, self._nthread, self.k)
            if self._row_models is not None:
                self._physics.set_models(self._row_models)

    def _ensure_capacity(self, n: int) -> None:
        if n <= self._capacity:
            return
        self._capacity = n
        self._make_physics()
        self._ctrl_buf = np.zeros((n, self.k, self._ncontrol))
        # one period of each row, z = [x, u]: at the start | after each of the k physics steps |
        # at the end (after state noise); u is held over steps 0 … k−1 and 0 after them
        self._period_buf = np.zeros((n, self.k + 2, 5))
        # the failure check's fast path runs on the period buffer flattened (one contiguous run
        # of numbers: a fraction of the cost of the same ufuncs on a 3-d view): the limits of
        # every entry, |z| and |z| < limit
        size = self._period_buf.size
        self._limits_flat = np.tile(self._limits_row, size // 5)
        self._scratch = np.empty(size)
        self._inside = np.empty(size, dtype=bool)
        self._row0 = self._views = _PeriodViews(self, 1)

    # ---- episodes ----------------------------------------------------------------------------
    def reset(self, generators: list[np.random.Generator], *, ids: np.ndarray | None = None,
              rows: np.ndarray | None = None, initial_states: np.ndarray | None = None,
              private_generators: bool = False) -> np.ndarray:
        """Start episodes; returns the initial true states (n, 4).

        Each generator first draws the initial state (4 normals), then the noise blocks.

        Parameters
        ----------
        generators : one per episode
        ids : episode numbers for the metrics (default ``0..n-1``)
        rows : reset only these rows of the running batch (vector envs' autoreset); ``ids``
            must then be given for them too
        initial_states : (n, 4) explicit initial states instead of the scenario's distribution
            (grids such as region-of-attraction maps); the 4 normals are drawn all the same so
            the noise that follows is unchanged
        private_generators : nothing draws from the generators after these episodes (a batch
            run), so the noise is drawn no further than the scenario's last period (the same
            numbers; see :meth:`NoiseStream.reset`'s ``horizon``). Not for gymnasium envs, whose
            next episode continues the generator.
        """
        sc = self.scenario
        with DRAW_LOCK:                           # one draw per generator: see DRAW_LOCK
            z = np.array([g.standard_normal(4) for g in generators]).reshape(-1, 4)
        x0 = np.asarray(sc.x0) + np.asarray(sc.x0_std) * z
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
            self.noise.reset(generators,
                             horizon=self.n_periods if private_generators else None)
            if self._streamed:
                self.metrics = MetricsAccumulator(
                    self.ids.max(initial=-1) + 1, h=self.h, k=self.k, weights=self.weights,
                    u_max=self.u_max, settle_band=sc.settle_band)
            self._w = np.zeros((n, self.noise.n_proc))
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
        self._id_index = _as_slice(self.ids)
        self._reset_sensing_and_actuation(generators, rows)
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
        """Draw this period's noise and return the noisy measurement ``y = [p, θ] + v`` (n, 2).

        ``rows`` measures only those rows (len(rows), 2) and draws noise for them only — for vector
        environments, whose rows end and restart at different periods. Every row must be measured
        once before each :meth:`step`.
        """
        if rows is None:
            self._w, v = self.noise.draw()
            y = self.x[:, :2] + v
            return y if self._plain_sensing else self._sense(y, None)
        rows = np.asarray(rows)
        w, v = self.noise.draw(rows)
        self._w = self._w.copy()             # it may be a view of the noise block
        self._w[rows] = w
        y = self.x[rows, :2] + v
        return y if self._plain_sensing else self._sense(y, rows)

    def measure_one(self) -> np.ndarray:
        """:meth:`measure` of a one-row simulator (the single gymnasium env): ``y`` (2,), the
        same numbers as ``measure()[0]`` without the batch's (1, 2) arrays."""
        if not self._plain_sensing:
            return self.measure()[0]
        self._w, v = self.noise.draw()
        return self.x[0, :2] + v[0]

    def noise_free_measurement(self) -> np.ndarray:
        return self.x[:, :2].copy()

    def step(self, u: np.ndarray, *, x_hat: np.ndarray | None = None) -> StepResult:
        """Advance every running episode by one control period with force ``u`` (n,) held.

        Parameters
        ----------
        u : (n,) requested forces [N] (saturated here to the actuator range)
        x_hat : (n, 4) the estimate the controller used at this sample, for the estimation-error
            metric (optional)
        """
        u = np.asarray(u, dtype=float).reshape(-1)
        n, k = self.n, self.k
        if u.shape[0] != n:
            raise ConfigError(f"u: expected {n} forces, got {u.shape[0]}")
        if n == 1 and self._single_row_path:
            u0 = float(u[0])
            if math.isfinite(u0):
                return self._step_single(min(max(u0, -self.u_max), self.u_max), x_hat)
        # a non-finite requested force (a policy that blew up) ends its episode as diverged at the
        # start of the period; the physics of that row runs with 0 N (one sum is the fast check)
        bad_u = None if math.isfinite(u.sum()) else ~np.isfinite(u)
        if bad_u is not None:
            u = np.where(bad_u, 0.0, u)
        # saturation (np.minimum/np.maximum: np.clip's values, at a fraction of its overhead)
        u = requested = np.minimum(np.maximum(u, -self.u_max), self.u_max)
        u_steps = None
        if not self._plain_actuation:        # delay line and/or lag: u becomes the applied force
            u, u_steps = self._actuate(u)
        v = self._views if self._views.n == n else self._views_of(n)
        buf = v.buf
        v.start[...] = self.x
        states = v.states
        forces = self.noise.forces(self._w) if self._force_noise else None
        held = u if u_steps is None else u_steps
        if self._linear is not None:
            reset_flag = self._linear.advance(self.x, u, states)
        elif self.backend == "rollout":
            reset_flag = self._advance_rollout(held, forces, buf)
        else:
            reset_flag = self._advance_step(held, forces, states)
        v.u[...] = u[:, None] if u_steps is None else u_steps        # after the physics
        # state noise: one jump per period at its end (x ← x + δx)
        if self._state_noise:
            np.add(v.last, self._w, out=v.end)
        else:
            v.end[...] = v.last
        failed, reason, fail_step = self._detect_failure(v, reset_flag)
        if bad_u is not None and bad_u.any():
            failed = failed | bad_u
            reason = np.where(bad_u, FAIL_DIVERGED, reason).astype(np.int8)
            fail_step = np.where(bad_u, 0, k if fail_step is None else fail_step)
        return self._finish_period(v, u, requested, x_hat, failed, reason, fail_step)

    def _views_of(self, n: int) -> _PeriodViews:
        """The views of the period buffer's first ``n`` rows (kept for the last ``n`` asked)."""
        self._views = _PeriodViews(self, n)
        return self._views

    def _step_single(self, u: float, x_hat: np.ndarray | None) -> StepResult:
        """:meth:`step` for one row (a one-episode run): :meth:`_period_single`, then the same
        metrics as the batch."""
        _, failed, reason, fail_step = self._period_single(u)
        u_arr = np.array([u])
        return self._finish_period(self._row0, u_arr, u_arr, x_hat, failed, reason, fail_step)

    def _period_single(self, u: float) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                 np.ndarray | None]:
        """One period of row 0 into its buffer: the same physics call and failure rule as the
        batch, without the batch's plumbing (per-row masks, broadcasts and fancy indexing cost
        more than the arithmetic for one row; the views of row 0 are made once). ``u`` is the
        saturated, finite force. Returns ``(buf, failed, reason, fail_step)`` as
        :meth:`_detect_failure` does."""
        physics = self._physics
        if physics is None:
            raise _closed_error()
        v = self._row0
        x = self.x                                        # (1, 4)
        forces = self.noise.forces(self._w)[:1] if self._force_noise else None
        reset = physics.advance_one(x, u, forces, v.buf, self._ctrl_buf)
        v.start[...] = x
        v.u.fill(u)
        if self._state_noise:
            np.add(v.last, self._w, out=v.end)
        else:
            v.end[...] = v.last
        buf = v.buf
        if not reset and v.within_limits():      # no failure: no per-row arrays for one row
            return buf, _NOT_FAILED, _NO_REASON, None
        return (buf, *self._detect_failure(v, np.array([reset])))

    def step_one(self, u: float) -> tuple[float, int]:
        """One control period of a one-row simulator (the single gymnasium env) with the force
        ``u`` [N] requested. Returns the period's cost and the failure code (``FAIL_NONE`` while
        the episode runs); ``self.x``, ``self.t`` and ``self.period`` advance as in :meth:`step`,
        which it equals (here ``x``, ``t`` and ``period`` are updated in place). Plain sensing and
        actuation without streamed metrics (the env's default) take the lean single-row path (no
        :class:`StepResult`, no metric arrays); anything else,
        and a non-finite force, goes through :meth:`step`."""
        if self.x.shape[0] != 1:
            raise PendulumLQGError(f"step_one: needs a one-row simulator, this one has {self.n} rows")
        if not (self._single_row_path and self.metrics is None and math.isfinite(u)):
            res = self.step(np.array([u]))
            return float(res.cost[0]), int(res.reason[0])
        u = min(max(u, -self.u_max), self.u_max)
        _, _, reason, fail_step = self._period_single(u)
        z = self._row0.z
        cost = float(period_cost(z, self.weights)[0] if fail_step is None else
                     period_integrals(z, fail_step, h=self.h, weights=self.weights)[2][0])
        self.t[0] += self.dt            # in place, element-wise (one row, nobody else holds them):
        self.period[0] += 1             # step()'s values without a ufunc call or an allocation
        self.x[...] = self._row0.end
        return cost, int(reason[0])

    def _finish_period(self, v: _PeriodViews, u: np.ndarray, requested: np.ndarray,
                       x_hat: np.ndarray | None, failed: np.ndarray, reason: np.ndarray,
                       fail_step: np.ndarray | None) -> StepResult:
        """Cost and metrics of the period in the buffer of ``v``; advance time and state. ``u``:
        the applied command of each row, ``requested`` the requested force after saturation."""
        buf, z, n = v.buf, v.z, v.n
        if self.metrics is not None:
            x_fail = None if fail_step is None else buf[np.arange(n), fail_step + 1, :4]
            cost = self.metrics.accumulate(self._id_index, z, u, x_hat, failed, reason, fail_step,
                                           self.t, x_fail)
        else:
            cost = period_integrals(z, fail_step, h=self.h, weights=self.weights)[2]
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
        self._w = self._w.copy()
        self._w[rows] = 0.0

    def select(self, rows: np.ndarray) -> None:
        """Keep only these rows (drop finished episodes from the batch)."""
        self.x, self.t, self.period = self.x[rows], self.t[rows], self.period[rows]
        self.ids = self.ids[rows]
        self._id_index = _as_slice(self.ids)
        self._w = self._w[rows]
        self.noise.select(rows)
        self._select_sensing_and_actuation(rows)

    # ---- delays, dropouts, actuator lag, randomised models (per-row state, batched) ----------
    def _reset_sensing_and_actuation(self, generators: list[np.random.Generator],
                                     rows: np.ndarray | None) -> None:
        """Empty the delay lines and the lag of the (re)started rows; draw their parameters."""
        if self._plain_sensing and self._plain_actuation and not self._randomized:
            return
        if rows is None:
            n = len(generators)
            self._y_ring = np.full((n, self._dm, 2), np.nan)     # nothing has arrived yet
            self._u_ring = np.zeros((n, self._da))                # 0 N until the first force
            self._force = np.zeros(n)                             # the lag's output
        else:
            self._y_ring[rows] = np.nan
            self._u_ring[rows] = 0.0
            self._force[rows] = 0.0
        if not (self._randomized or self._drops is not None):
            return
        children = [child_generator(g) for g in generators]
        if self._randomized:                                      # the child's first draws
            models = [self._episode_model(c.random(3)) for c in children]
            if rows is None:
                self._row_models = models
            else:
                assert self._row_models is not None
                for r, m in zip(np.asarray(rows).tolist(), models, strict=True):
                    self._row_models[r] = m
            if self._physics is not None:
                self._physics.set_models(self._row_models)
        if self._drops is not None:
            self._drops.reset(children, rows)

    def _episode_model(self, r: np.ndarray) -> mujoco.MjModel:
        """The simulated model of an episode with randomisation uniforms ``r`` (3,)."""
        ov = Randomization.apply(self.plant.overrides, self.scenario.randomize.scales(r))
        return load_plant(self.plant.path, overrides=ov).model

    def _sense(self, y: np.ndarray, rows: np.ndarray | None) -> np.ndarray:
        """Dropouts (lost samples become nan) and the measurement delay line of ``rows``."""
        idx = np.arange(self.n) if rows is None else rows
        if self._drops is not None:
            y[self._drops.draw(rows) < self._dropout] = np.nan
        if self._dm:
            slot = self.period[idx] % self._dm          # holds the sample taken d periods ago
            y, self._y_ring[idx, slot] = self._y_ring[idx, slot], y
        return y

    def _actuate(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """The actuator delay line and lag: ``(applied command (n,), force per physics step
        (n, k) with a lag, else None)`` for the requested (saturated) forces ``u``."""
        if self._da:
            idx = np.arange(self.n)
            slot = self.period % self._da                # holds the force requested d periods ago
            u, self._u_ring[idx, slot] = self._u_ring[idx, slot], u
        if self._lag_decay is None:
            return u, None
        steps = u[:, None] + (self._force - u)[:, None] * self._lag_decay
        self._force = steps[:, -1].copy()
        return u, steps

    def _select_sensing_and_actuation(self, rows: np.ndarray) -> None:
        if self._plain_sensing and self._plain_actuation and not self._randomized:
            return
        self._y_ring, self._u_ring = self._y_ring[rows], self._u_ring[rows]
        self._force = self._force[rows]
        if self._row_models is not None:
            self._row_models = [self._row_models[r] for r in np.asarray(rows).tolist()]
            if self._physics is not None:
                self._physics.set_models(self._row_models)
        if self._drops is not None:
            self._drops.select(rows)

    # ---- physics -----------------------------------------------------------------------------
    def _advance_rollout(self, u: np.ndarray, forces: np.ndarray | None, buf: np.ndarray,
                         ) -> np.ndarray:
        """k physics steps of every row into the period buffer ``buf`` (n, k+2, 5) (see
        :meth:`BatchPhysics.advance`); returns the rows MuJoCo reset."""
        if self._physics is None:
            raise _closed_error()
        return self._physics.advance(self.n, self.x, u, forces, buf, self._ctrl_buf)

    def _advance_step(self, u: np.ndarray, forces: np.ndarray | None, out: np.ndarray,
                      ) -> np.ndarray:
        """The same with a plain ``mj_step`` loop, one row at a time."""
        m, d = self.model, self._data
        reset_flag = np.zeros(self.n, dtype=bool)
        qi, vi = self.plant.qpos_index, self.plant.qvel_index
        per_step = u.ndim == 2                             # actuator lag: a force per step
        for r in range(self.n):
            if self._row_models is not None:
                m = self._row_models[r]
            mujoco.mj_resetData(m, d)
            d.qpos[qi] = self.x[r, :2]
            d.qvel[vi] = self.x[r, 2:]
            d.ctrl[0] = u[r, 0] if per_step else u[r]
            for j in range(self.k):
                if per_step:
                    d.ctrl[0] = u[r, j]
                if forces is not None:
                    d.qfrc_applied[vi] = forces[r, j]
                mujoco.mj_step(m, d)
                out[r, j, :2] = d.qpos[qi]
                out[r, j, 2:] = d.qvel[vi]
                if any(d.warning[w].number for w in _INSTABILITY_WARNINGS):
                    # MuJoCo reset the data after an instability: as the batch's rollout does, stop
                    # and hold the state reached for the rest of the period
                    out[r, j + 1:] = out[r, j]
                    reset_flag[r] = True
                    break
            else:
                reset_flag[r] = abs(d.time - self.k * self.h) > 0.5 * self.h
        return reset_flag

    def _detect_failure(self, v: _PeriodViews, reset_flag: np.ndarray,
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """Failure of each row in the period buffer of ``v``, (n, k+2, 5) = ``[x, u]`` at [the
        start | the k physics steps | the end]: ``failed``, the reason codes and the first failing
        physics step (``k`` if none), or ``None`` for the latter when no row failed."""
        sc = self.scenario
        buf: np.ndarray = v.buf
        n, k = v.n, self.k
        failed = np.zeros(n, dtype=bool)
        reason = np.zeros(n, dtype=np.int8)                      # FAIL_NONE is 0
        if n == 0 or (np.count_nonzero(reset_flag) == 0 and v.within_limits()):
            return failed, reason, None
        states, x_end = buf[:, 1:k + 1, :4], buf[:, k + 1, :4]
        with np.errstate(invalid="ignore"):
            mag = np.abs(states)
            # ``not (|x| <= RUNAWAY)`` is true for nan, inf and runaway values alike
            bad = ~(mag <= RUNAWAY).all(axis=2)
            pole = mag[:, :, 1] > sc.theta_max
            track = mag[:, :, 0] >= self.track
            end_bad = ~(np.abs(x_end) <= RUNAWAY).all(axis=1)
        bad[:, -1] |= end_bad | reset_flag
        any_fail = bad | pole | track
        failed = any_fail.any(axis=1)
        fail_step = np.where(failed, np.argmax(any_fail, axis=1), k)
        if failed.any():
            idx = np.nonzero(failed)[0]
            s = fail_step[idx]
            reason[idx] = np.where(bad[idx, s], FAIL_DIVERGED,
                                   np.where(pole[idx, s], FAIL_POLE, FAIL_TRACK))
            return failed, reason, fail_step
        return failed, reason, None


class _PeriodViews:
    """Views of the first ``n`` rows of a simulator's period buffer ``(n, k+2, 5)``, made once
    for a row count (slicing a 3-d array costs as much as the small copies through it).

    ``buf`` the rows, ``z`` their ``[x, u]`` at the start of each physics step, ``start``,
    ``last`` and ``end`` the states (n, 4) at the start, after the k-th step and after the state
    noise, ``states`` (n, k, 4) after each step, ``u`` (n, k) the force of each step. The failure
    check's fast path, :meth:`within_limits`, runs on the rows flattened.
    """

    def __init__(self, sim: Simulator, n: int) -> None:
        k = sim.k
        self.n = n
        self.buf = b = sim._period_buf[:n]
        self.z, self.states, self.u = b[:, :k], b[:, 1:k + 1, :4], b[:, :k, 4]
        self.start, self.last, self.end = b[:, 0, :4], b[:, k, :4], b[:, k + 1, :4]
        size = b.size
        self.flat, self.limits = b.reshape(-1), sim._limits_flat[:size]
        self.scratch, self.inside = sim._scratch[:size], sim._inside[:size]

    def within_limits(self) -> bool:
        """The failure check's fast path: every ``|z_i| < limit_i`` over the rows (the start and
        end states too: a stricter test than the full checks of
        :meth:`Simulator._detect_failure`, which then find no failure; a nan fails it). It runs
        on the rows flattened, one contiguous run (a fraction of the cost of the same ufuncs on
        3-d views); ``count_nonzero`` is a plain C count, cheaper than ``all`` on small arrays."""
        np.less(np.abs(self.flat, out=self.scratch), self.limits, out=self.inside)
        return bool(np.count_nonzero(self.inside) == self.inside.size)


class BatchPhysics:
    """The physics of a batch of rows: ``mujoco.batch.Batch`` (MuJoCo ≥ 4), one simulation a row.

    Each period starts every row from a freshly reset ``MjData`` state (``mj_resetData``: time 0,
    no warm start) with the row's ``[p, θ, ṗ, θ̇]`` written in, exactly as the ``mj_step`` backend
    does, so the two give bit-identical states. ``Batch.rollout`` then runs the k physics steps on
    the batch's threads (the calling thread among them, the GIL released) and records only
    ``qpos`` and ``qvel`` after each step — the failure rule and the cost need nothing else. A row
    whose MuJoCo warnings rise (an instability: MuJoCo resets its data) stops there and repeats
    its last record; its time then falls short of ``k·h``, which is how :meth:`advance` reports it.

    Parameters
    ----------
    plant : the nominal plant (its model is the batch's; rows may run other models of the same
        layout, :meth:`set_models`)
    capacity : rows; nthread : threads, the caller's included (0 or 1: the caller alone)
    k : physics steps per period
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
        #: the columns a physics step changes — time, qpos, qvel, act, history and warm start
        #: come before the inputs (ctrl, applied forces, mocap, …), which it only reads; plugin
        #: state (last) changes too, so a model with plugins resets its whole row
        plugin = int(mujoco.mj_stateSize(m, st.mjSTATE_PLUGIN.value))
        self.dynamic = slice(0, self.batch.nstate if plugin else self.ctrl_col)
        self.state0_dynamic = self.state0[self.dynamic]
        self.x_cols = _maybe_slice(np.concatenate([qpos0 + plant.qpos_index,
                                                   qvel0 + plant.qvel_index]))
        #: [p, θ, ṗ, θ̇] are qpos and qvel as they lie in MjData (the shipped model): each step
        #: is recorded as [time, p, θ, ṗ, θ̇], five numbers like a row of the period buffer
        #: [p, θ, ṗ, θ̇, u] one place later, so the k records land in rows 1 … k of the buffer as
        #: one copy of 5k consecutive numbers per row (see :meth:`advance`)
        #: (``aligned=False`` forces the general copy, for models with other layouts; tests)
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
        self.rec_cols = _maybe_slice(np.concatenate([plant.qpos_index, m.nq + plant.qvel_index]))
        self.control_spec = st.mjSTATE_CTRL.value
        self.force_control_spec = int(st.mjSTATE_CTRL | st.mjSTATE_QFRC_APPLIED)
        self.force_cols = 1 + plant.qvel_index             # qfrc_applied's columns in a control row
        self.reset_before = (k - 0.5) * plant.timestep
        self._ids: dict[int, np.ndarray | None] = {capacity: None}
        # row 0 alone (advance_one)
        self._state1 = self.batch.state[0]
        self._ids1 = None if capacity == 1 else np.zeros(1, dtype=np.int32)
        self._records1 = [(None, self.record_spec, self.rec[:1])]
        self._rec1_flat = self.rec[:1].reshape(1, -1)
        self._buf1: np.ndarray | None = None      # the period buffer the records go straight into

    def _rollout(self, ids: np.ndarray | None, control: np.ndarray | None, spec: int,
                 records: list[tuple[None, int, np.ndarray]]) -> None:
        """``Batch.rollout`` of k steps recording ``records`` (``[(None, state spec, (n, k, ·)
        C-contiguous float64 array)]``) for the simulations ``ids`` (int32, or None for all).

        The arguments are built once and valid by construction, so on the MuJoCo release whose
        ``Batch`` internals were checked (4.0) the call goes straight to its C++ core, skipping
        the per-call validation of the Python wrapper (2 µs, a tenth of a single env's step);
        any other release takes the public method."""
        if _DIRECT_BATCH:
            nfail = self.batch._b.rollout(ids, self.k, control, spec, records)
            if nfail:
                self.batch._check(ids, nfail)          # raises mujoco.batch.SimulationError
            return
        _, record, out = records[0]
        self.batch.rollout(self.k, control, control_spec=spec, record=(record,), ids=ids,
                           out={record: out})

    def set_models(self, models: list[mujoco.MjModel]) -> None:
        """Run row i on ``models[i]`` (randomised models); rows beyond them run the nominal one."""
        self.batch.set_models(list(models) + [self.model] * (self.capacity - len(models)))

    def advance_one(self, x: np.ndarray, u: float, forces: np.ndarray | None, buf: np.ndarray,
                    ctrl_buf: np.ndarray) -> bool:
        """:meth:`advance` of row 0 alone, ``x`` (1, 4), ``u`` a float held over the period,
        ``buf`` (1, k+2, 5); returns whether MuJoCo reset the row."""
        if forces is not None:
            return bool(self.advance(1, x, u, forces, buf, ctrl_buf)[0])
        state = self._state1
        state[self.dynamic] = self.state0_dynamic            # mj_resetData's values
        state[self.x_cols] = x
        state[self.ctrl_col] = u
        if buf is self._buf1:            # aligned: the rollout records straight into the buffer
            self._rollout(self._ids1, None, self.control_spec, self._direct1)
        else:
            self._rollout(self._ids1, None, self.control_spec, self._records1)
            self._store(buf, self._rec1_flat, self.rec[:1])
            self._bind_row(buf)
        return bool(state[0] < self.reset_before)

    def _bind_row(self, buf: np.ndarray) -> None:
        """Let later :meth:`advance_one` calls with this one-row buffer record into it directly.

        With the aligned layout, :meth:`_store` copies the k records, one run of 5k numbers, to
        the numbers 4 … 4+5k−1 of the row; that run of a C-contiguous buffer is itself a
        C-contiguous (1, k, 5) array, which the rollout can fill instead (one copy fewer per
        step of a single env)."""
        if not (self.aligned and buf.shape[0] == 1 and buf.flags.c_contiguous):
            return
        self._direct1 = [(None, self.record_spec,
                          buf.reshape(-1)[4:4 + 5 * self.k].reshape(1, self.k, 5))]
        self._buf1 = buf

    def _store(self, buf: np.ndarray, rec_flat: np.ndarray, rec: np.ndarray) -> None:
        """The k records of each row into rows 1 … k, columns 0 … 3, of the period buffer
        ``buf`` (n, k+2, 5). Aligned records go in as one run of 5k numbers per row starting at
        row 0's column 4, so column 4 of rows 0 … k−1 receives the times: the caller writes the
        forces there afterwards."""
        n, k = buf.shape[0], self.k
        if self.aligned:
            buf.reshape(n, -1)[:, 4:4 + 5 * k] = rec_flat
        else:
            buf[:, 1:k + 1, :4] = rec[:, :, self.rec_cols]

    def advance(self, n: int, x: np.ndarray, u: np.ndarray | float, forces: np.ndarray | None,
                buf: np.ndarray, ctrl_buf: np.ndarray) -> np.ndarray:
        """k physics steps of rows ``0 … n−1`` from states ``x`` (n, 4) into rows 1 … k of the
        C-contiguous period buffer ``buf`` (n, k+2, 5), columns 0 … 3; column 4 of rows 0 … k−1
        may be overwritten (write the forces after this call).

        ``u``: the force of each row held over the period (n,), or one per physics step (n, k)
        (actuator lag); ``forces``: generalised forces (n, k, 2) on slider and hinge per physics
        step (force noise) or None; ``ctrl_buf``: a (≥ n, k, ·) scratch for the per-step
        controls. Returns the rows MuJoCo reset (an instability), (n,) bool.
        """
        state = self.batch.state[:n]
        state[:, self.dynamic] = self.state0_dynamic         # mj_resetData's values
        state[:, self.x_cols] = x
        control, spec = None, self.control_spec
        if forces is not None or (isinstance(u, np.ndarray) and u.ndim == 2):
            control = ctrl_buf[:n]
            control[:, :, 0] = u[:, None] if isinstance(u, np.ndarray) and u.ndim == 1 else u
            if forces is not None:
                control[:, :, self.force_cols] = forces
                spec = self.force_control_spec
        else:
            state[:, self.ctrl_col] = u
        rec = self.rec[:n]
        if n in self._ids:
            ids = self._ids[n]
        else:
            ids = self._ids[n] = np.arange(n, dtype=np.int32)
        self._rollout(ids, control, spec, [(None, self.record_spec, rec)])
        self._store(buf, rec.reshape(n, -1), rec)
        return state[:, 0] < self.reset_before


#: ``mujoco.batch.Batch``'s C++ rollout is called directly on the release it was checked against.
_DIRECT_BATCH = mujoco.__version__.split(".")[:2] == ["4", "0"] and hasattr(Batch, "_check")


def _maybe_slice(cols: np.ndarray) -> np.ndarray | slice:
    """``cols`` as a slice when they are consecutive (a slice indexes without copying)."""
    if np.array_equal(cols, np.arange(cols[0], cols[0] + cols.size)):
        return slice(int(cols[0]), int(cols[0]) + cols.size)
    return cols


def _closed_error() -> PendulumLQGError:
    return PendulumLQGError("simulator: closed (its physics threads were released by close()); "
                            "make a new one")


def _as_slice(ids: np.ndarray) -> np.ndarray | slice:
    """``slice(a, a + n)`` if ``ids`` are the consecutive integers ``a … a+n−1``, else ``ids``
    (the metrics then add in place instead of gathering and scattering)."""
    n = ids.shape[0]
    if n and int(ids[-1]) - int(ids[0]) == n - 1 and (n == 1 or bool((np.diff(ids) == 1).all())):
        return slice(int(ids[0]), int(ids[0]) + n)
    return ids


class _LinearPlant:
    """The linearised cart-pole stepped in place of MuJoCo (``Scenario.plant``), batched numpy.

    ``linear-zoh``: ``x ← Φ_h x + Γ_h u`` at every physics step h (the exact ZOH of ``ẋ = Ax + Bu``,
    so the end of the period is exactly ``Φ_T x + Γ_T u``). ``linear-euler``: the lecture's update
    ``x ← x + T·(A x + B u)`` once per control period; the k physics-step samples in between (which
    the failure rule and the cost integrate over) lie on the straight line to it, the last one
    exactly on it. State noise is added at the end of the period by the core, as for MuJoCo.
    """

    def __init__(self, plant: Plant, kind: str, h: float, k: int) -> None:
        from pendulum_lqg.design import euler, zoh
        from pendulum_lqg.linearize import linearize

        lin = linearize(plant)
        self.kind, self.k = kind, k
        if kind == "linear-zoh":
            self.Phi, self.Gamma = zoh(lin.A, lin.B, h)
        else:
            self.Phi, self.Gamma = euler(lin.A, lin.B, k * h)       # I + TA, TB
        self.Gamma = self.Gamma[:, 0]
        self._frac = (np.arange(1, k + 1) / k)[None, :, None]

    def advance(self, x: np.ndarray, u: np.ndarray, out: np.ndarray) -> np.ndarray:
        """States after each of the k physics steps into ``out`` (n, k, 4); nothing resets."""
        if self.kind == "linear-zoh":
            for j in range(self.k):
                x = np.einsum("ij,nj->ni", self.Phi, x) + u[:, None] * self.Gamma
                out[:, j] = x
        else:
            x_end = np.einsum("ij,nj->ni", self.Phi, x) + u[:, None] * self.Gamma
            out[...] = x[:, None, :] + self._frac * (x_end - x)[:, None, :]
            out[:, -1] = x_end
        return np.zeros(x.shape[0], dtype=bool)


def thread_count(nthread: int | None) -> int:
    """Rollout threads for a request: ``None`` → the CPU cores this process may use, at most 8;
    a number → itself, capped to those cores (more threads than cores only add hand-offs, and
    thousands of them can exhaust the process)."""
    if nthread is None:
        return min(8, _cpu_count())
    if isinstance(nthread, bool) or not isinstance(nthread, int | np.integer) or nthread < 0:
        raise ConfigError(f"nthread: expected a non-negative integer, got {nthread!r}")
    return min(int(nthread), _cpu_count())


def _cpu_count() -> int:
    import os

    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - non-Linux
        return max(1, os.cpu_count() or 1)


@dataclass
class Trajectory:
    """One episode's trajectory (kept only when a caller asks, e.g. for a recording).

    Control-rate arrays have one row per control sample ``n`` (time ``t[n]``); ``states`` holds the
    physics-rate states with times ``t_physics``.

    Attributes
    ----------
    t : (N,) sample times [s]; x : (N, 4) true state at the sample; y : (N, 2) noisy measurement;
    y_true : (N, 2) noise-free measurement; u : (N,) applied force; x_hat : (N, 4) estimate used;
    x_prior : (N, 4) a-priori estimate; innovation : (N, 2); P : (N, 4, 4) a-posteriori covariance
    (nan if the estimator has none); cost : (N,) running cost at the end of each period;
    t_physics : (N·k,), states : (N·k, 4)
    """

    episode: int
    seed: int
    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    y_true: np.ndarray
    u: np.ndarray
    x_hat: np.ndarray
    x_prior: np.ndarray
    innovation: np.ndarray
    P: np.ndarray
    cost: np.ndarray
    t_physics: np.ndarray
    states: np.ndarray
    row: dict[str, object] = field(default_factory=dict)


@dataclass
class BatchResult:
    """Per-episode metric rows (and trajectories on request) of one batch run.

    ``shard_seconds``: when each shard (:func:`shard_count`) started and ended, in seconds of
    ``time.perf_counter`` since the run started, one ``(start, end)`` per shard: a diagnostic of
    how evenly the shards shared the threads (``pendulum-lqg perf`` reports it).
    """

    rows: list[dict[str, Any]]
    trajectories: list[Trajectory] | None = None
    shard_seconds: list[tuple[float, float]] = field(default_factory=list)


class _TrajectoryLog:
    """Per-period snapshots of the running rows, split per episode at the end."""

    def __init__(self) -> None:
        self.frames: list[dict[str, np.ndarray]] = []

    def add(self, ids: np.ndarray, **arrays: np.ndarray) -> None:
        self.frames.append({"ids": ids.copy(), **{k: np.array(v) for k, v in arrays.items()}})

    def split(self, n: int, seeds: list[int], rows: list[dict[str, object]]) -> list[Trajectory]:
        out = []
        for e in range(n):
            parts: dict[str, list[np.ndarray]] = {}
            for fr in self.frames:
                hit = np.nonzero(fr["ids"] == e)[0]
                if hit.size == 0:
                    continue
                i = hit[0]
                for key, arr in fr.items():
                    if key != "ids":
                        parts.setdefault(key, []).append(arr[i] if arr.ndim and arr.shape[0] ==
                                                         fr["ids"].shape[0] else arr)
            stack = {k: np.array(v) for k, v in parts.items()}
            cost = np.cumsum(stack["cost"])
            states = stack["states"].reshape(-1, 4)
            k = stack["states"].shape[1]
            h = (stack["t"][1] - stack["t"][0]) / k if stack["t"].size > 1 else np.nan
            t_phys = (stack["t"][:, None] + h * np.arange(1, k + 1)[None, :]).ravel()
            out.append(Trajectory(
                episode=e, seed=seeds[e], t=stack["t"], x=stack["x"], y=stack["y"],
                y_true=stack["x"][:, :2], u=stack["u"], x_hat=stack["x_hat"],
                x_prior=stack["x_prior"], innovation=stack["innovation"], P=stack["P"],
                cost=cost, t_physics=t_phys, states=states, row=rows[e]))
        return out


class _FixedBatch:
    """A policy without ``select``: it keeps its whole original batch; rows of ended episodes get
    zero measurements and their forces are dropped."""

    def __init__(self, policy: Any, n: int) -> None:
        self.policy, self.n0, self.alive = policy, n, np.arange(n)

    def act(self, y: np.ndarray) -> np.ndarray:
        if self.alive.size == self.n0:
            return np.asarray(self.policy.act(y), dtype=np.float64).reshape(-1)
        full = np.zeros((self.n0, y.shape[1]))
        full[self.alive] = y
        u = np.asarray(self.policy.act(full), dtype=np.float64).reshape(-1)
        return u[self.alive]

    def select(self, rows: np.ndarray) -> None:
        self.alive = self.alive[rows]

    @property
    def x_hat(self) -> np.ndarray | None:
        est = getattr(self.policy, "x_hat", None)
        return None if est is None else np.asarray(est)[self.alive]


def _estimator_snapshot(policy: object, x_hat: np.ndarray | None, n: int,
                        ) -> dict[str, np.ndarray]:
    """The estimator intermediates a recording logs (nan where the policy has none)."""
    est = getattr(policy, "estimator", None)
    nan4 = np.full((n, 4), np.nan)
    P = getattr(est, "P", None)
    return {"x_hat": x_hat if x_hat is not None else nan4,
            "x_prior": getattr(est, "x_prior", nan4),
            "innovation": getattr(est, "innovation", np.full((n, 2), np.nan)),
            "P": np.broadcast_to(P if P is not None else np.full((4, 4), np.nan), (n, 4, 4))}


#: Fewest episodes a shard of :func:`run_episodes` gets (smaller batches are run as one).
MIN_SHARD_ROWS = 32


def shard_count(n: int, nthread: int, backend: str, policy: object) -> int:
    """How many independent shards :func:`run_episodes` splits ``n`` episodes into.

    A batch on ``nthread ≥ 2`` physics threads runs as ``nthread`` shards of about ``n / nthread``
    episodes, each a :class:`Simulator` stepping its physics in its own Python thread
    (MuJoCo's batch and numpy's larger operations release the GIL): the policy and metrics work
    of one shard overlaps the physics of the others, where a single batch would leave the rollout
    threads idle during it. Results do not change (episodes are independent and each draws from its
    own generator). Only policies that declare ``independent_rows = True`` (every built-in; a plugin
    may opt in) are split — each shard gets a deep copy — others run as one batch.
    """
    if backend != "rollout" or nthread < 2 or getattr(policy, "independent_rows", False) is not True:
        return 1
    return max(1, min(nthread, n // MIN_SHARD_ROWS))


class _Cancelled(Exception):
    """Another shard failed or the caller was interrupted: stop this one."""


def run_episodes(plant: Plant, scenario: Scenario, policy: Any, *, seed: int,
                 episodes: Iterable[int] | np.ndarray, backend: Literal["rollout", "step"] = "rollout",
                 nthread: int | None = None, trajectory: bool = False,
                 initial_states: np.ndarray | None = None) -> BatchResult:
    """Run episodes ``episodes`` of the run seeded ``seed`` through the closed loop.

    Episode ``e`` draws everything from ``default_rng(episode_seed(seed, e))``, so its result does
    not depend on which other episodes share the batch, on the backend or on the thread count.

    Parameters
    ----------
    plant : the simulated plant (possibly mismatched with the policy's design model)
    scenario : the control problem
    policy : any policy of the protocol in :mod:`pendulum_lqg.plugins` — ``reset(n)`` (or
        ``reset(n, x_hat0=…)`` when ``scenario.estimate0 == "true"``), ``act(y) -> u``, and
        optionally ``select(rows)``, ``needs_state``, ``x_hat`` (for the estimation-error metrics),
        ``estimator`` (for recordings) and ``independent_rows`` (see :func:`shard_count`);
        built-in policies and plugins alike
    seed : the run's seed; episodes : episode numbers to run
    backend, nthread : see :class:`Simulator` (with ``nthread ≥ 2`` a large batch is split into
        shards, :func:`shard_count`)
    trajectory : keep full trajectories (for recordings), not only the streamed metrics
    initial_states : optional (len(episodes), 4) initial states replacing the scenario's
        ``x0``/``x0_std`` draw (e.g. a region-of-attraction grid)
    """
    episodes = [int(e) for e in episodes]
    nthread = thread_count(nthread)
    shards = shard_count(len(episodes), nthread, backend, policy)
    t0 = time.perf_counter()
    if shards == 1:
        return _run_batch(plant, scenario, policy, seed, episodes, backend, nthread, trajectory,
                          initial_states, None, t0)
    parts = np.array_split(np.arange(len(episodes)), shards)
    stop = threading.Event()
    with ThreadPoolExecutor(max_workers=min(shards, nthread),
                            thread_name_prefix="pendulum-lqg-shard") as pool:
        futures = [pool.submit(_run_batch, plant, scenario, copy.deepcopy(policy), seed,
                               [episodes[i] for i in part], backend, 1, trajectory,
                               None if initial_states is None
                               else np.asarray(initial_states)[part], stop, t0)
                   for part in parts]
        try:
            results = [f.result() for f in futures]
        except BaseException:
            stop.set()                      # the other shards end at their next control period
            raise
    rows = [r for res in results for r in res.rows]
    trajectories = None if not trajectory else [
        tr for res in results for tr in (res.trajectories or [])]
    return BatchResult(rows=rows, trajectories=trajectories,
                       shard_seconds=[t for res in results for t in res.shard_seconds])


def _run_batch(plant: Plant, scenario: Scenario, policy: Any, seed: int, episodes: list[int],
               backend: Literal["rollout", "step"], nthread: int, trajectory: bool,
               initial_states: np.ndarray | None, stop: threading.Event | None,
               t0: float) -> BatchResult:
    """:func:`run_episodes` on one batch (one :class:`Simulator`); ``t0``: the run's start
    (``time.perf_counter``), for :attr:`BatchResult.shard_seconds`."""
    start = time.perf_counter() - t0
    seeds = episode_seeds(seed, episodes)       # = [episode_seed(seed, e) …], hashed at once
    gens = episode_generators(seeds)            # = [default_rng(s) …]
    n = len(episodes)
    log = _TrajectoryLog() if trajectory else None
    with Simulator(plant, scenario, backend=backend, nthread=nthread) as sim:
        x0 = sim.reset(gens, initial_states=initial_states, private_generators=True)
        if scenario.estimate0 == "true":
            policy.reset(n, x_hat0=x0.copy())
        else:
            policy.reset(n)
        needs_state = bool(getattr(policy, "needs_state", False))
        can_select = callable(getattr(policy, "select", None))
        if not can_select:             # keep feeding the whole batch; use only the running rows
            policy = _FixedBatch(policy, n)
        for _ in range(sim.n_periods):
            if stop is not None and stop.is_set():
                raise _Cancelled
            y = sim.measure()
            x_now = sim.x
            u = policy.act(x_now if needs_state else y)
            x_hat = getattr(policy, "x_hat", None)
            if log is not None:
                snap = dict(t=sim.t, x=x_now, y=y, u=np.clip(u, -sim.u_max, sim.u_max),
                            **_estimator_snapshot(policy, x_hat, sim.n))
            res = sim.step(u, x_hat=x_hat)
            if log is not None:
                log.add(sim.ids, cost=res.cost, states=res.states, **snap)
            if res.failed.any():
                keep = np.nonzero(~res.failed)[0]
                sim.select(keep)
                policy.select(keep)
                if keep.size == 0:
                    break
        assert sim.metrics is not None
        rows = sim.metrics.rows(np.arange(n), np.array(seeds))
    for row, e in zip(rows, episodes, strict=True):
        row["episode"] = e
    trajectories = log.split(n, seeds, rows) if log is not None else None
    if trajectories is not None:
        for tr, e in zip(trajectories, episodes, strict=True):
            tr.episode = e
    return BatchResult(rows=rows, trajectories=trajectories,
                       shard_seconds=[(start, time.perf_counter() - t0)])
