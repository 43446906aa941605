"""Linearisation of the MuJoCo cart-pole about the upright equilibrium.

* :func:`linearize` — continuous ``(A, B, C, D)`` (and the generalised-force input ``F``) by central
  finite differences of MuJoCo's own forward dynamics and sensors;
* :func:`discretize_transition` — discrete ``(Φ, Γ)`` at a control period ``T = k·h`` by composing
  ``mjd_transitionFD`` over the ``k`` physics steps (what the simulator really does, integrator
  included);
* the same from ``(A, B)`` by exact zero-order hold is
  :func:`~pendulum_lqg.model.interface.discretize_zoh` (any plant's linear model);
* :func:`analytic_linearization` — a rigid-body reference built from the model's own masses, centre of
  mass and inertia, used by the tests to cross-check the finite differences.

State ``x = [p, θ, ṗ, θ̇]``, input the cart force [N], output ``y = [p, θ]``.
"""

from __future__ import annotations

from typing import Protocol

import mujoco
import numpy as np

from pendulum_lqg.model.interface import (
    ContinuousModel,
    DiscreteModel,
    SimulatedPlant,
    steps_per_period,
)
from pendulum_lqg.model.interface import discretize_zoh as discretize_zoh  # public here too


class CartPoleModel(SimulatedPlant, Protocol):
    """What the linearisation reads of the cart-pole (:class:`pendulum_lqg.model.plant.Plant`,
    whose :meth:`~pendulum_lqg.model.plant.Plant.linear_model` calls :func:`linearize`: a
    structural type, so this module does not import the one that imports it)."""

    @property
    def model(self) -> mujoco.MjModel: ...
    @property
    def qpos_index(self) -> np.ndarray: ...
    @property
    def qvel_index(self) -> np.ndarray: ...
    @property
    def sensor_index(self) -> np.ndarray: ...
    @property
    def ctrl_gear(self) -> float: ...
    @property
    def gravity(self) -> float: ...
    @property
    def cart_mass(self) -> float: ...
    @property
    def pole_mass(self) -> float: ...
    @property
    def pole_com(self) -> float: ...
    @property
    def pole_inertia_com(self) -> float: ...

#: Finite-difference step for states and inputs (central differences: error O(eps²)).
FD_EPS = 1e-6


def _equilibrium(plant: CartPoleModel) -> mujoco.MjData:
    data = mujoco.MjData(plant.model)
    mujoco.mj_resetData(plant.model, data)
    data.qpos[:] = 0.0
    data.qvel[:] = 0.0
    data.ctrl[:] = 0.0
    return data


def _dynamics(plant: CartPoleModel, data: mujoco.MjData, x: np.ndarray, u: float, f: np.ndarray,
              ) -> tuple[np.ndarray, np.ndarray]:
    """``(ẋ, y)`` at state x, force u and generalised forces f, from MuJoCo's forward dynamics."""
    m = plant.model
    data.qpos[plant.qpos_index] = x[:2]
    data.qvel[plant.qvel_index] = x[2:]
    data.ctrl[0] = u / plant.ctrl_gear          # u in newtons: the force is gear · ctrl
    data.qfrc_applied[:] = 0.0
    data.qfrc_applied[plant.qvel_index] = f
    mujoco.mj_forward(m, data)
    xdot = np.concatenate([data.qvel[plant.qvel_index], data.qacc[plant.qvel_index]])
    return xdot, data.sensordata[plant.sensor_index].copy()


def linearize(plant: CartPoleModel, *, eps: float = FD_EPS) -> ContinuousModel:
    """Continuous linearisation about ``x = 0, u = 0`` by central differences of ``mj_forward``.

    The actuator must be unsaturated at the equilibrium (ctrl = 0 lies inside ``ctrlrange``), so
    ``B`` is the force-to-acceleration map of the motor. ``ẋ`` for the positions is ``qvel``
    (hinge and slide joints), for the velocities ``qacc``.
    """
    data = _equilibrium(plant)
    n, m = 4, 1
    x0, f0 = np.zeros(n), np.zeros(2)
    A, B = np.zeros((n, n)), np.zeros((n, m))
    C, D = np.zeros((2, n)), np.zeros((2, m))
    F = np.zeros((n, 2))
    for i in range(n):
        dx = np.zeros(n)
        dx[i] = eps
        fp, yp = _dynamics(plant, data, x0 + dx, 0.0, f0)
        fm, ym = _dynamics(plant, data, x0 - dx, 0.0, f0)
        A[:, i] = (fp - fm) / (2 * eps)
        C[:, i] = (yp - ym) / (2 * eps)
    fp, yp = _dynamics(plant, data, x0, eps, f0)
    fm, ym = _dynamics(plant, data, x0, -eps, f0)
    B[:, 0] = (fp - fm) / (2 * eps)
    D[:, 0] = (yp - ym) / (2 * eps)
    for j in range(2):
        df = np.zeros(2)
        df[j] = eps
        fp, _ = _dynamics(plant, data, x0, 0.0, df)
        fm, _ = _dynamics(plant, data, x0, 0.0, -df)
        F[:, j] = (fp - fm) / (2 * eps)
    return ContinuousModel(A=A, B=B, C=C, D=D, F=F)


