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

from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import msgspec
import numpy as np

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.util.limits import MAX_STEPS_PER_PERIOD, check_control_period

if TYPE_CHECKING:        # the design code (scipy) only where a model is discretised or checked
    from pendulum_lqg.design.structure import StructureReport


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


class ContinuousModel(msgspec.Struct, frozen=True):
    """``ẋ = Ax + Bu + F f``, ``y = Cx + Du``: a plant's continuous linear model (about its
    equilibrium; :meth:`SimulatedPlant.linear_model`).

    Attributes
    ----------
    A : (n, n), B : (n, m) per unit of each input (N or N·m), C : (p, n), D : (p, m)
    F : (n, nv) input matrix of the joints' generalised forces (``qfrc_applied``; the cart-pole's
        ``[f_slider (N), τ_hinge (N m)]``), used when process noise enters as forces, or ``None``
        where the plant has no such noise (a plant given as matrices)
    """

    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    F: np.ndarray | None = None

    def structure(self) -> StructureReport:
        from pendulum_lqg.design.structure import structure

        return structure(self.A, self.B, self.C)


class DiscreteModel(msgspec.Struct, frozen=True):
    """``x[n+1] = Φ x[n] + Γ u[n]``, ``y[n] = C x[n]`` at period ``dt``."""

    Phi: np.ndarray
    Gamma: np.ndarray
    C: np.ndarray
    dt: float
    method: str

    def structure(self) -> StructureReport:
        from pendulum_lqg.design.structure import structure

        return structure(self.Phi, self.Gamma, self.C, discrete=True)


def discretize_zoh(model: ContinuousModel, dt: float) -> DiscreteModel:
    """Exact zero-order-hold discretisation of ``(A, B)`` at period ``dt``."""
    from pendulum_lqg.design import zoh

    Phi, Gamma = zoh(model.A, model.B, dt)
    return DiscreteModel(Phi=Phi, Gamma=Gamma, C=model.C, dt=float(dt), method="zoh")



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

    def linear_model(self) -> ContinuousModel:
        """Its continuous ``(A, B, C, D)`` (the cart-pole's linearisation about the upright)."""
        ...

    def sampled(self, period: float, kind: str = "linear-zoh") -> tuple[np.ndarray, np.ndarray]:
        """``(Φ, Γ)`` of its linear model at ``period`` (``kind``: the exact ZOH, or forward
        Euler ``(I + T A, T B)``)."""
        ...

    def fingerprint(self) -> str:
        """SHA-256 of what defines it (equal for equal plants, stable across runs)."""
        ...

    @property
    def u_max(self) -> Any:
        """The input limit of its actuators in physical units [N or N·m]: one number, or one
        per input (``inf``: none)."""
        ...

    def transition(self, period: float) -> DiscreteModel | None:
        """``(Φ, Γ)`` at ``period`` by a second route, its simulator's own one-step Jacobians
        composed over the period (MuJoCo's ``mjd_transitionFD``, integrator included), or
        ``None`` where the matrices are the plant (no other route to check them by)."""
        ...


class MujocoPlant(SimulatedPlant, Protocol):
    """A plant MuJoCo steps (the cart-pole, a plant file's MJCF): what the MuJoCo backends
    (:mod:`pendulum_lqg.core.physics`) read of it.

    The state is ``x = [qpos[qpos_index] − x_offset, qvel[qvel_index]]`` (``x_offset``: the
    equilibrium's joint positions, ``None`` when it is qpos = 0); MuJoCo's ``ctrl`` is
    ``u / ctrl_gear`` (u in N or N·m).
    """

    @property
    def model(self) -> Any:
        """The compiled ``mujoco.MjModel``."""
        ...

    @property
    def qpos_index(self) -> np.ndarray: ...

    @property
    def qvel_index(self) -> np.ndarray: ...

    @property
    def x_offset(self) -> np.ndarray | None: ...

    @property
    def ctrl_gear(self) -> float: ...

    def varied(self, scales: dict[str, float]) -> Any:
        """The compiled model of one episode of a randomised scenario: its parameters multiplied
        by ``scales`` (:meth:`Randomization.scales
        <pendulum_lqg.model.overrides.Randomization.scales>`); refused, one line naming
        ``randomize``, by a plant that has no such parameters."""
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

