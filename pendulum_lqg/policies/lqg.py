"""Policies: a controller (state feedback) plus an estimator, ``reset(n)`` / ``act(y) -> u``.

:func:`design_policy` turns a plant, a control period and a noise model into any of the project's
LQG variants. The policy is an ordinary agent: it sees only the measurement ``y = [p, θ]`` (or the
true state for ``observer="none"``), knows the actuator limit (so its model uses the force actually
applied), and is vectorised over a batch of episodes. It knows nothing of gymnasium or Rerun.

Controllers
    ``lqr``  continuous design ``lqr(A, B, Q, R)``, emulated under sample-and-hold;
    ``dlqr`` discrete design on the ZOH model with the exact sampled cost weights, so it minimises
    the very ``J = ∫ xᵀQx + uᵀRu dt`` the benchmark measures (:func:`~pendulum_lqg.design.sampled_cost`).
Observers
    ``none`` true state · ``luenberger`` current form, continuous poles mapped by z = e^{sT} ·
    ``kalman`` steady-state filter (current) form · ``kalman-predictor`` steady-state predictor form ·
    ``kalman-tv`` time-varying filter from ``M0`` · ``kalman-bucy`` continuous Kalman–Bucy design,
    its observer ODE discretised by ZOH (a predictor-type recursion) · ``reduced-order`` discrete
    minimal-order observer of the velocities (poles ``reduced_order_poles`` mapped by z = e^{sT}) ·
    ``ackermann`` discrete predictor from the cart position p alone (Ackermann's formula on
    ``(Φ, C₁)``, poles ``ackermann_poles`` mapped by z = e^{sT}) · ``lmi`` continuous decay-rate
    observer (Re λ ≤ −``lmi_decay``) · ``h2`` continuous H₂ filter by LMI (= Kalman–Bucy) ·
    ``hinf`` continuous H∞ filter by LMI (minimal certified γ). The continuous designs run under
    sample-and-hold like ``kalman-bucy``: the observer ODE with y and u held, discretised exactly.
    ``kalman-delay`` the steady-state filter of the state augmented with the scenario's
    measurement and actuator delay lines (exact for whole periods), whose controller acts on the
    state predicted over the actuator delay, ``u_n = −K x̂_{n+d_a|n}``
    (:func:`~pendulum_lqg.design.augment_delays`). The other observers ignore delays.
    ``luenberger-euler`` / ``kalman-bucy-euler`` the lecture's own observers: the continuous
    Luenberger (poles ``observer_poles``) or Kalman–Bucy gain L in the observer ODE stepped by
    forward Euler at the control period, ``x̂ ← x̂ + T·(A x̂ + B u + L (y − C x̂))`` (a predictor:
    the force at sample n uses y up to n − 1). With ``lqr`` and ``plant = "linear-euler"`` this is
    the lecture's simulation exactly (:func:`euler_observer`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, ClassVar, Literal

import numpy as np
from scipy.linalg import expm

from pendulum_lqg import design
from pendulum_lqg.core.noise import NoiseModel
from pendulum_lqg.core.rules import saturate
from pendulum_lqg.design.checks import as_poles
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.model.linearize import ContinuousModel, discretize_zoh, linearize
from pendulum_lqg.model.plant import Plant, steps_per_period
from pendulum_lqg.names import CONTROLLERS, OBSERVERS
from pendulum_lqg.policies.estimators import (
    CurrentEstimator,
    DelayKalman,
    Estimator,
    PredictorEstimator,
    ReducedOrderEstimator,
    TimeVaryingKalman,
    TrueState,
    mv,
)
from pendulum_lqg.util.config import config_vector

Controller = Literal["lqr", "dlqr"]
Observer = Literal["none", "luenberger", "kalman", "kalman-predictor", "kalman-tv", "kalman-bucy",
                   "reduced-order", "ackermann", "lmi", "h2", "hinf", "kalman-delay",
                   "luenberger-euler", "kalman-bucy-euler"]


@dataclass(frozen=True)
class DesignSpec:
    """Everything a policy design depends on besides the plant, the period and the noise.

    Attributes
    ----------
    controller, observer : names from :data:`CONTROLLERS` / :data:`OBSERVERS`
    Q : diagonal of the state weight (4,), R : input weight (N⁻²)
    observer_poles : continuous-time Luenberger poles (s-plane), mapped by z = e^{sT}
    M0 : diagonal of the initial a-priori covariance of the time-varying Kalman filter
    discretization : model the discrete designs use, "zoh" (exact) or "euler" (first order)
    reduced_order_poles : continuous-time poles (2) of the reduced-order observer [rad/s]
    ackermann_poles : continuous-time poles (4) of the Ackermann observer from p alone [rad/s];
        faster than ``observer_poles``: estimating θ from the cart position alone with the slow
        default set is too slow for the falling pole (3.97 rad/s) even without noise
    lmi_decay : decay rate α [1/s] of the ``lmi`` observer (every error pole at Re λ ≤ −α)
    """

    controller: str = "dlqr"
    observer: str = "kalman"
    Q: tuple[float, ...] = (1.0, 1.0, 1.0, 1.0)
    R: float = 1.0
    observer_poles: tuple[float, ...] = design.DEFAULT_OBSERVER_POLES
    M0: tuple[float, ...] = (0.01, 0.01, 0.01, 0.01)
    discretization: str = "zoh"
    reduced_order_poles: tuple[float, ...] = (-4.0, -5.0)
    ackermann_poles: tuple[float, ...] = (-2.0, -3.0, -4.0, -5.0)
    lmi_decay: float = 1.0

    def __post_init__(self) -> None:
        if self.controller not in CONTROLLERS:
            raise ConfigError(f"controller: unknown {self.controller!r}; expected one of "
                              + ", ".join(CONTROLLERS))
        if self.observer not in OBSERVERS:
            raise ConfigError(f"observer: unknown {self.observer!r}; expected one of "
                              + ", ".join(OBSERVERS))
        if self.discretization not in ("zoh", "euler"):
            raise ConfigError(f"discretization: expected 'zoh' or 'euler', got "
                              f"{self.discretization!r}")
        for name in ("Q", "M0"):             # diagonals of 4×4 matrices
            object.__setattr__(self, name, config_vector(name, getattr(self, name), 4, nonneg=True))
        if isinstance(self.R, bool) or not isinstance(self.R, int | float | np.integer
                                                      | np.floating):
            raise ConfigError(f"R: expected a finite positive number, got {self.R!r}")
        r = float(self.R)
        if not np.isfinite(r) or r <= 0:
            raise ConfigError(f"R: expected a finite positive number, got {self.R!r}")
        object.__setattr__(self, "R", r)
        for name, count in (("observer_poles", 4), ("reduced_order_poles", 2),
                            ("ackermann_poles", 4)):
            checked = as_poles(name, getattr(self, name), count)
            poles = tuple(complex(p) if abs(p.imag) > 0 else float(p.real) for p in checked)
            object.__setattr__(self, name, poles)
        decay = self.lmi_decay
        if isinstance(decay, bool) or not isinstance(decay, int | float) \
                or not np.isfinite(decay) or decay < 0:
            raise ConfigError(f"lmi_decay: expected a finite rate ≥ 0 [1/s], got {decay!r}")
        object.__setattr__(self, "lmi_decay", float(decay))

    @property
    def Q_matrix(self) -> np.ndarray:
        return np.diag(self.Q)

    @property
    def R_matrix(self) -> np.ndarray:
        return np.array([[self.R]])


@dataclass
class Policy:
    """``u = sat(−K x̂)`` with an estimator; vectorised over a batch.

    A built-in policy follows the same protocol as a user's plugin (:mod:`pendulum_lqg.policies.loading`):
    ``reset(n)``, ``act(y) -> u``, ``select(rows)``, ``needs_state``, ``x_hat``.

    Attributes
    ----------
    K : (1, 4) state-feedback gain
    estimator : the runtime estimator
    u_max : actuator limit [N]; the policy saturates its own output so its model sees the
        applied force
    name : "<controller>+<observer>"
    info : design data (gains, poles, matrices) for reports and recordings
    independent_rows : always True — each row (episode) evolves on its own, so the core may run
        a batch as shards, each with a copy of the policy (:func:`~pendulum_lqg.core.runner.shard_count`)
    """

    independent_rows: ClassVar[bool] = True
    K: np.ndarray
    estimator: Estimator
    u_max: float
    name: str
    x_hat0: np.ndarray = field(default_factory=lambda: np.zeros(4))
    info: dict[str, Any] = field(default_factory=dict)

    @property
    def needs_state(self) -> bool:
        return self.estimator.needs_state

    def reset(self, n: int, x_hat0: np.ndarray | None = None) -> None:
        """Start ``n`` episodes; ``x_hat0`` (n, 4) defaults to the policy's ``x_hat0``."""
        if x_hat0 is None:
            x_hat0 = np.tile(self.x_hat0, (n, 1))
        self.estimator.reset(x_hat0)

    def act(self, y: np.ndarray) -> np.ndarray:
        """One control period: measurement (n, 2) (or state (n, 4)) → force (n,) in newtons."""
        x_hat = self.estimator.estimate(y)
        u = saturate(-mv(self.K, x_hat), self.u_max)    # the core's rule: the observer sees u applied
        self.estimator.update(u)
        return u[:, 0]

    def select(self, rows: np.ndarray) -> None:
        self.estimator.select(rows)

    @property
    def x_hat(self) -> np.ndarray:
        """The estimate (n, 4) the controller used at the last sample (the protocol's ``x_hat``)."""
        return self.estimator.x_hat


