r"""The expected RMS over one episode from its start x₀ and x̂₀, in closed form (no Monte Carlo).

The episode's mean trajectory and covariance are propagated through the closed loop of
:mod:`pendulum_lqg.policies.closed_loop` (the time-varying Kalman filter period by period through
its own gains, then the steady loop in closed form), and averaged over the periods the simulated
RMS takes, in the simulated metrics' own definitions (:mod:`pendulum_lqg.core.metrics`). The
stationary spread (:mod:`pendulum_lqg.policies.theory`) is its limit over a long episode; from a
start away from zero the episode's RMS holds the transient from x₀ and from x̂₀ as well.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.policies.closed_loop import (
    AugmentedLoop,
    LinearEstimator,
    Readouts,
    StationaryProblem,
    augmented_loop,
    per_state,
    readouts,
)


@dataclass(frozen=True)
class EpisodeStart:
    """How an episode starts: ``x₀ ~ N(x0, diag(x0_std²))`` (n,) each, and the initial estimate
    ``x̂₀ = x_hat0`` (n,), or ``x̂₀ = x₀`` itself when ``x_hat0`` is ``None`` (the scenario's
    ``estimate0 = "true"``)."""

    x0: np.ndarray
    x0_std: np.ndarray
    x_hat0: np.ndarray | None = None


@dataclass(frozen=True)
class EpisodeTheory:
    """The expected RMS over one episode from its start (:func:`episode_theory`), in the
    simulated metrics' own definitions (:mod:`pendulum_lqg.core.metrics`).

    Attributes
    ----------
    rms : per state name, ``sqrt`` of the mean over the episode's physics steps (the state at the
        start of each step, periods ``skip … periods−1``) of ``E[x_i²]``
    u_rms : ``sqrt`` of the mean over those periods of ``E[u²]`` (the first input)
    u_rms_by_input : the same per input name (several inputs; empty for one)
    estimate_error_rms : per state name, ``sqrt`` of the mean over those periods' samples of
        ``E[(x̂ − x)²]``
    cost_J : ``E[J]`` over the whole episode (every period: J has no burn-in)
    periods : control periods of the episode; skip : the first periods left out of the RMS
    burn_in : ``skip`` in seconds
    """

    rms: dict[str, float]
    u_rms: float
    estimate_error_rms: dict[str, float]
    cost_J: float
    periods: int
    skip: int
    burn_in: float
    u_rms_by_input: dict[str, float] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready: ``rms.{state}, u_rms, estimate_error_rms.{state}, cost_J, periods, skip,
        burn_in`` (and ``u_rms_by_input.{input}`` with several inputs)."""
        return {"rms": dict(self.rms), "u_rms": self.u_rms,
                **({"u_rms_by_input": dict(self.u_rms_by_input)} if self.u_rms_by_input else {}),
                "estimate_error_rms": dict(self.estimate_error_rms), "cost_J": self.cost_J,
                "periods": self.periods, "skip": self.skip, "burn_in": self.burn_in}