def discretize_transition(plant: CartPoleModel, dt: float, *, eps: float = FD_EPS) -> DiscreteModel:
    """``(Φ, Γ)`` by composing MuJoCo's one-step ``mjd_transitionFD`` over one control period.

    With ``k`` physics steps per period and one-step Jacobians ``(A_h, B_h)``:
    ``Φ = A_hᵏ`` and ``Γ = Σ_{j<k} A_hʲ B_h`` (the input is held over the period). This includes
    the integrator's own discretisation, so it differs from the exact ZOH by O(h).
    """
    k = steps_per_period(plant, dt)
    m = plant.model
    data = _equilibrium(plant)
    mujoco.mj_forward(m, data)
    nx = 2 * m.nv + m.na
    Ah, Bh = np.zeros((nx, nx)), np.zeros((nx, m.nu))
    mujoco.mjd_transitionFD(m, data, eps, True, Ah, Bh, None, None)
    idx = np.concatenate([plant.qvel_index, m.nv + plant.qvel_index])  # tangent-space order
    Ah, Bh = Ah[np.ix_(idx, idx)], Bh[idx, :] / plant.ctrl_gear      # per newton, not per ctrl
    Phi, Gamma = np.eye(4), np.zeros((4, m.nu))
    for _ in range(k):
        Gamma = Ah @ Gamma + Bh
        Phi = Ah @ Phi
    C = linearize(plant, eps=eps).C  # the sensors do not depend on the period
    return DiscreteModel(Phi=Phi, Gamma=Gamma, C=C, dt=k * plant.timestep,
                         method="mjd_transitionFD")


def analytic_linearization(plant: CartPoleModel) -> ContinuousModel:
    r"""Rigid-body cart-pole linearised at the upright, from the model's own parameters.

    Generalised coordinates ``q = [p, θ]``; mass matrix at θ = 0

    .. math:: M_0 = \begin{bmatrix} m_c + m_p + a_p & m_p l \\ m_p l & I_p + m_p l^2 + a_θ
              \end{bmatrix},

    gravity stiffness ``∂τ/∂θ = m_p g l`` (the pole's potential is ``m_p g l \cos θ``), joint damping
    ``d``, input on the slider. ``l`` is the hinge-to-centre-of-mass distance, ``I_p`` the pole
    inertia about its centre of mass around the hinge axis, ``a`` the joint armatures — all read from
    the compiled model.
    """
    m = plant.model
    mc, mp, l_com, Ip, g = (plant.cart_mass, plant.pole_mass, plant.pole_com,
                            plant.pole_inertia_com, plant.gravity)
    dof = plant.qvel_index
    arm = m.dof_armature[dof]
    damp = m.dof_damping[dof]
    M0 = np.array([[mc + mp + arm[0], mp * l_com], [mp * l_com, Ip + mp * l_com**2 + arm[1]]])
    Minv = np.linalg.inv(M0)
    stiffness = np.array([[0.0, 0.0], [0.0, mp * g * l_com]])
    A = np.zeros((4, 4))
    A[:2, 2:] = np.eye(2)
    A[2:, :2] = Minv @ stiffness
    A[2:, 2:] = -Minv @ np.diag(damp)
    B = np.zeros((4, 1))
    B[2:, 0] = Minv @ np.array([1.0, 0.0])           # per newton on the slider
    F = np.zeros((4, 2))
    F[2:, :] = Minv
    C = np.hstack([np.eye(2), np.zeros((2, 2))])
    return ContinuousModel(A=A, B=B, C=C, D=np.zeros((2, 1)), F=F)
