"""The observers of the built-in policies: one builder per name of
:data:`~pendulum_lqg.names.OBSERVERS`, in one registry (:data:`OBSERVER_BUILDERS`), and the noise
models the designs share.

A builder takes the design problem (:class:`ObserverProblem`: the linearisation, its discrete model,
the nominal noise and the spec), returns the runtime estimator and records what it designed (the
gain ``L``, the observer's poles, …) in the problem's ``info``, which becomes the policy's.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.linalg import expm

from pendulum_lqg import design
from pendulum_lqg.core.noise import NoiseModel
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.model.interface import ContinuousModel
from pendulum_lqg.policies.estimators import (
    CurrentEstimator,
    DelayKalman,
    Estimator,
    FilterStart,
    PredictorEstimator,
    ReducedOrderEstimator,
    TimeVaryingKalman,
    TrueState,
)
from pendulum_lqg.policies.spec import DesignSpec


@dataclass
class ObserverProblem:
    """What an observer is designed from: the continuous model ``lin``, its discrete model
    ``(Phi, Gamma)`` at the period ``dt`` [s], the nominal ``noise`` and its per-period process
    covariance ``Qd_noise``, the ``spec``, the ``(measurement, actuator)`` delays in periods, and
    ``info``, the policy's record, which the builder extends."""

    lin: ContinuousModel
    noise: NoiseModel
    dt: float
    spec: DesignSpec
    Phi: np.ndarray
    Gamma: np.ndarray
    Qd_noise: np.ndarray
    delays: tuple[int, int]
    info: dict[str, Any]

    @property
    def C(self) -> np.ndarray:
        return self.lin.C


