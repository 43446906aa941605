"""A complete policy plugin: LQR state feedback on α-β tracker estimates.

Benchmark it against the built-in LQG policies on the very same seeded episodes::

    uv run pendulum-lqg run --policy experiments/plugin_example.py:make --episodes 100
    uv run pendulum-lqg bench plugins          # experiments/plugins.toml: this plugin beside LQG

How a plugin works (docs/plugins.md): ``make`` is a *factory*. The benchmark
calls it once per batch of episodes with a :class:`pendulum_lqg.PolicyContext` — the nominal
plant's linear models (``A, B, C``, ``Phi, Gamma`` at the control period ``dt``), the noise
(``W``, ``V``), the actuator limit ``u_max`` and the cost weights ``Q, R`` — and gets back an object
with two methods, both vectorised over the ``n`` episodes of the batch:

* ``reset(n)`` — n episodes start (the estimate starts at zero, as the built-ins' does);
* ``act(y) -> u`` — ``y`` is an (n, 2) array of the noisy measurements ``[p, θ]`` [m, rad] taken at
  the start of the control period, ``u`` an (n,) array of forces [N] held over the period (the
  benchmark saturates them to ±u_max).

Optional: ``select(rows)`` (keep only these rows when episodes end; without it the benchmark keeps
feeding the whole batch), ``x_hat`` (the (n, 4) estimate, so the estimation-error columns are
filled), ``needs_state = True`` (``act`` then receives the true state (n, 4) instead of ``y``).

The design here is deliberately *not* a Kalman filter, to show what a model-free estimator costs:

* estimator — one α-β tracker per measured channel (p and θ), the classic constant-velocity
  filter of radar tracking: predict ``x̄ = x̂ + T v̂``, then correct with the residual
  ``r = y − x̄``: ``x̂ = x̄ + α r``, ``v̂ = v̂ + (β / T) r``. α and β come from Kalata's tracking
  index ``λ = σ_a T² / σ_v`` (the steady-state Kalman gains of a white-acceleration model), so the
  only tuning knob is ``sigma_a``, the acceleration noise each channel is assumed to have.
* controller — continuous LQR ``u = −K x̂`` for the benchmark's own cost weights ``Q, R``, from
  ``A, B`` of the context (scipy's CARE solver; no pendulum_lqg design code is used).
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import solve_continuous_are


def alpha_beta_gains(tracking_index: float) -> tuple[float, float]:
    """Steady-state α, β of the α-β filter for Kalata's tracking index ``λ`` (Kalata 1984)."""
    lam = float(tracking_index)
    r = (4.0 + lam - np.sqrt(8.0 * lam + lam * lam)) / 4.0
    return 1.0 - r * r, 2.0 * (2.0 - (1.0 - r * r)) - 4.0 * r


class AlphaBetaLQR:
    """LQR on α-β estimates of ``[p, θ, ṗ, θ̇]``, vectorised over a batch of episodes.

    Parameters
    ----------
    K : (1, 4) state-feedback gain, u = −K x̂
    dt : control period [s]
    alpha, beta : (2,) α-β gains of the p and θ channels
    """

    def __init__(self, K: np.ndarray, dt: float, alpha: np.ndarray, beta: np.ndarray) -> None:
        self.K, self.dt = np.asarray(K, dtype=float), float(dt)
        self.alpha, self.beta = np.asarray(alpha, dtype=float), np.asarray(beta, dtype=float)
        self.info = {"K": self.K, "alpha": self.alpha, "beta": self.beta}
        self.x_hat = np.zeros((0, 4))

    def reset(self, n: int) -> None:
        self.x_hat = np.zeros((n, 4))          # [p, θ, ṗ, θ̇], the estimate starts at zero
        self._pos = np.zeros((n, 2))           # tracker position estimates after the last sample
        self._vel = np.zeros((n, 2))
        self._started = False

    def act(self, y: np.ndarray) -> np.ndarray:
        if self._started:
            predicted = self._pos + self.dt * self._vel
        else:                                   # first sample: nothing to predict from yet
            predicted = self._pos
            self._started = True
        residual = y - predicted
        self._pos = predicted + self.alpha * residual
        self._vel = self._vel + (self.beta / self.dt) * residual
        self.x_hat = np.hstack([self._pos, self._vel])
        return -(self.x_hat @ self.K.T)[:, 0]

    def select(self, rows: np.ndarray) -> None:
        self._pos, self._vel, self.x_hat = self._pos[rows], self._vel[rows], self.x_hat[rows]


def make(ctx, sigma_a: tuple[float, float] = (10.0, 30.0)) -> AlphaBetaLQR:
    """The plugin factory: LQR for the context's cost, α-β trackers for its noise.

    ``sigma_a`` is the assumed acceleration noise of the (p, θ) channels [m/s², rad/s²]: the pole
    accelerates far more than the cart, so its tracker must follow faster.
    """
    P = solve_continuous_are(ctx.A, ctx.B, ctx.Q, ctx.R)
    K = np.linalg.solve(ctx.R, ctx.B.T @ P)
    sigma_v = np.sqrt(np.diag(ctx.V))                       # measurement noise std [m, rad]
    gains = [alpha_beta_gains(s * ctx.dt**2 / sv) for s, sv in zip(sigma_a, sigma_v, strict=True)]
    alpha, beta = (np.array(g) for g in zip(*gains, strict=True))
    return AlphaBetaLQR(K, ctx.dt, alpha, beta)
