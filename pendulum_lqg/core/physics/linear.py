"""The MJCF model's linearisation about the upright, stepped in numpy instead of MuJoCo."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from pendulum_lqg.errors import ConfigError

if TYPE_CHECKING:
    import mujoco

    from pendulum_lqg.core.period import PeriodView
    from pendulum_lqg.model.interface import SimulatedPlant


class LinearPhysics:
    """The :class:`~pendulum_lqg.core.physics.base.Physics` of ``ẋ = A x + B u`` (``Scenario.plant``).

    ``linear-zoh``: ``x ← Φ_h x + Γ_h u`` at every physics step h (the exact ZOH of ``ẋ = Ax + Bu``,
    so the end of the period is exactly ``Φ_T x + Γ_T u``). ``linear-euler``: the lecture's update
    ``x ← x + T·(A x + B u)`` once per control period; the k physics-step samples in between (which
    the failure rule and the cost integrate over) lie on the straight line to it, the last one
    exactly on it. State noise is added at the end of the period by the loop, as for MuJoCo; a
    linear plant has no force noise, no actuator lag and no randomised models (the scenario refuses
    them). The plant gives ``(Φ, Γ)`` (:meth:`SimulatedPlant.sampled
    <pendulum_lqg.model.interface.SimulatedPlant.sampled>`): an LTI plant given as matrices
    (:mod:`pendulum_lqg.model.lti`) is stepped by its own exact sampled model ``x ← Φ x + Γ u``,
    once per control period (its physics step is T).
    """

    def __init__(self, plant: SimulatedPlant, kind: str, k: int) -> None:
        self.kind, self.k = kind, k
        self._frac = (np.arange(1, k + 1) / k)[None, :, None]
        if kind not in ("linear-zoh", "linear-euler"):
            raise ConfigError(f"plant: expected 'linear-zoh' or 'linear-euler', got {kind!r}")
        # the exact ZOH at every physics step h, or Euler over the whole period k·h
        period = plant.timestep if kind == "linear-zoh" else k * plant.timestep
        self.Phi, Gamma = plant.sampled(period, kind)
        # one input: Γ (n,), u (rows,) enters as u·Γ; m inputs (an LTI plant, k = 1): Γ u
        self.Gamma = Gamma[:, 0] if Gamma.shape[1] == 1 else Gamma

    def set_models(self, models: list[mujoco.MjModel]) -> None:
        raise ConfigError("randomize: per-episode models need plant = 'mujoco'")

    def advance(self, x: np.ndarray, u: np.ndarray, forces: np.ndarray | None,
                out: PeriodView) -> np.ndarray | None:
        """See :meth:`Physics.advance <pendulum_lqg.core.physics.base.Physics.advance>`;
        nothing resets."""
        states = out.states
        if self.Gamma.ndim == 2:                       # an LTI plant of m inputs, k = 1
            states[:, 0] = np.einsum("ij,nj->ni", self.Phi, x) + np.einsum(
                "ij,nj->ni", self.Gamma, u)
        elif self.kind == "linear-zoh":
            for j in range(self.k):
                x = np.einsum("ij,nj->ni", self.Phi, x) + u[:, None] * self.Gamma
                states[:, j] = x
        else:
            x_end = np.einsum("ij,nj->ni", self.Phi, x) + u[:, None] * self.Gamma
            states[...] = x[:, None, :] + self._frac * (x_end - x)[:, None, :]
            states[:, -1] = x_end
        return None                                        # a linear model never resets