def _emulated_observer(A: np.ndarray, B: np.ndarray, C: np.ndarray, L: np.ndarray, dt: float,
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
        G, W = noise_design_matrices(lin, noise, dt)
        L = design.kalman(A, G, C, W, noise.V_density(dt)).L
    n = A.shape[0]
    est = PredictorEstimator(np.eye(n) + dt * (A - L @ C), dt * B, dt * L, C, gain=L,
                             Phi=np.eye(n) + dt * A, Gamma=dt * B)
    return est, L


def noise_design_matrices(plant_lin: ContinuousModel, noise: NoiseModel, dt: float,
                          ) -> tuple[np.ndarray, np.ndarray]:
    """``(G, W)`` of the continuous process-noise model matching the simulator's injection."""
    G = np.eye(4) if noise.process == "state" else plant_lin.F
    return G, noise.W


def per_sample_process_covariance(plant_lin: ContinuousModel, noise: NoiseModel, dt: float,
                                  ) -> np.ndarray:
    """Covariance ``Q_d`` of the process noise accumulated over one control period.

    State noise is injected as one jump ``δx ~ N(0, W·T)`` per period, so ``Q_d = W·T`` exactly;
    force noise is integrated through the dynamics (Van Loan).
    """
    if noise.process == "state":
        return noise.W * dt
    G, W = noise_design_matrices(plant_lin, noise, dt)
    return design.process_noise_covariance(plant_lin.A, G, W, dt)


def design_policy(plant: Plant, control_period: float, noise: NoiseModel,
                  spec: DesignSpec | None = None, *, linear: ContinuousModel | None = None,
                  delays: tuple[int, int] = (0, 0), u_max: float | None = None) -> Policy:
    """Design the policy ``spec`` for ``plant`` at ``control_period`` with the nominal noise.

    Parameters
    ----------
    plant : the (nominal) model the designer believes in
    control_period : T [s], a multiple of the physics step
    noise : nominal noise model (its ``scale`` is ignored: designs use the nominal densities)
    spec : controller / observer choice and weights
    linear : a precomputed :func:`~pendulum_lqg.model.linearize.linearize` result (to save time)
    delays : ``(measurement, actuator)`` delays in control periods that ``kalman-delay``
        compensates (:func:`delay_periods` of the scenario; the other observers ignore them)
    u_max : the force limit the policy saturates its own output to [N] (default the plant's
        ``ctrlrange``; :func:`~pendulum_lqg.core.rules.limits` of a scenario, ``inf`` for none)
    """
    spec = spec or DesignSpec()
    steps_per_period(plant, control_period)
    dt = float(control_period)
    lin = linear if linear is not None else linearize(plant)
    A, B, C = lin.A, lin.B, lin.C
    if spec.discretization == "zoh":
        disc = discretize_zoh(lin, dt)
        Phi, Gamma = disc.Phi, disc.Gamma
    else:
        Phi, Gamma = design.euler(A, B, dt)
    Q, R = spec.Q_matrix, spec.R_matrix
    info: dict[str, Any] = {"A": A, "B": B, "C": C, "Phi": Phi, "Gamma": Gamma, "dt": dt,
                               "Q": Q, "R": R}

    if spec.controller == "lqr":
        ctrl = design.lqr(A, B, Q, R)
    else:
        Qd, Rd, Nd = design.sampled_cost(A, B, Q, R, dt)
        ctrl = design.dlqr(Phi, Gamma, Qd, Rd, N=Nd)
    info["K"], info["P_lqr"], info["controller_poles"] = ctrl.K, ctrl.P, ctrl.poles

    V = noise.V
    Qd_noise = per_sample_process_covariance(lin, noise, dt)
    est: Estimator
    if spec.observer == "none":
        est = TrueState()
    elif spec.observer == "luenberger":
        obs = design.dluenberger(Phi, C, spec.observer_poles, form="current", dt=dt)
        est = CurrentEstimator(Phi, Gamma, C, obs.L)
        info["L"], info["observer_poles"] = obs.L, obs.poles
    elif spec.observer in ("kalman", "kalman-predictor"):
        kf = design.dkalman(Phi, np.eye(4), C, Qd_noise, V)
        if spec.observer == "kalman":
            est = CurrentEstimator(Phi, Gamma, C, kf.L, P=kf.P, M=kf.M)
            info["L"] = kf.L
        else:
            est = PredictorEstimator(Phi - kf.L_pred @ C, Gamma, kf.L_pred, C, P=kf.M, M=kf.M)
            info["L"] = kf.L_pred
        info["observer_poles"], info["P_kalman"] = kf.poles, kf.P
    elif spec.observer == "kalman-tv":
        M0 = np.diag(spec.M0)
        est = TimeVaryingKalman(Phi, Gamma, C, Qd_noise, V, M0)
        kf = design.dkalman(Phi, np.eye(4), C, Qd_noise, V)
        info["L"], info["observer_poles"], info["M0"] = kf.L, kf.poles, M0
    elif spec.observer == "ackermann":
        # discrete predictor from the cart position alone: Ackermann on (Φ, C₁) with the poles
        # z = e^{sT}; the θ column of the gain is 0, so the loop sees y = [p, θ] but uses p only
        z_poles = np.exp(np.asarray(spec.ackermann_poles, dtype=complex) * dt)
        L_p = np.hstack([design.ackermann(Phi, C[:1], z_poles).L, np.zeros((4, 1))])
        est = PredictorEstimator(Phi - L_p @ C, Gamma, L_p, C)
        info["L"], info["observer_poles"] = L_p, np.linalg.eigvals(Phi - L_p @ C)
    elif spec.observer == "reduced-order":
        ro = design.dreduced_order_observer(
            Phi, Gamma, C, np.exp(np.asarray(spec.reduced_order_poles, dtype=complex) * dt))
        est = ReducedOrderEstimator(ro, C)
        info["L"], info["observer_poles"] = ro.G, ro.poles
    elif spec.observer == "kalman-delay":
        aug = design.augment_delays(Phi, Gamma, C, measurement_delay=int(delays[0]),
                                    actuator_delay=int(delays[1]))
        kf = design.dkalman(aug.Phi, aug.G, aug.C, Qd_noise, V)
        est = DelayKalman(aug.Phi, aug.Gamma, aug.C, kf.L, aug.predict, P=kf.P, M=kf.M)
        info["L"], info["observer_poles"], info["P_kalman"] = kf.L, kf.poles, kf.P
        info["delays"], info["predict"] = tuple(int(d) for d in delays), aug.predict
    elif spec.observer in ("luenberger-euler", "kalman-bucy-euler"):
        est, L = euler_observer(lin, noise, dt, spec)
        info["L"], info["observer_poles"] = L, np.linalg.eigvals(est.F)
        info["observer_poles_continuous"] = np.linalg.eigvals(A - L @ C)
    else:  # continuous designs, emulated under sample-and-hold
        G, W = noise_design_matrices(lin, noise, dt)
        P_obs = None
        if spec.observer == "kalman-bucy":
            kb = design.kalman(A, G, C, W, noise.V_density(dt))
            L, P_obs = kb.L, kb.P
        elif spec.observer == "lmi":
            L = design.lmi_observer(A, C, decay=spec.lmi_decay).L
        elif spec.observer == "h2":
            L = design.h2_filter(A, G, C, W, noise.V_density(dt)).L
        else:  # hinf
            res = design.hinf_filter(A, G, C, W, noise.V_density(dt))
            L = res.L
            info["hinf_gamma"] = res.bound
        F, G_u, G_y = _emulated_observer(A, B, C, L, dt)
        est = PredictorEstimator(F, G_u, G_y, C, gain=L, P=P_obs, Phi=Phi, Gamma=Gamma)
        info["L"], info["observer_poles"] = L, np.linalg.eigvals(F)
        info["observer_poles_continuous"] = np.linalg.eigvals(A - L @ C)
    info["noise_Qd"], info["noise_V"] = Qd_noise, V
    return Policy(K=ctrl.K, estimator=est, u_max=plant.u_max if u_max is None else float(u_max),
                  name=f"{spec.controller}+{spec.observer}", info=info)


def delay_periods(scenario: object) -> tuple[int, int]:
    """``(measurement, actuator)`` delays of a :class:`~pendulum_lqg.core.scenario.Scenario` in periods —
    what :func:`design_policy` takes as ``delays``."""
    return (int(getattr(scenario, "measurement_delay_periods", 0)),
            int(getattr(scenario, "actuator_delay_periods", 0)))


def design_all(plant: Plant, control_period: float, noise: NoiseModel,
               spec: DesignSpec | None = None) -> dict[str, Any]:
    """Every design of the project for one plant and period (what ``pendulum-lqg design`` prints).

    Returns plain arrays: the linearisation (``A, B, C, D``), the ZOH and ``mjd_transitionFD``
    discretisations, structure reports, continuous / discrete LQR, Kalman–Bucy / discrete Kalman
    (filter and predictor gains), continuous / discrete Luenberger, and the separation checks of the
    continuous and the discrete (current-form) LQG loops.
    """
    from pendulum_lqg.model.linearize import discretize_transition

    spec = spec or DesignSpec()
    steps_per_period(plant, control_period)
    dt = float(control_period)
    lin = linearize(plant)
    zoh_model = discretize_zoh(lin, dt)
    fd_model = discretize_transition(plant, dt)
    A, B, C = lin.A, lin.B, lin.C
    Phi, Gamma = zoh_model.Phi, zoh_model.Gamma
    Q, R = spec.Q_matrix, spec.R_matrix
    Qd, Rd, Nd = design.sampled_cost(A, B, Q, R, dt)
    G, W = noise_design_matrices(lin, noise, dt)
    Qd_noise = per_sample_process_covariance(lin, noise, dt)
    out: dict[str, Any] = {
        "linear": lin, "zoh": zoh_model, "transition_fd": fd_model,
        "structure": lin.structure(), "structure_discrete": zoh_model.structure(),
        "open_loop_poles": np.linalg.eigvals(A),
        "lqr": design.lqr(A, B, Q, R),
        "dlqr": design.dlqr(Phi, Gamma, Qd, Rd, N=Nd),
        "kalman": design.kalman(A, G, C, W, noise.V_density(dt)),
        "dkalman": design.dkalman(Phi, np.eye(4), C, Qd_noise, V := noise.V),
        "luenberger": design.luenberger(A, C, spec.observer_poles),
        "dluenberger": design.dluenberger(Phi, C, spec.observer_poles, form="current", dt=dt),
        "weights": {"Q": Q, "R": R, "Qd": Qd, "Rd": Rd, "Nd": Nd, "W": W, "V": V,
                    "W_per_sample": Qd_noise, "V_density": noise.V_density(dt), "G": G},
        "dt": dt, "steps_per_period": steps_per_period(plant, dt),
    }
    out["lqg"] = design.lqg(A, B, C, out["lqr"].K, out["kalman"].L, form="continuous")
    out["dlqg"] = design.lqg(Phi, Gamma, C, out["dlqr"].K, out["dkalman"].L, form="current")
    return out
