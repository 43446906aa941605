"""The one interface every physics backend implements.

A backend advances ``n`` rows (one simulated cart-pole each) by one control period of ``k`` physics
steps, with each row's force held (or given per physics step), optional generalised forces on the
slider and the hinge at every step (force noise), and writes the state after each step into the
period buffer (:mod:`pendulum_lqg.core.period`). It knows nothing of policies, noise draws, costs
or the failure rule: the loop (:class:`~pendulum_lqg.core.loop.Simulator`) applies those
(:mod:`pendulum_lqg.core.rules`) to what the backend wrote.

Adding a backend — say MuJoCo Warp on a GPU — is one new class in one new file of this package
that implements :class:`Physics`, plus its name in :func:`pendulum_lqg.core.physics.make_physics`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol

import numpy as np

if TYPE_CHECKING:
    import mujoco

    from pendulum_lqg.core.period import PeriodView


class Physics(Protocol):
    """Advance rows of the cart-pole by one control period.

    Attributes
    ----------
    k : physics steps per control period
    """

    k: int

    def advance(self, x: np.ndarray, u: np.ndarray, forces: np.ndarray | None,
                out: PeriodView) -> np.ndarray | None:
        """k physics steps of rows ``0 … n−1`` (``n = out.n``) from the states ``x`` (n, 4).

        Parameters
        ----------
        x : (n, 4) ``[p, θ, ṗ, θ̇]`` at the start of the period
        u : (n,) the force [N] of each row held over the period, or (n, k) one per physics step
            (an actuator lag); already saturated and finite
        forces : (n, k, 2) generalised forces [N, N·m] on slider and hinge per physics step
            (force noise), or ``None``
        out : the period's rows: the backend writes ``out.states`` (n, k, 4), the state after
            each physics step, and nothing else the caller reads afterwards (column 4 of the
            buffer may be overwritten: the loop writes the forces after this call)

        Returns
        -------
        (n,) bool: the rows whose simulation became unstable (MuJoCo reset its data); their
        states stop at the last good step and repeat it. ``None`` when no row was reset (the
        common case, told apart without an array operation)
        """
        ...

    def set_models(self, models: list[mujoco.MjModel]) -> None:
        """Simulate row i with ``models[i]`` (per-episode randomised models of the same layout)."""
        ...
