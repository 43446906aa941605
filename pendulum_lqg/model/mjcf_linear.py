"""The linearisation of any MuJoCo model about an equilibrium, in the plant's own coordinates.

The state is ``x = [q − q*, q̇]`` over the model's hinge and slide joints (``q*`` the equilibrium's
qpos, the velocities' equilibrium 0), the inputs are the actuators' forces or torques in physical
units (``ctrl = u / gear``), the outputs the named sensors. Two routes, each a check of the other:

* :func:`continuous_model` — ``(A, B, C)`` by central differences of ``mj_forward`` (``ẋ`` is
  ``[q̇, q̈]``, the sensors ``y``), the route of :func:`pendulum_lqg.model.linearize.linearize`;
* :func:`transition_model` — ``(Φ, Γ)`` of one control period of ``k`` physics steps by composing
  MuJoCo's one-step ``mjd_transitionFD`` (its integrator included), which differs from the exact
  ZOH of ``(A, B)`` by O(h).

Nothing here holds a physical constant: the model is the source of every number.
"""

from __future__ import annotations

import mujoco
import numpy as np

#: Finite-difference step of states and inputs (central differences: error O(eps²)).
FD_EPS = 1e-6


class JointMap:
    """Where the plant's state lives in MuJoCo's vectors.

    Attributes
    ----------
    qpos_index, qvel_index : (nq,) the qpos and the dof address of each state joint (hinge and
        slide joints: one coordinate each, so the tangent space is the coordinates)
    qpos_eq : (nq,) the equilibrium's qpos of those joints
    sensor_index : (p,) the sensordata address of each output
    gear : (m,) each actuator's gear (u = gear · ctrl)
    """

    def __init__(self, qpos_index: np.ndarray, qvel_index: np.ndarray, qpos_eq: np.ndarray,
                 sensor_index: np.ndarray, gear: np.ndarray) -> None:
        self.qpos_index, self.qvel_index = qpos_index, qvel_index
        self.qpos_eq, self.sensor_index, self.gear = qpos_eq, sensor_index, gear

    @property
    def nq(self) -> int:
        return len(self.qpos_index)

    def data_at(self, model: mujoco.MjModel, x: np.ndarray, u: np.ndarray,
                data: mujoco.MjData) -> None:
        """Write state ``x`` and input ``u`` (physical units) into ``data`` and run
        ``mj_forward``."""
        nq = self.nq
        data.qpos[self.qpos_index] = self.qpos_eq + x[:nq]
        data.qvel[self.qvel_index] = x[nq:]
        data.ctrl[:] = u / self.gear
        mujoco.mj_forward(model, data)


def equilibrium_data(model: mujoco.MjModel, joints: JointMap) -> mujoco.MjData:
    """A fresh ``MjData`` at the equilibrium: qpos*, zero velocity, zero input."""
    data = mujoco.MjData(model)
    mujoco.mj_resetData(model, data)
    data.qvel[:] = 0.0
    joints.data_at(model, np.zeros(2 * joints.nq), np.zeros(model.nu), data)
    return data


def residual(model: mujoco.MjModel, joints: JointMap) -> float:
    """``max |q̈|`` at the equilibrium with zero input: 0 at a true equilibrium."""
    data = equilibrium_data(model, joints)
    return float(np.max(np.abs(data.qacc[joints.qvel_index]), initial=0.0))


def continuous_model(model: mujoco.MjModel, joints: JointMap, *, eps: float = FD_EPS,
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(A, B, C)`` of ``ẋ = A x + B u``, ``y = C x`` by central differences of ``mj_forward``
    (B per physical unit of each input)."""
    data = equilibrium_data(model, joints)
    n, m = 2 * joints.nq, model.nu

    def f(x: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        joints.data_at(model, x, u, data)
        xdot = np.concatenate([data.qvel[joints.qvel_index], data.qacc[joints.qvel_index]])
        return xdot, data.sensordata[joints.sensor_index].copy()

    A, B = np.zeros((n, n)), np.zeros((n, m))
    C = np.zeros((len(joints.sensor_index), n))
    x0, u0 = np.zeros(n), np.zeros(m)
    for i in range(n):
        dx = np.zeros(n)
        dx[i] = eps
        (fp, yp), (fm, ym) = f(x0 + dx, u0), f(x0 - dx, u0)
        A[:, i] = (fp - fm) / (2 * eps)
        C[:, i] = (yp - ym) / (2 * eps)
    for j in range(m):
        du = np.zeros(m)
        du[j] = eps
        (fp, _), (fm, _) = f(x0, du), f(x0, -du)
        B[:, j] = (fp - fm) / (2 * eps)
    return A, B, C


def transition_model(model: mujoco.MjModel, joints: JointMap, k: int, *,
                     eps: float = FD_EPS) -> tuple[np.ndarray, np.ndarray]:
    """``(Φ, Γ)`` over ``k`` physics steps with the input held: ``Φ = A_hᵏ``,
    ``Γ = Σ_{j<k} A_hʲ B_h`` from MuJoCo's one-step ``mjd_transitionFD`` (Γ per physical unit)."""
    data = equilibrium_data(model, joints)
    nx = 2 * model.nv + model.na
    Ah, Bh = np.zeros((nx, nx)), np.zeros((nx, model.nu))
    mujoco.mjd_transitionFD(model, data, eps, True, Ah, Bh, None, None)
    idx = np.concatenate([joints.qvel_index, model.nv + joints.qvel_index])   # tangent order
    Ah, Bh = Ah[np.ix_(idx, idx)], Bh[idx, :] / joints.gear                   # per u, not ctrl
    n = len(idx)
    Phi, Gamma = np.eye(n), np.zeros((n, model.nu))
    for _ in range(k):
        Gamma = Ah @ Gamma + Bh
        Phi = Ah @ Phi
    return Phi, Gamma
