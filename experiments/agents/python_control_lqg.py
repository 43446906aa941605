"""A Gymnasium agent written outside the package: its own LQR and Kalman filter (python-control).

A template for scoring your own agent on the suites::

    uv run pendulum-lqg score --agent experiments/agents/python_control_lqg.py:make --suite lecture

It uses nothing of pendulum_lqg's design code: the model comes from MuJoCo itself (the env's MJCF),
linearised by MuJoCo's finite differences at the upright, and the noise from the env's documented
keywords. Design:

* one physics step ``x⁺ = A x + B u`` from ``mujoco.mjd_transitionFD`` (state ``[p, θ, ṗ, θ̇]`` =
  ``[qpos; qvel]`` of the slider and the hinge); one control period of k steps with ``u`` held:
  ``Φ = Aᵏ``, ``Γ = Σ_{j<k} Aʲ B`` — exactly how the simulator holds the force;
* controller — ``control.dlqr(Φ, Γ, Q·T, R·T)`` (the rectangle rule for ``∫ xᵀQx + R u² dt``);
* estimator — ``control.dlqe(Φ, I, C, W·T, V)`` gives the a-priori covariance ``M``; the filter
  (current-estimate) gain ``L = M Cᵀ (C M Cᵀ + V)⁻¹``; at each sample ``x̂ = x̄ + L (y − C x̄)``,
  ``u = sat(−K x̂)``, ``x̄ ← Φ x̂ + Γ u`` with the saturated force. A lost sample (nan) keeps the
  prediction ``x̂ = x̄``.
"""

from __future__ import annotations

import control
import mujoco
import numpy as np


class PythonControlLQG:
    """``u = sat(−K x̂)`` from a steady-state Kalman filter, one env."""

    def __init__(self, K: np.ndarray, L: np.ndarray, Phi: np.ndarray, Gamma: np.ndarray,
                 C: np.ndarray, u_max: float) -> None:
        self.K, self.L, self.Phi, self.Gamma, self.C, self.u_max = K, L, Phi, Gamma, C, u_max
        self.reset()

    def reset(self) -> None:
        self.x_bar = np.zeros(4)

    def act(self, y: np.ndarray) -> np.ndarray:
        y = np.asarray(y, dtype=float)
        x_hat = self.x_bar if not np.all(np.isfinite(y)) else \
            self.x_bar + self.L @ (y - self.C @ self.x_bar)
        u = np.clip(-(self.K @ x_hat), -self.u_max, self.u_max)
        self.x_bar = self.Phi @ x_hat + self.Gamma @ u
        return u


def period_model(model: mujoco.MjModel, k: int) -> tuple[np.ndarray, np.ndarray]:
    """``(Φ, Γ)`` of one control period of ``k`` physics steps at the upright (see the docstring)."""
    data = mujoco.MjData(model)
    mujoco.mj_resetData(model, data)
    mujoco.mj_forward(model, data)
    n = 2 * model.nv
    A, B = np.zeros((n, n)), np.zeros((n, model.nu))
    mujoco.mjd_transitionFD(model, data, 1e-6, True, A, B, None, None)
    order = [model.joint("slider").dofadr[0], model.joint("hinge").dofadr[0]]
    idx = order + [model.nv + i for i in order]              # [p, θ, ṗ, θ̇]
    A, B = A[np.ix_(idx, idx)], B[idx]
    Phi, Gamma, power = np.eye(n), np.zeros_like(B), np.eye(n)
    for _ in range(k):
        Gamma += power @ B
        power = A @ power
    Phi = power
    return Phi, Gamma


def make(env) -> PythonControlLQG:
    """The agent factory ``f(env)``: designs from the env's model, period, weights and noise."""
    from pendulum_lqg.errors import NotApplicable

    base = env.unwrapped
    if base.observation_mode != "measurement":
        raise NotApplicable("this agent estimates the state from y = [p, θ]; the env gives x")
    model, sc = base.plant.model, base.scenario
    k = round(sc.control_period / model.opt.timestep)
    T = k * model.opt.timestep
    Phi, Gamma = period_model(model, k)
    C = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0]])
    Q, R = np.diag(sc.cost_Q), np.array([[sc.cost_R]])
    K, _, _ = control.dlqr(Phi, Gamma, Q * T, R * T)
    W, V = sc.noise.W, sc.noise.V         # density [units²·s] of x ← x + δx; per-sample covariance
    _, M, _ = control.dlqe(Phi, np.eye(4), C, W * T, V)
    L = M @ C.T @ np.linalg.inv(C @ M @ C.T + V)
    _, u_max = model.actuator("force").ctrlrange
    return PythonControlLQG(np.asarray(K), L, Phi, Gamma, C, float(u_max))