def start_moments(loop: AugmentedLoop, est: LinearEstimator, start: EpisodeStart,
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Mean (n+q,) and covariance (n+q, n+q) of ``s₀ = [x₀; ξ₀]`` with ``ξ₀ = S x̂₀``
    (:meth:`LinearEstimator.start_map`)."""
    x0 = np.asarray(start.x0, dtype=float)
    n = x0.shape[0]
    S = est.start_map(n)
    D0 = np.diag(np.asarray(start.x0_std, dtype=float) ** 2)
    if start.x_hat0 is None:                    # x̂₀ = x₀: ξ₀ moves with x₀
        J = np.vstack([np.eye(n), S])
        return J @ x0, J @ D0 @ J.T
    m0 = np.concatenate([x0, S @ np.asarray(start.x_hat0, dtype=float)])
    P0 = np.zeros((loop.A.shape[0],) * 2)
    P0[:n, :n] = D0
    return m0, P0


def mean_second_moment(A: np.ndarray, Sigma: np.ndarray, G: np.ndarray, a: int, b: int) -> Any:
    r"""The mean over periods ``a … b−1`` of :math:`E[s_k s_k^T] = \Sigma + A^k G A^{kT}`.

    With :math:`X = A X A^T + G` (one Lyapunov equation, A stable) the finite sum is
    :math:`\sum_{j<L} A^j G A^{jT} = X - A^L X A^{LT}`, so the mean is
    :math:`\Sigma + A^a (X - A^L X A^{LT}) A^{aT} / L` with ``L = b − a`` — exact for any
    horizon (the ceiling of 10⁸ periods included) at the cost of two matrix powers.
    """
    from scipy.linalg import solve_discrete_lyapunov

    L = b - a
    X = solve_discrete_lyapunov(A, G)
    AL, Aa = np.linalg.matrix_power(A, L), np.linalg.matrix_power(A, a)
    out = Sigma + Aa @ (X - AL @ X @ AL.T) @ Aa.T / L
    return 0.5 * (out + out.T)


def episode_theory(loop: AugmentedLoop, maps: list[np.ndarray], N: np.ndarray,
                   Sigma: np.ndarray | None, start: EpisodeStart, *, prob: StationaryProblem,
                   periods: int, skip: int = 0,
                   state_names: Sequence[str] = ("p", "theta", "p_dot", "theta_dot"),
                   ) -> EpisodeTheory:
    r"""The expected RMS over an episode of ``periods`` control periods from ``start``.

    The loop :math:`s_{k+1} = \mathcal{A}s_k + \mathcal{B}e_k` carries the mean
    :math:`m_k = \mathcal{A}^k m_0` and the covariance :math:`P_{k+1} = \mathcal{A}P_k
    \mathcal{A}^T + \mathcal{B}N\mathcal{B}^T`; with the stationary Σ,
    :math:`E[s_k s_k^T] = m_k m_k^T + P_k = \Sigma + \mathcal{A}^k (P_0 - \Sigma + m_0 m_0^T)
    \mathcal{A}^{kT}`. Its mean over the periods ``skip … periods−1``
    (:func:`mean_second_moment`) goes through the read-outs of the stationary theory
    (:func:`readouts`): x at the start of every physics step, u and ``x̂ − x`` at every sample —
    the samples the simulated ``rms_*`` take. ``Sigma`` ``None`` (an unstable loop): every value
    is ``inf``. ``cost_J`` is ``E[J]`` over all the periods.
    """
    skip = min(max(skip, 0), periods - 1)
    period = prob.k * prob.h
    burn = skip * period
    if Sigma is None:
        inf, m = float("inf"), prob.Gamma.shape[1]
        return EpisodeTheory(rms=dict.fromkeys(state_names, inf), u_rms=inf,
                             estimate_error_rms=dict.fromkeys(state_names, inf), cost_J=inf,
                             periods=periods, skip=skip, burn_in=burn,
                             u_rms_by_input=dict.fromkeys(by_input(np.eye(m), prob), inf))
    m, P = start_moments(loop, prob.estimator, start)
    sums: dict[int, list[Any]] = {0: [0.0] * 4, skip: [0.0] * 4}   # x, u, e, xu from 0, skip
    sched = prob.estimator.schedule[:periods]       # the periods of a varying gain, one by one
    for a, est in enumerate(sched):
        la = augmented_loop(loop.Phi, loop.Gamma, prob.C, prob.K, est)
        r = readouts(la, maps, N, P + np.outer(m, m))
        for b in {0, skip} if a >= skip else {0}:
            sums[b] = [s + v for s, v in zip(sums[b], _moments(r), strict=True)]
        m, P = la.A @ m, la.A @ P @ la.A.T + la.B @ N @ la.B.T
    rest, G = periods - len(sched), P - Sigma + np.outer(m, m)
    for b in {0, skip} if rest > 0 else ():          # then the steady loop, in closed form
        a = max(b - len(sched), 0)
        r = readouts(loop, maps, N, mean_second_moment(loop.A, Sigma, G, a, rest))
        sums[b] = [s + v * (rest - a) for s, v in zip(sums[b], _moments(r), strict=True)]
    whole, window = ([v / (periods - b) for v in sums[b]] for b in (0, skip))
    cost = periods * period * prob.cost_rate(Readouts(z=whole[1], x_steps=whole[0], u=whole[1],
                                                      error=whole[2], xu_steps=whole[3]))
    if not (all(np.all(np.isfinite(v)) for v in window) and math.isfinite(cost)):
        raise ConfigError("x0: the episode's second moments overflow; the theory needs a "
                          "smaller initial state or noise")
    return EpisodeTheory(rms=per_state(window[0], state_names, True),
                         u_rms=float(np.sqrt(max(window[1][0, 0], 0.0))),
                         estimate_error_rms=per_state(window[2], state_names, True),
                         cost_J=cost, periods=periods, skip=skip, burn_in=burn,
                         u_rms_by_input=by_input(window[1], prob))


def _moments(r: Readouts) -> tuple[np.ndarray, ...]:
    """The second moments an episode sums over its periods: x over the physics steps, u, the
    estimation error and ``x uᵀ`` over the physics steps (the cost's cross term)."""
    return r.x_steps, r.u, r.error, r.xu_steps


def by_input(cov_u: np.ndarray, prob: StationaryProblem) -> dict[str, float]:
    """The RMS (or std) of each input by name from its second moment ``cov_u`` (m, m); empty for
    one input, whose value is the summaries' ``u_rms`` / ``u_std`` alone."""
    names = prob.input_names()
    return per_state(cov_u, names, True) if len(names) > 1 else {}


def episode_start(x0: Any, x0_std: Any, estimate0: str, policy: Any) -> EpisodeStart:
    """The :class:`EpisodeStart` of a scenario's ``x0``, ``x0_std`` and ``estimate0`` for
    ``policy`` (``"zero"``: its own ``x_hat0``, as the runner's ``policy.reset(n)``)."""
    x0 = np.asarray(x0, dtype=float)
    if estimate0 == "true":
        return EpisodeStart(x0=x0, x0_std=np.asarray(x0_std, dtype=float))
    x_hat0 = np.asarray(getattr(policy, "x_hat0", np.zeros_like(x0)), dtype=float)
    return EpisodeStart(x0=x0, x0_std=np.asarray(x0_std, dtype=float), x_hat0=x_hat0)
