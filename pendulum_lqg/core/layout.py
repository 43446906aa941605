"""What the loop needs to know about the simulated plant's vectors: their sizes, names and roles.

The one loop (:class:`~pendulum_lqg.core.loop.Simulator`) steps any
:class:`~pendulum_lqg.model.interface.SimulatedPlant`: the cart-pole
(:class:`~pendulum_lqg.model.plant.Plant`, MuJoCo or its linearisation; ``x = [p, θ, ṗ, θ̇]``,
``y = [p, θ]``, the failure rule of the pole's angle and the track,
:func:`~pendulum_lqg.core.rules.detect_failure`) or a linear plant given as matrices
(:class:`~pendulum_lqg.model.lti.LTIPlant`, :mod:`pendulum_lqg.model.lti_layout`). Each plant
gives its own :class:`Layout` (:class:`~pendulum_lqg.model.interface.Layout`, re-exported here);
nothing in the core asks which kind of plant it runs.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pendulum_lqg.model.interface import Layout, SimulatedPlant
from pendulum_lqg.model.plant import CARTPOLE as CARTPOLE  # its old home

if TYPE_CHECKING:
    from pendulum_lqg.core.scenario import Scenario


def layout(plant: SimulatedPlant, scenario: Scenario) -> Layout:
    """The :class:`Layout` of ``plant`` (a cart-pole ``Plant`` or an ``LTIPlant``) under
    ``scenario`` (:meth:`SimulatedPlant.layout
    <pendulum_lqg.model.interface.SimulatedPlant.layout>`)."""
    return plant.layout(scenario)

