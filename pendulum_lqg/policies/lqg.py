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
from typing import Any, ClassVar

import numpy as np

from pendulum_lqg import design
from pendulum_lqg.core.noise import NoiseModel
from pendulum_lqg.core.rules import saturate
from pendulum_lqg.model.interface import (
    ContinuousModel,
    SimulatedPlant,
    discretize_zoh,
    steps_per_period,
)
from pendulum_lqg.policies.estimators import Estimator, matvec
from pendulum_lqg.policies.observers import (
    OBSERVER_BUILDERS,
    ObserverProblem,
    noise_design_matrices,
    per_sample_process_covariance,
)
from pendulum_lqg.policies.spec import DesignSpec


@dataclass
class Policy:
    """``u = sat(−K x̂)`` with an estimator; vectorised over a batch.

    A built-in policy follows the same protocol as a user's plugin (:mod:`pendulum_lqg.policies.loading`):
    ``reset(n)``, ``act(y) -> u``, ``select(rows)``, ``needs_state``, ``x_hat``.

    Attributes
    ----------
    K : (1, 4) state-feedback gain
    estimator : the runtime estimator
    u_max : actuator limit [N] (an LTI plant of m inputs: one per input, (m,)); the policy
        saturates its own output so its model sees the applied force
    name : "<controller>+<observer>"
    info : design data (gains, poles, matrices) for reports and recordings
    independent_rows : always True — each row (episode) evolves on its own, so the core may run
        a batch as shards, each with a copy of the policy (:func:`~pendulum_lqg.core.runner.shard_count`)
    """

    independent_rows: ClassVar[bool] = True
    K: np.ndarray
    estimator: Estimator
    u_max: float | np.ndarray
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
        """One control period: measurement (n, 2) (or state (n, 4)) → force (n,) in newtons (an
        LTI plant of m inputs: (n, m))."""
        x_hat = self.estimator.estimate(y)
        u = saturate(-matvec(self.K, x_hat), self.u_max)    # the core's rule: the observer sees u applied
        self.estimator.update(u)
        return u[:, 0] if u.shape[1] == 1 else u          # (n, m) for a plant of m inputs

    def select(self, rows: np.ndarray) -> None:
        self.estimator.select(rows)

    @property
    def x_hat(self) -> np.ndarray:
        """The estimate (n, 4) the controller used at the last sample (the protocol's ``x_hat``)."""
        return self.estimator.x_hat


def design_policy(plant: SimulatedPlant, control_period: float, noise: NoiseModel,
                  spec: DesignSpec | None = None, *, linear: ContinuousModel | None = None,
                  delays: tuple[int, int] = (0, 0), u_max: float | None = None) -> Policy:
    """Design the policy ``spec`` for ``plant`` at ``control_period`` with the nominal noise.

    Parameters
    ----------
    plant : the (nominal) model the designer believes in
    control_period : T [s], a multiple of the physics step
    noise : nominal noise model (its ``scale`` is ignored: designs use the nominal densities)
    spec : controller / observer choice and weights
    linear : a precomputed :meth:`plant.linear_model()
        <pendulum_lqg.model.interface.SimulatedPlant.linear_model>` (to save time)
    delays : ``(measurement, actuator)`` delays in control periods that ``kalman-delay``
        compensates (:func:`delay_periods` of the scenario; the other observers ignore them)
    u_max : the force limit the policy saturates its own output to [N] (default the plant's
        ``ctrlrange``; :func:`~pendulum_lqg.core.rules.limits` of a scenario, ``inf`` for none)
    """
    spec = spec or DesignSpec()
    steps_per_period(plant, control_period)
    dt = float(control_period)
    lin = linear if linear is not None else plant.linear_model()
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
    problem = ObserverProblem(lin=lin, noise=noise, dt=dt, spec=spec, Phi=Phi, Gamma=Gamma,
                              Qd_noise=Qd_noise, delays=delays, info=info)
    est = OBSERVER_BUILDERS[spec.observer](problem)
    info["noise_Qd"], info["noise_V"] = Qd_noise, V
    return Policy(K=ctrl.K, estimator=est, u_max=plant.u_max if u_max is None else float(u_max),
                  name=f"{spec.controller}+{spec.observer}", info=info)


def delay_periods(scenario: object) -> tuple[int, int]:
    """``(measurement, actuator)`` delays of a :class:`~pendulum_lqg.core.scenario.Scenario` in periods —
    what :func:`design_policy` takes as ``delays``."""
    return (int(getattr(scenario, "measurement_delay_periods", 0)),
            int(getattr(scenario, "actuator_delay_periods", 0)))


def design_all(plant: SimulatedPlant, control_period: float, noise: NoiseModel,
               spec: DesignSpec | None = None) -> dict[str, Any]:
    """Every design of the project for one plant and period (what ``pendulum-lqg design`` prints).

    Returns plain arrays: the linearisation (``A, B, C, D``), the ZOH and ``mjd_transitionFD``
    discretisations, structure reports, continuous / discrete LQR, Kalman–Bucy / discrete Kalman
    (filter and predictor gains), continuous / discrete Luenberger, and the separation checks of the
    continuous and the discrete (current-form) LQG loops.
    """
    spec = spec or DesignSpec()
    steps_per_period(plant, control_period)
    dt = float(control_period)
    lin = plant.linear_model()
    zoh_model = discretize_zoh(lin, dt)
    fd_model = plant.transition(dt)
    A, B, C = lin.A, lin.B, lin.C
    Phi, Gamma = zoh_model.Phi, zoh_model.Gamma
    Q, R = spec.Q_matrix, spec.R_matrix
    Qd, Rd, Nd = design.sampled_cost(A, B, Q, R, dt)
    G, W = noise_design_matrices(lin, noise)
    Qd_noise = per_sample_process_covariance(lin, noise, dt)
    out: dict[str, Any] = {
        "linear": lin, "zoh": zoh_model, "transition_fd": fd_model,
        "structure": lin.structure(), "structure_discrete": zoh_model.structure(),
        "open_loop_poles": np.linalg.eigvals(A),
        "lqr": design.lqr(A, B, Q, R),
        "dlqr": design.dlqr(Phi, Gamma, Qd, Rd, N=Nd),
        "kalman": design.kalman(A, G, C, W, noise.V_density(dt)),
        "dkalman": design.dkalman(Phi, np.eye(A.shape[0]), C, Qd_noise, V := noise.V),
        "luenberger": design.luenberger(A, C, spec.observer_poles),
        "dluenberger": design.dluenberger(Phi, C, spec.observer_poles, form="current", dt=dt),
        "weights": {"Q": Q, "R": R, "Qd": Qd, "Rd": Rd, "Nd": Nd, "W": W, "V": V,
                    "W_per_sample": Qd_noise, "V_density": noise.V_density(dt), "G": G},
        "dt": dt, "steps_per_period": steps_per_period(plant, dt),
    }
    out["lqg"] = design.lqg(A, B, C, out["lqr"].K, out["kalman"].L, form="continuous")
    out["dlqg"] = design.lqg(Phi, Gamma, C, out["dlqr"].K, out["dkalman"].L, form="current")
    return out
