"""Realistic sensing and actuation: delay lines, sample losses, actuator lag, per-episode models.

All are off by default (``Scenario`` fields), and then nothing here runs: the loop is the plain
sample-and-hold loop. Each feature keeps per-row state, batched, indexed by each row's own period,
and emptied when a row (re)starts:

* measurement delay ``d_m`` periods: a ring ``(n, d_m, p)``; at sample n the policy gets the
  sample taken at n − d_m (nan until one has arrived);
* dropouts: a lost sample becomes ``[nan, nan]``; one uniform per period from the episode's child
  generator (:func:`~pendulum_lqg.core.seeding.child_generator`), so the episode's noise stream is
  the same with and without losses;
* actuator delay ``d_a`` periods: a ring ``(n, d_a)`` of requested forces (``(n, d_a, m)`` for a
  plant of m > 1 inputs; 0 until the first arrives);
* actuator lag τ: the first-order response ``f_j = u + (f_{j−1} − u)·e^{−h/τ}`` at the end of
  each physics step j, so the physics gets a force per step;
* randomised models: each episode's simulated model from three uniforms of its child generator
  (:class:`~pendulum_lqg.model.overrides.Randomization`, drawn by the plant:
  :meth:`~pendulum_lqg.model.interface.MujocoPlant.varied`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, cast

import mujoco
import numpy as np

from pendulum_lqg.core.noise import UniformStream
from pendulum_lqg.core.seeding import child_generator

if TYPE_CHECKING:
    from pendulum_lqg.core.physics import Physics
    from pendulum_lqg.core.scenario import Scenario
    from pendulum_lqg.model.interface import MujocoPlant, SimulatedPlant


class SensingActuation:
    """The per-row state of the realistic sensing and actuation of a simulator's rows.

    Parameters
    ----------
    plant : the simulated plant (the randomised models are variations of it)
    scenario : the delays, dropout, lag and randomisation to apply
    k : physics steps per control period
    outputs : the length of the measurement y (the cart-pole's 2)
    inputs : the length of u (1: u is one number per row)
    """

    def __init__(self, plant: SimulatedPlant, scenario: Scenario, k: int, *, outputs: int = 2,
                 inputs: int = 1) -> None:
        self.plant, self.scenario = plant, scenario
        self.outputs = outputs                                  # the length of y
        self.input_shape = () if inputs == 1 else (inputs,)    # one row's u
        self.meas_delay = scenario.measurement_delay_periods     # whole control periods
        self.act_delay = scenario.actuator_delay_periods
        self.dropout = scenario.dropout
        self.randomized = not scenario.randomize.is_empty()
        self.drops = UniformStream() if self.dropout > 0 else None
        #: e^{−(j+1)h/τ}, j = 0 … k−1: the lag's decay over the physics steps of a period
        h = plant.timestep
        self.lag_decay = (np.exp(-np.arange(1, k + 1) * h / scenario.actuator_tau)
                          if scenario.actuator_tau > 0 else None)
        #: no delay and no losses: the measurement is the noisy sample of this period
        self.plain_sensing = not (self.meas_delay or self.drops is not None)
        #: no delay and no lag: the force requested is the force held over the period
        self.plain_actuation = not (self.act_delay or self.lag_decay is not None)
        self.active = not (self.plain_sensing and self.plain_actuation and not self.randomized)
        self.row_models: list[mujoco.MjModel] | None = None

    def reset(self, generators: list[np.random.Generator], rows: np.ndarray | None,
              physics: Physics | None) -> None:
        """Empty the delay lines and the lag of the (re)started rows (all, or ``rows``); draw their
        randomised models and dropout streams from each episode's child generator."""
        if not self.active:
            return
        if rows is None:
            n = len(generators)
            self.y_ring = np.full((n, self.meas_delay, self.outputs), np.nan)     # nothing has arrived yet
            self.u_ring = np.zeros((n, self.act_delay, *self.input_shape))   # 0 until the first
            self.force = np.zeros(n)                            # the lag's output
        else:
            self.y_ring[rows] = np.nan
            self.u_ring[rows] = 0.0
            self.force[rows] = 0.0
        if not (self.randomized or self.drops is not None):
            return
        children = [child_generator(g) for g in generators]
        if self.randomized:                                     # the child's first draws
            models = [self._episode_model(c.random(3)) for c in children]
            if rows is None or self.row_models is None:
                self.row_models = models
            else:
                for r, m in zip(np.asarray(rows).tolist(), models, strict=True):
                    self.row_models[r] = m
            if physics is not None:
                physics.set_models(self.row_models)
        if self.drops is not None:
            self.drops.reset(children, rows)

    def _episode_model(self, r: np.ndarray) -> mujoco.MjModel:
        """The simulated model of an episode with randomisation uniforms ``r`` (3,)."""
        # only a MuJoCo plant is randomised (the linear simulators and the plant files refuse
        # ``randomize`` as the scenario is laid out)
        plant = cast("MujocoPlant", self.plant)
        return plant.varied(self.scenario.randomize.scales(r))

    def sense(self, y: np.ndarray, rows: np.ndarray, period: np.ndarray) -> np.ndarray:
        """Dropouts (lost samples become nan) and the measurement delay line of ``rows`` (their
        current ``period``s) applied to this period's noisy samples ``y`` (len(rows), p)."""
        if self.drops is not None:
            y[self.drops.draw(rows) < self.dropout] = np.nan
        if self.meas_delay:
            slot = period % self.meas_delay                    # holds the sample taken d periods ago
            y, self.y_ring[rows, slot] = self.y_ring[rows, slot], y
        return y

    def actuate(self, u: np.ndarray, period: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        """The actuator delay line and lag for the requested (saturated) forces ``u`` (n,) — or
        (n, m) with several inputs, delay only — of rows at periods ``period``: ``(command,
        steps)`` — the command reaching the actuator (n,) or (n, m) (after
        the delay; what the metrics' ``u`` is), and with a lag the force of each physics step
        (n, k), else ``None``."""
        if self.act_delay:
            idx = np.arange(u.shape[0])
            slot = period % self.act_delay                    # holds the force requested d periods ago
            u, self.u_ring[idx, slot] = self.u_ring[idx, slot], u
        if self.lag_decay is None:
            return u, None
        steps = u[:, None] + (self.force - u)[:, None] * self.lag_decay
        self.force = steps[:, -1].copy()
        return u, steps

    def select(self, rows: np.ndarray, physics: Physics | None) -> None:
        """Keep only these rows (finished episodes leave the batch)."""
        if not self.active:
            return
        self.y_ring, self.u_ring = self.y_ring[rows], self.u_ring[rows]
        self.force = self.force[rows]
        if self.row_models is not None:
            self.row_models = [self.row_models[r] for r in np.asarray(rows).tolist()]
            if physics is not None:
                physics.set_models(self.row_models)
        if self.drops is not None:
            self.drops.select(rows)
