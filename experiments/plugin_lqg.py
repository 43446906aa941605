"""The LQG baseline rebuilt as a plugin from :class:`pendulum_lqg.PolicyContext` alone.

A template for your own model-based policy, and the proof that a plugin is scored exactly like a
built-in: discrete LQR plus the steady-state Kalman filter in its current-estimate form, designed
with scipy only (no pendulum_lqg design code)::

    uv run pendulum-lqg run --policy experiments/plugin_lqg.py:make --episodes 200

Design (docs/theory.md §2–3): the plant is ``x[n+1] = Φ x[n] + Γ u[n] + w[n]``, ``y[n] = C x[n] + v[n]``
with ``E{wwᵀ} = W·T`` (the context's state-form density over one period) and ``E{vvᵀ} = V``.

* controller — DARE for ``(Φ, Γ, Q·T, R·T)``, ``K = (R·T + ΓᵀPΓ)⁻¹ ΓᵀPΦ`` (the rectangle rule
  for the cost ``∫ xᵀQx + uᵀRu dt``; the built-in ``dlqr`` uses the exact sampled weights, which
  differ by O(T));
* estimator — DARE for ``(Φᵀ, Cᵀ, W·T, V)`` gives the a-priori covariance ``M``; filter gain
  ``L = M Cᵀ (C M Cᵀ + V)⁻¹``; each sample ``x̂ = x̄ + L (y − C x̄)``, ``u = sat(−K x̂)``,
  ``x̄ ← Φ x̂ + Γ u`` with the saturated force (the benchmark saturates at ``u_max`` too); a
  lost sample (``--dropout``, a measurement delay's first samples: nan) keeps ``x̂ = x̄``.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import solve_discrete_are


def mv(M: np.ndarray, X: np.ndarray) -> np.ndarray:
    """``X @ M.T`` row by row: (n, j) rows of ``M`` (i, j) times each row of ``X``."""
    return np.einsum("ij,nj->ni", M, X)


class DiscreteLQG:
    """``u = sat(−K x̂)`` with a current-form steady-state Kalman filter, batched."""

    def __init__(self, K: np.ndarray, L: np.ndarray, Phi: np.ndarray, Gamma: np.ndarray,
                 C: np.ndarray, u_max: float) -> None:
        self.K, self.L, self.Phi, self.Gamma, self.C = K, L, Phi, Gamma, C
        self.u_max = u_max
        self.info = {"K": K, "L": L}

    def reset(self, n: int) -> None:
        self.x_bar = np.zeros((n, 4))          # a-priori estimate of the coming sample
        self.x_hat = np.zeros((n, 4))

    def act(self, y: np.ndarray) -> np.ndarray:
        # Row-wise products (einsum, no BLAS): a BLAS matrix product may round a row differently
        # with another number of rows, and then one episode's numbers would depend on its batch.
        innovation = y - mv(self.C, self.x_bar)
        innovation[~np.isfinite(y).all(axis=1)] = 0.0     # a lost sample (nan): predict only
        self.x_hat = self.x_bar + mv(self.L, innovation)
        u = np.clip(-mv(self.K, self.x_hat), -self.u_max, self.u_max)
        self.x_bar = mv(self.Phi, self.x_hat) + mv(self.Gamma, u)
        return u[:, 0]

    def select(self, rows: np.ndarray) -> None:
        self.x_bar, self.x_hat = self.x_bar[rows], self.x_hat[rows]


def make(ctx) -> DiscreteLQG:
    """The plugin factory: DLQR + steady-state Kalman filter from the context's matrices."""
    T = ctx.dt
    P = solve_discrete_are(ctx.Phi, ctx.Gamma, ctx.Q * T, ctx.R * T)
    K = np.linalg.solve(ctx.R * T + ctx.Gamma.T @ P @ ctx.Gamma, ctx.Gamma.T @ P @ ctx.Phi)
    M = solve_discrete_are(ctx.Phi.T, ctx.C.T, ctx.W * T, ctx.V)
    L = M @ ctx.C.T @ np.linalg.inv(ctx.C @ M @ ctx.C.T + ctx.V)
    return DiscreteLQG(K, L, ctx.Phi, ctx.Gamma, ctx.C, ctx.u_max)
