r"""The exact gap: the stationary cost of any linear controller on the plant's linearisation.

A linear controller file (:mod:`pendulum_lqg.scoreboard.linear`) maps what it has seen,
``z_k = [y_k, u_{k−1}/s]``, to the force through a state: ``v_k = C_c ξ_k + D_c z_k + c``,
``ξ_{k+1} = A_c ξ_k + B_c z_k``, ``u_k = s·v_k`` (the ``state_space`` form as written; the
``history`` form as a shift register of its last ``frames − 1`` inputs, with
``c = bias − w·mean/std``). With the compensator state ``ζ = [ξ; u_{k−1}]`` this is an estimator
and a gain of :mod:`pendulum_lqg.policies.closed_loop` exactly: the "estimate" ``x̂`` holds the
force in its first entry and zeros elsewhere, ``K = −e₁ᵀ``, so ``u = −K x̂``::

    x̂ = H ζ + D_y y,  H = [[s·C_c, D_u], 0], D_y = [[s·D_y], 0]
    ζ⁺ = F ζ + G_y y + G_u u,  F = [[A_c, B_u/s], [0, 0]], G_y = [[B_y], [0]], G_u = [[0], [1]]

(``D_c = [D_y, D_u]``, ``B_c = [B_y, B_u]``; ``ζ₀ = 0``: ``ξ₀ = 0`` and no force before the first
period, the file's rule). The plant + compensator + held force loop then takes the one rule the
built-in policies' theory takes (:func:`~pendulum_lqg.policies.theory.linear_problem`,
:func:`~pendulum_lqg.policies.theory.stationary`): one discrete Lyapunov equation, the cost at the
physics step by the rectangle rule over the held period (``J = ∫ xᵀQx + R u² dt`` as
:func:`~pendulum_lqg.core.rules.period_integrals` sums it), the suite's noise. The loop is
unstable where its spectral radius is ≥ 1 (``J = ∞``).

The constant ``c`` (a history controller's bias and input means) moves the stationary mean:
``m = (I − 𝒜)⁻¹ g·s·c`` with ``g = [Γ; G_u]``; its cost ``E[z]ᵀ W E[z]`` over the period's physics
steps adds to the covariance's (:func:`_mean_cost_rate`). Over an episode from ``x₀`` the mean
``M_{k+1} = 𝒜 M_k + g·s·c`` is stepped period by period and the covariance is the episode
theory's (:func:`~pendulum_lqg.policies.episode_theory.episode_theory`).

``J*`` is the same theory's stationary J of the suite's reference (``dlqr+kalman`` designed on the
plant played), so ``gap = J/J* − 1`` is the exact price of the controller on the linearised
plant, free of Monte Carlo noise; ``episode_gap = E[J]/E[J*] − 1`` is the same over one episode of
the suite from its ``x₀`` and ``x̂₀``, the quantity whose Monte Carlo estimate is ``score``'s gap
(with the limits off: saturation and failures are outside the theory). A suite that randomises
its plant, delays or loses samples or lags its actuator has no single linear loop: refused, one
line naming the suite.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from pendulum_lqg.errors import ConfigError, PendulumLQGError

__all__ = ["ExactCost", "compensator", "exact_builtin", "exact_linear", "exact_reference"]


def _ratio_gap(J: float, J_opt: float, stable: bool) -> float:
    """``J/J* − 1``: ``inf`` for an unstable loop, ``nan`` when ``J* = 0``."""
    if not stable:
        return math.inf
    return J / J_opt - 1.0 if J_opt > 0 else math.nan


@dataclass(frozen=True)
class ExactCost:
    """The exact stationary figures of one controller on one suite (module docstring)."""

    suite: str
    spectral_radius: float
    stable: bool
    J: float                   # stationary cost_rate · duration (inf when unstable)
    J_opt: float               # the reference's
    episode_J: float           # E[J] over one episode from x₀ (inf when unstable)
    episode_J_opt: float

    @property
    def gap(self) -> float:
        """``J/J* − 1`` (``inf`` when the loop is unstable, ``nan`` where the reference's J is 0:
        a noise-free suite's stationary cost, where no ratio is defined)."""
        return _ratio_gap(self.J, self.J_opt, self.stable)

    @property
    def episode_gap(self) -> float:
        return _ratio_gap(self.episode_J, self.episode_J_opt, self.stable)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (``None`` for ∞)."""
        def num(x: float) -> float | None:
            return float(x) if math.isfinite(x) else None

        return {"suite": self.suite, "spectral_radius": self.spectral_radius,
                "stable": self.stable, "J": num(self.J), "J_opt": self.J_opt,
                "gap": num(self.gap), "episode_J": num(self.episode_J),
                "episode_J_opt": self.episode_J_opt, "episode_gap": num(self.episode_gap)}


def _matrices(doc: dict[str, Any]) -> tuple[Any, ...]:
    """``(A_c, B_c, C_c (r,), D_c (q,), c, s)`` of a checked controller document (``q``: the
    inputs ``z = [y, u_prev/s]`` per period, 3 on the cart-pole)."""
    from pendulum_lqg.boundary.schemas import linear_inputs

    s, q = float(doc["action_scale"]), linear_inputs(doc)
    if doc["form"] == "state_space":
        m = doc["state_space"]
        A, B = np.asarray(m["A"], dtype=float), np.asarray(m["B"], dtype=float)
        C, D = np.asarray(m["C"], dtype=float)[0], np.asarray(m["D"], dtype=float)[0]
        return A.reshape(len(A), -1), B.reshape(len(A), q), C, D, np.float64(0.0), np.float64(s)
    h = doc["history"]
    frames = int(h["frames"])
    w = np.asarray(h["weights"], dtype=float) / np.asarray(h["std"], dtype=float)
    c = float(h["bias"]) - float(w @ np.asarray(h["mean"], dtype=float))
    r = q * (frames - 1)                   # ξ: the last frames − 1 inputs z, oldest first
    A, B = np.zeros((r, r)), np.zeros((r, q))
    if r:
        A[:-q, q:] = np.eye(r - q)         # shift the stack by one frame …
        B[-q:, :] = np.eye(q)              # … and append this period's z
    return A, B, w[:r], w[r:], np.float64(c), np.float64(s)


def compensator(doc: dict[str, Any], n: int) -> tuple[np.ndarray, Any, float]:
    """``(K, estimator, d)``: the controller file ``doc`` as a gain ``K`` (1, n) and a
    :class:`~pendulum_lqg.policies.closed_loop.LinearEstimator` of ``n`` plant states, and the
    constant force ``d = s·c`` [N] (module docstring)."""
    from pendulum_lqg.policies.closed_loop import LinearEstimator

    A, B, C, D, c, s = _matrices(doc)
    r, p = A.shape[0], D.shape[0] - 1
    q = r + 1
    H, D_y = np.zeros((n, q)), np.zeros((n, p))
    H[0, :r], H[0, r], D_y[0] = s * C, D[p], s * D[:p]
    F, G_y, G_u = np.zeros((q, q)), np.zeros((q, p)), np.zeros((q, 1))
    F[:r, :r], F[:r, r], G_y[:r] = A, B[:, p] / s, B[:, :p]
    G_u[r, 0] = 1.0
    K = np.zeros((1, n))
    K[0, 0] = -1.0
    est = LinearEstimator(F, G_y, G_u, H, D_y, S=np.zeros((q, n)),
                          note="a linear controller file: x̂ holds its force, not an estimate")
    return K, est, float(s * c)


def _suite_problem(suite: Any) -> tuple[Any, Any]:
    """``(plant played, scenario)`` of a suite with one linear loop, or one line naming it."""
    scenario = suite.config.scenario
    if not scenario.randomize.is_empty():
        raise ConfigError(f"suite {suite.name!r}: it randomises its plant per episode; the exact "
                          "gap is for one fixed plant (e.g. lecture, noisy)")
    for name in ("measurement_delay", "actuator_delay", "dropout", "actuator_tau"):
        if getattr(scenario, name):
            raise ConfigError(f"suite {suite.name!r}: it sets {name}; the exact gap covers the "
                              "plain sampled loop (e.g. lecture, noisy)")
    if suite.observes_state:
        raise ConfigError(f"suite {suite.name!r} gives the true state; a linear controller file "
                          "takes y = [p, θ]")
    return suite.plants()[0], scenario


def _theory(plant: Any, scenario: Any, K: np.ndarray, est: Any, name: str, d: float) -> Any:
    """``(ClosedLoopTheory, stationary J, episode E[J])`` of ``K``, ``est`` and the constant force
    ``d`` on ``plant`` under ``scenario``."""
    from pendulum_lqg.policies.closed_loop import augmented_loop, period_samples
    from pendulum_lqg.policies.episode_theory import EpisodeStart
    from pendulum_lqg.policies.theory import linear_problem, stationary

    prob, lims = linear_problem(plant, scenario, K, est)
    period = prob.k * prob.h
    duration = scenario.n_periods * period
    x0, x0_std = np.asarray(scenario.x0, dtype=float), np.asarray(scenario.x0_std, dtype=float)
    n = x0.shape[0]
    # the covariance from x₀'s spread; the means (x₀, x̂₀, the constant force) stepped below
    start = EpisodeStart(x0=np.zeros(n), x0_std=x0_std, x_hat0=np.zeros(n))
    th = stationary(prob, name=name, duration=duration, limits=lims, start=start,
                    burn_in=scenario.burn_in)
    if not th.stable:
        return th, math.inf, math.inf
    maps, Phi_T, Gamma_T = period_samples(prob.kind, prob.Phi, prob.Gamma, prob.k)
    loop = augmented_loop(Phi_T, Gamma_T, prob.C, prob.K, est)
    g = np.concatenate([Gamma_T[:, 0], est.G_u[:, 0] if not est.full_state else np.zeros(0)])
    ns = loop.A.shape[0]
    J = th.cost_J
    if d:
        m = np.linalg.solve(np.eye(ns) - loop.A, g * d)
        J += _mean_cost_rate(prob, loop, maps, m, d) * duration
    # the episode: E[s sᵀ] = P_k + M_k M_kᵀ, M_0 = [x₀; S x̂₀], M_{k+1} = 𝒜 M_k + g d
    x_hat0 = x0 if scenario.estimate0 == "true" else np.zeros(n)
    M = np.concatenate([x0, est.start_map(n) @ x_hat0])
    rates = 0.0
    for _ in range(scenario.n_periods):
        rates += _mean_cost_rate(prob, loop, maps, M, d)
        M = loop.A @ M + g * d
    assert th.episode is not None              # asked for by the start above
    return th, J, th.episode.cost_J + rates * period


def _mean_cost_rate(prob: Any, loop: Any, maps: list[np.ndarray], m: np.ndarray,
                    d: float) -> float:
    """The cost rate of the mean ``m`` of the loop's state (and the constant force ``d``) over a
    period: the rectangle rule of :meth:`StationaryProblem.cost_rate` on ``E[z] E[z]ᵀ``."""
    from pendulum_lqg.policies.closed_loop import Readouts

    n = maps[0].shape[0]
    z = np.concatenate([m[:n], loop.C_u @ m + d])
    zz = np.outer(z, z)
    x_steps = np.sum([T @ zz @ T.T for T in maps], axis=0) / len(maps)
    xu = np.sum([T @ zz[:, n:] for T in maps], axis=0) / len(maps)
    return prob.cost_rate(Readouts(z=zz, x_steps=x_steps, u=zz[n:, n:],
                                   error=np.zeros((n, n)), xu_steps=xu))


def exact_reference(suite: Any) -> tuple[float, float]:
    """``(J*, E[J*])``: the stationary J and the episode's expected J of the suite's reference
    (designed on the plant played) on the plant's linearisation."""
    plant, scenario = _suite_problem(suite)
    th = _builtin(suite, suite.reference, plant, scenario)
    return th.cost_J, th.episode.cost_J


def _builtin(suite: Any, policy: str, plant: Any, scenario: Any) -> Any:
    from pendulum_lqg.policies.loading import build_policy
    from pendulum_lqg.policies.theory import policy_theory

    built = build_policy(policy, plant=suite.plants()[1], scenario=scenario)
    return policy_theory(plant, scenario, built)


def exact_linear(suite: Any, doc: dict[str, Any], *,
                 reference: tuple[float, float] | None = None) -> ExactCost:
    """The :class:`ExactCost` of the controller document ``doc`` on ``suite`` (``reference``:
    :func:`exact_reference`'s answer, computed when not given)."""
    plant, scenario = _suite_problem(suite)
    K, est, d = compensator(doc, len(scenario.x0))
    th, J, eJ = _theory(plant, scenario, K, est, f"linear controller on {suite.name}", d)
    J_opt, eJ_opt = reference or exact_reference(suite)
    return ExactCost(suite=suite.name, spectral_radius=th.spectral_radius, stable=th.stable,
                     J=J, J_opt=J_opt, episode_J=eJ, episode_J_opt=eJ_opt)


def exact_builtin(suite: Any, policy: str, *,
                  reference: tuple[float, float] | None = None) -> ExactCost:
    """The :class:`ExactCost` of a built-in linear ``policy`` designed on the suite's design
    plant (the theory's estimators; plug-ins and kalman-delay refused, one line)."""
    plant, scenario = _suite_problem(suite)
    th = _builtin(suite, policy, plant, scenario)
    J_opt, eJ_opt = reference or exact_reference(suite)
    return ExactCost(suite=suite.name, spectral_radius=th.spectral_radius, stable=th.stable,
                     J=th.cost_J, J_opt=J_opt, episode_J=th.episode.cost_J, episode_J_opt=eJ_opt)


def exact_entry(suite: Any, *, doc: dict[str, Any] | None = None, policy: str | None = None,
                ) -> dict[str, Any]:
    """The score file's ``exact`` entry of a suite for a controller document ``doc`` or a built-in
    ``policy``: :meth:`ExactCost.to_dict` without the suite, or ``{"reason": …}`` where the
    theory has no single linear loop for it (one line)."""
    try:
        res = exact_linear(suite, doc) if doc is not None else exact_builtin(suite, str(policy))
    except PendulumLQGError as exc:
        return {"reason": str(exc)}
    out = res.to_dict()
    del out["suite"]
    return out