def emulated_observer(A: np.ndarray, B: np.ndarray, C: np.ndarray, L: np.ndarray, dt: float,
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """ZOH of ``x̂̇ = (A − LC)x̂ + Bu + Ly`` with u, y held: ``x̂⁺ = F x̂ + G_u u + G_y y``."""
    n, m, p = A.shape[0], B.shape[1], C.shape[0]
    block = np.zeros((n + m + p, n + m + p))
    block[:n, :n] = A - L @ C
    block[:n, n:n + m] = B
    block[:n, n + m:] = L
    E = expm(block * dt)
    return E[:n, :n], E[:n, n:n + m], E[:n, n + m:]


def euler_observer(lin: ContinuousModel, noise: NoiseModel, dt: float, spec: DesignSpec,
                   ) -> tuple[PredictorEstimator, np.ndarray]:
    """The lecture's observer (seed 003): a continuous gain L, its ODE stepped by forward Euler.

    ``x̂[n+1] = x̂[n] + T·(A x̂[n] + B u[n] + L (y[n] − C x̂[n]))``, i.e. the predictor
    ``F = I + T(A − LC)``, ``G_u = T B``, ``G_y = T L``. L places the continuous poles
    ``spec.observer_poles`` (``luenberger-euler``; the lecture writes ``A + LC`` with the opposite
    sign of L) or is the Kalman–Bucy gain for the density W and ``V·T`` (``kalman-bucy-euler``;
    the lecture's ``care(Aᵀ, Cᵀ, Σ_w, Σ_v)`` with ``Σ_w = 0.04·I``, ``Σ_v = 0.01·I`` has the same
    ratio, hence the same gain). Returns the estimator and L (4, 2).
    """
    A, B, C = lin.A, lin.B, lin.C
    if spec.observer == "luenberger-euler":
        L = design.luenberger(A, C, spec.observer_poles).L
    else:
        G, W = noise_design_matrices(lin, noise)
        L = design.kalman(A, G, C, W, noise.V_density(dt)).L
    n = A.shape[0]
    est = PredictorEstimator(np.eye(n) + dt * (A - L @ C), dt * B, dt * L, C, gain=L,
                             Phi=np.eye(n) + dt * A, Gamma=dt * B)
    return est, L


def noise_design_matrices(plant_lin: ContinuousModel, noise: NoiseModel,
                          ) -> tuple[np.ndarray, np.ndarray]:
    """``(G, W)`` of the continuous process-noise model matching the simulator's injection."""
    if noise.process == "state":
        return np.eye(plant_lin.A.shape[0]), noise.W
    if plant_lin.F is None:
        raise ConfigError("noise.process: 'force' needs a plant whose joints take the force noise "
                          "(the MuJoCo cart-pole); this one's linear model has no F")
    return plant_lin.F, noise.W


def per_sample_process_covariance(plant_lin: ContinuousModel, noise: NoiseModel, dt: float,
                                  ) -> np.ndarray:
    """Covariance ``Q_d`` of the process noise accumulated over one control period.

    State noise is injected as one jump ``δx ~ N(0, W·T)`` per period, so ``Q_d = W·T`` exactly;
    force noise is integrated through the dynamics (Van Loan).
    """
    if noise.process == "state":
        return noise.W * dt
    G, W = noise_design_matrices(plant_lin, noise)
    return design.process_noise_covariance(plant_lin.A, G, W, dt)


def true_state(d: ObserverProblem) -> Estimator:
    return TrueState()


def luenberger(d: ObserverProblem) -> Estimator:
    obs = design.dluenberger(d.Phi, d.C, d.spec.observer_poles, form="current", dt=d.dt)
    d.info["L"], d.info["observer_poles"] = obs.L, obs.poles
    return CurrentEstimator(d.Phi, d.Gamma, d.C, obs.L)


def kalman(d: ObserverProblem) -> Estimator:
    """The steady-state filter, current (``kalman``) or predictor (``kalman-predictor``) form."""
    kf = design.dkalman(d.Phi, np.eye(4), d.C, d.Qd_noise, d.noise.V)
    # the error covariance of an episode starts where kalman-tv's does (M0), not at the limit P
    start = FilterStart(np.diag(d.spec.M0), d.Qd_noise, d.noise.V)
    est: Estimator
    if d.spec.observer == "kalman":
        est = CurrentEstimator(d.Phi, d.Gamma, d.C, kf.L, P=kf.P, M=kf.M, start=start)
        d.info["L"] = kf.L
    else:
        est = PredictorEstimator(d.Phi - kf.L_pred @ d.C, d.Gamma, kf.L_pred, d.C, P=kf.M, M=kf.M,
                                 start=start)
        d.info["L"] = kf.L_pred
    d.info["observer_poles"], d.info["P_kalman"] = kf.poles, kf.P
    return est


def kalman_time_varying(d: ObserverProblem) -> Estimator:
    M0 = np.diag(d.spec.M0)
    est = TimeVaryingKalman(d.Phi, d.Gamma, d.C, d.Qd_noise, d.noise.V, M0)
    kf = design.dkalman(d.Phi, np.eye(4), d.C, d.Qd_noise, d.noise.V)
    d.info["L"], d.info["observer_poles"], d.info["M0"] = kf.L, kf.poles, M0
    return est


def ackermann(d: ObserverProblem) -> Estimator:
    """Discrete predictor from the cart position alone: Ackermann on (Φ, C₁) with the poles
    z = e^{sT}; the θ column of the gain is 0, so the loop sees y = [p, θ] but uses p only."""
    z_poles = np.exp(np.asarray(d.spec.ackermann_poles, dtype=complex) * d.dt)
    L_p = np.hstack([design.ackermann(d.Phi, d.C[:1], z_poles).L, np.zeros((4, 1))])
    d.info["L"], d.info["observer_poles"] = L_p, np.linalg.eigvals(d.Phi - L_p @ d.C)
    return PredictorEstimator(d.Phi - L_p @ d.C, d.Gamma, L_p, d.C)


def reduced_order(d: ObserverProblem) -> Estimator:
    ro = design.dreduced_order_observer(
        d.Phi, d.Gamma, d.C,
        np.exp(np.asarray(d.spec.reduced_order_poles, dtype=complex) * d.dt))
    d.info["L"], d.info["observer_poles"] = ro.G, ro.poles
    return ReducedOrderEstimator(ro, d.C)


def kalman_delay(d: ObserverProblem) -> Estimator:
    aug = design.augment_delays(d.Phi, d.Gamma, d.C, measurement_delay=int(d.delays[0]),
                                actuator_delay=int(d.delays[1]))
    kf = design.dkalman(aug.Phi, aug.G, aug.C, d.Qd_noise, d.noise.V)
    d.info["L"], d.info["observer_poles"], d.info["P_kalman"] = kf.L, kf.poles, kf.P
    d.info["delays"], d.info["predict"] = tuple(int(n) for n in d.delays), aug.predict
    return DelayKalman(aug.Phi, aug.Gamma, aug.C, kf.L, aug.predict, P=kf.P, M=kf.M)


def euler(d: ObserverProblem) -> Estimator:
    """The lecture's observers (``luenberger-euler``, ``kalman-bucy-euler``): :func:`euler_observer`."""
    est, L = euler_observer(d.lin, d.noise, d.dt, d.spec)
    d.info["L"], d.info["observer_poles"] = L, np.linalg.eigvals(est.F)
    d.info["observer_poles_continuous"] = np.linalg.eigvals(d.lin.A - L @ d.C)
    return est


def continuous(d: ObserverProblem) -> Estimator:
    """A continuous design (``kalman-bucy``, ``lmi``, ``h2``, ``hinf``), emulated under
    sample-and-hold: the observer ODE with y and u held, discretised exactly."""
    A, C, noise, observer = d.lin.A, d.C, d.noise, d.spec.observer
    G, W = noise_design_matrices(d.lin, noise)
    P_obs = None
    if observer == "kalman-bucy":
        kb = design.kalman(A, G, C, W, noise.V_density(d.dt))
        L, P_obs = kb.L, kb.P
    elif observer == "lmi":
        L = design.lmi_observer(A, C, decay=d.spec.lmi_decay).L
    elif observer == "h2":
        L = design.h2_filter(A, G, C, W, noise.V_density(d.dt)).L
    else:  # hinf
        res = design.hinf_filter(A, G, C, W, noise.V_density(d.dt))
        L = res.L
        d.info["hinf_gamma"] = res.bound
    F, G_u, G_y = emulated_observer(A, d.lin.B, C, L, d.dt)
    d.info["L"], d.info["observer_poles"] = L, np.linalg.eigvals(F)
    d.info["observer_poles_continuous"] = np.linalg.eigvals(A - L @ C)
    return PredictorEstimator(F, G_u, G_y, C, gain=L, P=P_obs, Phi=d.Phi, Gamma=d.Gamma)


#: Each observer name (:data:`~pendulum_lqg.names.OBSERVERS`, the CLI's numpy-free list, which a
#: test holds equal to these keys) and its builder.
OBSERVER_BUILDERS: dict[str, Callable[[ObserverProblem], Estimator]] = {
    "none": true_state,
    "luenberger": luenberger,
    "kalman": kalman,
    "kalman-predictor": kalman,
    "kalman-tv": kalman_time_varying,
    "kalman-bucy": continuous,
    "reduced-order": reduced_order,
    "ackermann": ackermann,
    "lmi": continuous,
    "h2": continuous,
    "hinf": continuous,
    "kalman-delay": kalman_delay,
    "luenberger-euler": euler,
    "kalman-bucy-euler": euler,
}
