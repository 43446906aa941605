"""The :class:`~pendulum_lqg.model.interface.Layout` of a plant given as matrices.

An LTI plant (:class:`~pendulum_lqg.model.lti.LTIPlant`): ``n`` states and ``p`` outputs named by
its file, ``y = C x + v``, ``m`` inputs, its own initial state, noise covariances (the state's jump
over one period, ``Φ``-consistent, and V), cost weights (diagonal, or the full
``[[Q, N], [Nᵀ, R]]``) and optional per-state failure limits; the scenario contributes the
duration, the noise scale and the force limit, if it sets one. The plant is typed ``Any``: this
module is what :meth:`LTIPlant.layout <pendulum_lqg.model.lti.LTIPlant.layout>` calls.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.model.interface import Layout


def lti_layout(plant: Any, scenario: Any) -> Layout:
    """An LTI plant's layout; refuses what its loop cannot run, one line naming the key."""
    n, m = plant.n_states, plant.n_inputs
    if m > 1 and scenario.actuator_tau > 0:
        raise ConfigError(f"actuator_tau: the actuator's lag takes one input; {plant.name!r} "
                          f"has {m}")
    if scenario.plant not in plant.simulators:
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
