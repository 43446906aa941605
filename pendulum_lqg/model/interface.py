"""What every simulated plant is: the :class:`SimulatedPlant` interface, its :class:`Layout`, and
the physics steps in one control period.

Two kinds of plant implement it: the MuJoCo cart-pole (:class:`~pendulum_lqg.model.plant.Plant`)
and a linear plant given as matrices (:class:`~pendulum_lqg.model.lti.LTIPlant`). The simulation
core (:mod:`pendulum_lqg.core`), the bench and the analyses ask a plant through these members
only, never which kind it is: a new kind of plant is one class with these members.

The scenario is typed ``Any`` here: :class:`~pendulum_lqg.core.scenario.Scenario` lives in the
core, which imports the plants (the layers run model → core, never back).
"""

from __future__ import annotations

from typing import Any, NamedTuple, Protocol, runtime_checkable

import msgspec
import numpy as np

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.util.limits import MAX_STEPS_PER_PERIOD, check_control_period


class Layout(msgspec.Struct, frozen=True, eq=False):
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


class LinearModel(NamedTuple):
    """The continuous linear model ``ẋ = A x + B u``, ``y = C x + D u`` of a plant."""

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray


@runtime_checkable
class SimulatedPlant(Protocol):
    """What the loop, the bench and the analyses ask of a plant (module docstring).

    ``simulators`` are the ``Scenario.plant`` kinds that can step it (``"mujoco"``,
    ``"linear-zoh"``, ``"linear-euler"``); :func:`pendulum_lqg.core.physics.make_physics` builds
    the backend, from :meth:`sampled` for the linear kinds.
    """

    @property
    def timestep(self) -> float:
        """The physics step h [s]."""
        ...

    @property
    def simulators(self) -> tuple[str, ...]: ...

    def layout(self, scenario: Any) -> Layout:
        """Its vectors under ``scenario`` (refusing, one line naming the key, what its loop
        cannot run)."""
        ...

    def limits(self, scenario: Any) -> tuple[float, float, Any]:
        """``(theta_max, track_limit, u_max)`` in force under ``scenario`` (``inf``: none)."""
        ...

    def linear_model(self) -> LinearModel:
        """Its continuous ``(A, B, C, D)`` (the cart-pole's linearisation about the upright)."""
        ...

    def sampled(self, period: float, kind: str = "linear-zoh") -> tuple[np.ndarray, np.ndarray]:
        """``(Φ, Γ)`` of its linear model at ``period`` (``kind``: the exact ZOH, or forward
        Euler ``(I + T A, T B)``)."""
        ...

    def fingerprint(self) -> str:
        """SHA-256 of what defines it (equal for equal plants, stable across runs)."""
        ...


def steps_per_period(plant: SimulatedPlant, dt: float) -> int:
    """Number of physics steps in one control period (with the plant, not the linearisation: the
    simulation core imports no design code).

    ``dt`` must be a whole number k of physics steps h with ``1 ≤ k ≤``
    :data:`MAX_STEPS_PER_PERIOD` and ``dt`` within the bounds of
    :func:`~pendulum_lqg.util.limits.check_control_period`; otherwise a one-line :class:`ConfigError`
    naming ``control_period``.
    """
    dt = check_control_period(dt)
    h = plant.timestep
    k = round(dt / h)
    if k < 1 or abs(k * h - dt) > 1e-9 * max(dt, h):
        raise ConfigError(f"control_period: {dt!r} s is not a positive integer multiple of the "
                          f"physics step {h!r} s")
    if k > MAX_STEPS_PER_PERIOD:
        raise ConfigError(f"control_period: expected at most {MAX_STEPS_PER_PERIOD} physics "
                          f"steps of {h!r} s (the ceiling), got {dt!r} s = {k} steps")
    return int(k)

