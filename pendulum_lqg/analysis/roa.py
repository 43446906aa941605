"""Region of attraction of a policy on the MuJoCo cart-pole, measured through the one closed loop.

Two measurements, both through :func:`pendulum_lqg.core.runner.run_episodes` (no second simulation loop):

* :func:`bisect_theta` — the largest initial pole angle ``|θ₀|`` (cart at rest at the origin, no
  initial rate) from which at least ``level`` (default 95 %) of a batch of noisy episodes survive
  the episode. Every bisection point reuses the same episode numbers, so the noise is common to all
  points (common random numbers) and the success fraction varies with θ₀ only. Bisection assumes the
  success fraction falls monotonically with |θ₀|; the evaluated points are returned so this can be
  checked.
* :func:`success_map` — a noise-free map of success over a grid of ``(θ₀, θ̇₀)``, one batch of
  episodes with explicit initial states. "Recovered" there means the episode survived *and* the
  pole settled (``settling_time`` ≤ ``settle_fraction × duration``).

Success is the scenario's own failure rule (``|θ| ≤ theta_max``, cart inside the track, no
divergence); a region-of-attraction study should raise ``theta_max`` above the default 0.5 rad.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pendulum_lqg.core.metrics import wilson_interval
from pendulum_lqg.core.protocol import PolicyProtocol
from pendulum_lqg.core.runner import run_episodes
from pendulum_lqg.core.scenario import Scenario
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.model.plant import Plant


@dataclass(frozen=True)
class Evaluation:
    """One Monte Carlo batch at initial angle ``theta0``: successes out of ``n``."""

    theta0: float
    successes: int
    n: int

    @property
    def rate(self) -> float:
        return self.successes / self.n

    def to_dict(self) -> dict[str, Any]:
        lo, hi = wilson_interval(self.successes, self.n)
        return {"theta0": self.theta0, "successes": self.successes, "episodes": self.n,
                "success_rate": self.rate, "ci95_low": lo, "ci95_high": hi}


@dataclass(frozen=True)
class BisectionResult:
    """Largest ``θ₀`` found with success ≥ ``level`` and every batch evaluated on the way.

    ``theta_star`` is the lower end of the final bracket ``[theta_star, theta_fail]``;
    ``censored`` is true when even ``theta_hi`` passed (the ROA reaches at least that far) and
    ``theta_star`` is 0 with ``theta_fail`` = the smallest angle tried when nothing passed.
    """

    theta_star: float
    theta_fail: float
    censored: bool
    evaluations: list[Evaluation] = field(default_factory=list)


def _x0(theta: float, theta_dot: float = 0.0) -> tuple[float, float, float, float]:
    return (0.0, float(theta), 0.0, float(theta_dot))


def success_count(plant: Plant, scenario: Scenario, policy: PolicyProtocol, theta0: float, *, seed: int,
                  episodes: int, nthread: int | None = None) -> Evaluation:
    """Run episodes ``0 … episodes−1`` from ``x₀ = [0, θ₀, 0, 0]`` and count the successes."""
    sc = scenario.replace(x0=_x0(theta0), x0_std=(0.0, 0.0, 0.0, 0.0))
    res = run_episodes(plant, sc, policy, seed=seed, episodes=range(episodes), nthread=nthread)
    return Evaluation(theta0=float(theta0), successes=sum(bool(r["success"]) for r in res.rows),
                      n=episodes)


def bisect_theta(plant: Plant, scenario: Scenario, policy: PolicyProtocol, *, seed: int, episodes: int,
                 level: float = 0.95, theta_lo: float = 0.05, theta_hi: float = 1.2,
                 tolerance: float = 0.01, nthread: int | None = None) -> BisectionResult:
    """Bisection for the largest ``θ₀`` whose batch success fraction is ≥ ``level``.

    Parameters
    ----------
    plant, scenario, policy : the closed loop (the scenario's noise, initial estimate and failure
        rule apply; its ``x0`` is replaced by ``[0, θ₀, 0, 0]``)
    seed, episodes : the batch at every point is episodes ``0 … episodes−1`` of ``seed``
    level : required success fraction; theta_lo, theta_hi : initial bracket [rad]
    tolerance : stop when the bracket is narrower than this [rad]
    """
    if not 0 < level <= 1:
        raise ConfigError(f"level: expected a fraction in (0, 1], got {level!r}")
    if not 0 < theta_lo < theta_hi or tolerance <= 0:
        raise ConfigError(f"theta_lo, theta_hi, tolerance: expected 0 < theta_lo < theta_hi and "
                          f"tolerance > 0, got {theta_lo}, {theta_hi}, {tolerance}")
    evals: list[Evaluation] = []

    def passes(theta: float) -> bool:
        ev = success_count(plant, scenario, policy, theta, seed=seed, episodes=episodes,
                           nthread=nthread)
        evals.append(ev)
        return ev.rate >= level

    if passes(theta_hi):
        return BisectionResult(theta_hi, float("inf"), True, evals)
    if not passes(theta_lo):
        return BisectionResult(0.0, theta_lo, True, evals)
    lo, hi = theta_lo, theta_hi
    while hi - lo > tolerance:
        mid = 0.5 * (lo + hi)
        if passes(mid):
            lo = mid
        else:
            hi = mid
    return BisectionResult(lo, hi, False, evals)


def success_map(plant: Plant, scenario: Scenario, policy: PolicyProtocol, thetas: np.ndarray,
                theta_dots: np.ndarray, *, seed: int, settle_fraction: float = 0.8,
                nthread: int | None = None) -> dict[str, np.ndarray]:
    """Success over the grid ``thetas × theta_dots`` of initial ``(θ₀, θ̇₀)`` (cart at rest at 0).

    Returns
    -------
    dict of (len(thetas), len(theta_dots)) arrays: ``survived`` (bool), ``recovered`` (bool:
    survived and settled within ``settle_fraction × duration``), ``cost`` (J of each episode).
    Noise follows the scenario (use ``noise.scale = 0`` for a deterministic map).
    """
    thetas = np.asarray(thetas, dtype=float)
    theta_dots = np.asarray(theta_dots, dtype=float)
    tt, dd = np.meshgrid(thetas, theta_dots, indexing="ij")
    x0 = np.stack([np.zeros(tt.size), tt.ravel(), np.zeros(tt.size), dd.ravel()], axis=1)
    res = run_episodes(plant, scenario, policy, seed=seed, episodes=range(x0.shape[0]),
                       nthread=nthread, initial_states=x0)
    survived = np.array([bool(r["success"]) for r in res.rows])
    settle = np.array([float(r["settling_time"]) for r in res.rows])
    duration = scenario.n_periods * scenario.control_period
    recovered = survived & (settle <= settle_fraction * duration)
    cost = np.array([float(r["cost"]) for r in res.rows])
    shape = tt.shape
    return {"survived": survived.reshape(shape), "recovered": recovered.reshape(shape),
            "cost": cost.reshape(shape)}
