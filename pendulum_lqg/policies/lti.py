"""The built-in policies on a plant given as matrices (:class:`~pendulum_lqg.model.lti.LTIPlant`),
the scenario it runs under and its stationary closed loop (:mod:`pendulum_lqg.policies.theory`)."""

from __future__ import annotations

from typing import Any

import numpy as np

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.model.lti import LTI_CONTROLLERS, LTI_OBSERVERS, LTIPlant


def design_lti_policy(plant: LTIPlant, name: str, *, u_max: float | None = None) -> Any:
    """The built-in policy ``"controller+observer"`` on ``plant``: ``lqr`` (continuous, emulated
    under sample-and-hold) or ``dlqr`` (on the ZOH model with the exact sampled cost weights);
    observers ``none``, ``kalman`` (steady-state filter, current form), ``kalman-predictor``,
    ``luenberger`` (current form, the plant's ``observer_poles`` by z = e^{sT}, default three
    times the controller's). ``u_max``: the force limit in force, to which the policy saturates
    its own output (default the file's ``force_limit``). Returns a
    :class:`~pendulum_lqg.policies.lqg.Policy`."""
    from pendulum_lqg import design
    from pendulum_lqg.policies.estimators import CurrentEstimator, PredictorEstimator, TrueState
    from pendulum_lqg.policies.lqg import Policy

    controller, _, observer = name.partition("+")
    if controller not in LTI_CONTROLLERS or observer not in LTI_OBSERVERS:
        raise ConfigError(f"policy: expected one of {', '.join(LTI_CONTROLLERS)} + one of "
                          f"{', '.join(LTI_OBSERVERS)} for an LTI plant, got {name!r}")
    T, Phi, Gamma, C = plant.control_period, plant.Phi, plant.Gamma, plant.C
    if controller == "lqr":
        if plant.A is None or plant.B is None:
            raise ConfigError(f"policy: {plant.name!r} is given in discrete time; use dlqr")
        K = design.lqr(plant.A, plant.B, plant.Q, plant.R).K
    elif plant.A is not None and plant.B is not None:
        Qd, Rd, Nd = design.sampled_cost(plant.A, plant.B, plant.Q, plant.R, T)
        K = design.dlqr(Phi, Gamma, Qd, Rd, N=Nd).K
    else:
        K = design.dlqr(Phi, Gamma, plant.Q, plant.R).K
    info: dict[str, Any] = {"K": K, "Phi": Phi, "Gamma": Gamma, "C": C}
    n = plant.n_states
    est: Any
    if observer == "none":
        est = TrueState(n)
    elif observer in ("kalman", "kalman-predictor"):
        kf = design.dkalman(Phi, np.eye(n), C, plant.process_covariance(), plant.V)
        est = (CurrentEstimator(Phi, Gamma, C, kf.L, P=kf.P, M=kf.M) if observer == "kalman"
               else PredictorEstimator(Phi - kf.L_pred @ C, Gamma, kf.L_pred, C, P=kf.M, M=kf.M))
        info["L"], info["observer_poles"] = est.gain, kf.poles
    else:
        if plant.observer_poles is not None:     # s-plane, mapped by z = e^{sT}
            obs = design.dluenberger(Phi, C, np.asarray(plant.observer_poles), form="current",
                                     dt=T)
        else:     # 3× the controller's s-poles, the documents' rule: z = z_c³ (e^{3sT})
            z = np.linalg.eigvals(Phi - Gamma @ K)
            obs = design.dluenberger(Phi, C, z ** 3, form="current")
        est = CurrentEstimator(Phi, Gamma, C, obs.L)
        info["L"], info["observer_poles"] = obs.L, obs.poles
    return Policy(K=K, estimator=est, u_max=plant.force_limit if u_max is None else float(u_max),
                  name=name,
                  x_hat0=np.zeros(n), info=info)


def lti_scenario(plant: LTIPlant, *, duration: float = 10.0, noise_scale: float = 1.0,
                 **fields: Any) -> Any:
    """The :class:`~pendulum_lqg.core.scenario.Scenario` an LTI plant runs under (``run --lti``,
    ``bench`` with ``lti_file``): its own period, the plant ``linear-zoh`` (its exact sampled
    model), the noise ``scale`` (its W and V come from the file), and any other scenario
    ``fields`` (``estimate0``, ``force_limit``, the delays, ``dropout``)."""
    from pendulum_lqg.core.noise import NoiseModel
    from pendulum_lqg.core.scenario import Scenario

    return Scenario(control_period=plant.control_period, duration=duration, plant="linear-zoh",
                    noise=NoiseModel(scale=noise_scale), **fields)


def lti_theory(plant: LTIPlant, names: tuple[str, ...] = ("dlqr+kalman", "dlqr+luenberger"), *,
               noise_scale: float = 1.0, duration: float = 10.0, estimate0: str = "zero",
               burn_in: float = 0.0) -> dict[str, Any]:
    """The stationary closed loop (:class:`~pendulum_lqg.policies.theory.ClosedLoopTheory`) of
    each built-in policy on ``plant`` with its noise scaled by ``noise_scale`` (std), and the
    expected RMS over an episode of ``duration`` seconds from the file's ``x0``, ``x0_std`` and
    ``estimate0`` (after ``burn_in`` seconds). A negative or too large ``noise_scale``, a
    ``duration`` that is not a positive number and a ``burn_in`` not shorter than it are refused
    with the scenario's own checks, one line each (not the whole scenario: a file may be
    sampled slower than the loop's ceiling of the control period)."""
    from pendulum_lqg.core.noise import NoiseModel
    from pendulum_lqg.core.scenario import check_burn_in
    from pendulum_lqg.policies.theory import (
        StationaryProblem,
        episode_start,
        linear_estimator,
        stationary,
    )
    from pendulum_lqg.util.config import positive_number

    s = NoiseModel(scale=noise_scale).scale
    duration = positive_number("duration", duration)
    burn_in = check_burn_in(burn_in, plant.control_period, duration)
    if estimate0 not in ("zero", "true"):
        raise ConfigError(f"estimate0: expected 'zero' or 'true', got {estimate0!r}")
    s2 = s * s
    x0 = np.zeros(plant.n_states) if plant.x0 is None else plant.x0
    x0_std = np.zeros(plant.n_states) if plant.x0_std is None else plant.x0_std
    out = {}
    for name in names:
        policy = design_lti_policy(plant, name)
        prob = StationaryProblem(kind="linear-zoh", Phi=plant.Phi, Gamma=plant.Gamma, k=1,
                                 h=plant.control_period, C=plant.C, K=policy.K,
                                 estimator=linear_estimator(policy),
                                 Wd=plant.process_covariance() * s2, V=plant.V * s2,
                                 Q=plant.Q, R=plant.R)
        out[name] = stationary(prob, name=name, duration=duration,
                               limits={"force_limit": plant.force_limit},
                               state_names=plant.state_names,
                               units=("",) * plant.n_states,
                               start=episode_start(x0, x0_std, estimate0, policy),
                               burn_in=burn_in)
    return out
