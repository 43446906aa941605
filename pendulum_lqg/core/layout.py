"""What the loop needs to know about the simulated plant's vectors: their sizes, names and roles.

The one loop (:class:`~pendulum_lqg.core.loop.Simulator`) steps two kinds of plant:

* the cart-pole (:class:`~pendulum_lqg.model.plant.Plant`, MuJoCo or its linearisation): the state
  ``x = [p, θ, ṗ, θ̇]``, the measurement ``y = [p, θ]`` (the first two states), the scenario's
  initial state, noise densities and cost weights, and the failure rule of the pole's angle and the
  track (:func:`~pendulum_lqg.core.rules.detect_failure`);
* a linear plant given as matrices (:class:`~pendulum_lqg.model.lti.LTIPlant`): ``n`` states and ``p``
  outputs named by its file, ``y = C x + v``, ``m`` inputs, its own initial state, noise
  covariances (the state's jump over one period, ``Φ``-consistent, and V), cost weights (diagonal,
  or the full ``[[Q, N], [Nᵀ, R]]``) and optional per-state failure limits; the scenario
  contributes the duration, the noise scale and the force limit, if it sets one.

:func:`layout` turns either into one :class:`Layout`; nothing else in the core asks which kind of
plant it runs.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.model.plant import OUTPUT_NAMES, STATE_NAMES

if TYPE_CHECKING:
    from pendulum_lqg.core.scenario import Scenario


@dataclass(frozen=True, eq=False)
class Layout:
    """The vectors of one simulated plant under one scenario.

    Attributes
    ----------
    states, outputs : names of x (n) and y (p); the metrics are named after them
    x0, x0_std : (n,) mean and standard deviation of the initial state
    C : (p, n) the measurement matrix, or ``None``: ``y`` is the first p states (the cart-pole)
    cost_Q : (n,) diagonal of Q; cost_R : R, weights of ``J = ∫ xᵀQx + R u² dt``
    state_limits : (n,) per-state failure limits of an LTI plant (``inf``: none), or ``None``:
        the cart-pole's rule (``theta_max`` and the track)
    covariances : ``(Wd, V)`` of an LTI plant, the covariance of the state's jump over one period
        (n, n) and of the measurement noise (p, p), or ``None``: the scenario's noise model
    reported : the leading state columns with ``rms_*`` / ``max_abs_*`` metrics (cart-pole: p, θ)
    order : the order of their metric columns (cart-pole: θ first, as the results always had)
    settle : the column of the settling time, or ``None`` (an LTI plant has no pole angle)
    inputs : names of u (m); one input's metrics are ``rms_u``, ``max_abs_u``, several inputs'
        ``rms_NAME``, ``max_abs_NAME``
    cost_matrix : ``[[Q, N], [Nᵀ, R]]`` (n+m, n+m) when the cost weights are not diagonal (an LTI
        plant's full Q or cross term N), else ``None`` (``cost_Q``, ``cost_R`` are the diagonal)
    """

    states: tuple[str, ...]
    outputs: tuple[str, ...]
    x0: np.ndarray
    x0_std: np.ndarray
    C: np.ndarray | None
    cost_Q: tuple[float, ...]
    cost_R: float
    state_limits: np.ndarray | None
    covariances: tuple[np.ndarray, np.ndarray] | None
    reported: int
    order: tuple[int, ...]
    settle: int | None
    inputs: tuple[str, ...] = ("u",)
    cost_matrix: np.ndarray | None = None

    @property
    def m(self) -> int:
        return len(self.inputs)

    @property
    def n(self) -> int:
        return len(self.states)

    @property
    def p(self) -> int:
        return len(self.outputs)


#: The cart-pole's layout (with the default scenario's initial state and weights): metrics of p
#: and θ (θ's columns first), the settling time of θ, ``y = [p, θ]``.
CARTPOLE = Layout(states=STATE_NAMES, outputs=OUTPUT_NAMES, x0=np.array([0.0, 0.1, 0.0, 0.0]),
                  x0_std=np.zeros(4), C=None, cost_Q=(1.0,) * 4, cost_R=1.0, state_limits=None,
                  covariances=None, reported=2, order=(1, 0), settle=1)


def layout(plant: Any, scenario: Scenario) -> Layout:
    """The :class:`Layout` of ``plant`` (a cart-pole ``Plant`` or an ``LTIPlant``) under
    ``scenario``."""
    if not getattr(plant, "is_lti", False):
        return dataclasses.replace(CARTPOLE, x0=np.asarray(scenario.x0),
                                   x0_std=np.asarray(scenario.x0_std), cost_Q=scenario.cost_Q,
                                   cost_R=scenario.cost_R)
    return _lti_layout(plant, scenario)


def _lti_layout(plant: Any, scenario: Scenario) -> Layout:
    """An LTI plant's layout; refuses what its loop cannot run, one line naming the key."""
    n, m = plant.n_states, plant.n_inputs
    if m > 1 and scenario.actuator_tau > 0:
        raise ConfigError(f"actuator_tau: the actuator's lag takes one input; {plant.name!r} "
                          f"has {m}")
    if scenario.plant != "linear-zoh":
        raise ConfigError(f"plant: an LTI plant runs as its own exact sampled model "
                          f"(plant = 'linear-zoh'), got {scenario.plant!r}")
    if not math.isclose(scenario.control_period, plant.control_period, rel_tol=1e-12):
        raise ConfigError(f"control_period: the LTI plant {plant.name!r} is sampled at "
                          f"{plant.control_period:g} s, got {scenario.control_period:g} s")
    weight = np.block([[np.asarray(plant.Q), plant.cross_weight],
                       [plant.cross_weight.T, np.asarray(plant.R)]])
    diagonal = bool(np.all(weight == np.diag(np.diag(weight))))
    zeros = np.zeros(n)
    limits = plant.state_limits if plant.state_limits is not None else np.full(n, math.inf)
    return Layout(states=plant.state_names, outputs=plant.output_names,
                  x0=zeros if plant.x0 is None else np.asarray(plant.x0, dtype=float),
                  x0_std=zeros if plant.x0_std is None else np.asarray(plant.x0_std, dtype=float),
                  C=np.asarray(plant.C, dtype=float), cost_Q=tuple(np.diag(weight)[:n].tolist()),
                  cost_R=float(weight[n, n]), state_limits=limits,
                  covariances=(plant.process_covariance(), np.asarray(plant.V, dtype=float)),
                  reported=n, order=tuple(range(n)), settle=None,
                  inputs=("u",) if m == 1 else plant.input_names,
                  cost_matrix=None if diagonal and m == 1 else weight)
