"""The built-in policies on a plant given as matrices (:class:`~pendulum_lqg.model.lti.LTIPlant`),
the scenario it runs under and its stationary closed loop (:mod:`pendulum_lqg.policies.theory`)."""

from __future__ import annotations

from typing import Any, cast

import numpy as np

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.model.lti import LTI_CONTROLLERS, LTI_OBSERVERS, LTIPlant
from pendulum_lqg.problem import defaults


def design_lti_policy(plant: LTIPlant, name: str, *,
                      u_max: float | np.ndarray | None = None) -> Any:
    """The built-in policy ``"controller+observer"`` on ``plant``: ``lqr`` (continuous, emulated
    under sample-and-hold) or ``dlqr`` (on the ZOH model with the exact sampled cost weights);
    observers ``none``, ``kalman`` (steady-state filter, current form), ``kalman-predictor``,
    ``luenberger`` (current form, the plant's ``observer_poles`` by z = e^{sT}, default three
    times the controller's). ``u_max``: the limit in force, one or one per input, to which the
    policy saturates its own output (default the file's ``force_limit``). Returns a
    :class:`~pendulum_lqg.policies.lqg.Policy`."""
    from pendulum_lqg import design
    from pendulum_lqg.policies.estimators import (
        CurrentEstimator,
        FilterStart,
        PredictorEstimator,
        TrueState,
    )
    from pendulum_lqg.policies.lqg import Policy

    controller, _, observer = name.partition("+")
    if controller not in LTI_CONTROLLERS or observer not in LTI_OBSERVERS:
        raise ConfigError(f"policy: expected one of {', '.join(LTI_CONTROLLERS)} + one of "
                          f"{', '.join(LTI_OBSERVERS)} for an LTI plant, got {name!r}")
    T, Phi, Gamma, C = plant.control_period, plant.Phi, plant.Gamma, plant.C
    K = lti_controller(plant, controller)
    info: dict[str, Any] = {"K": K, "Phi": Phi, "Gamma": Gamma, "C": C}
    n = plant.n_states
    est: Any
    if observer == "none":
        est = TrueState(n)
    elif observer in ("kalman", "kalman-predictor"):
        Qd = plant.process_covariance()
        kf = design.dkalman(Phi, np.eye(n), C, Qd, plant.V)
        # a plant given as matrices has no M0 option: its start is x₀ ~ N(x0, diag(x0_std²))
        # with x̂₀ = 0, so x̄₀ − x₀ has the second moment x0 x0ᵀ + diag(x0_std²)
        x0 = np.zeros(n) if plant.x0 is None else np.asarray(plant.x0, dtype=float)
        sd = np.zeros(n) if plant.x0_std is None else np.asarray(plant.x0_std, dtype=float)
        start = FilterStart(np.outer(x0, x0) + np.diag(sd ** 2), Qd, plant.V)
        est = (CurrentEstimator(Phi, Gamma, C, kf.L, P=kf.P, M=kf.M, start=start)
               if observer == "kalman"
               else PredictorEstimator(Phi - kf.L_pred @ C, Gamma, kf.L_pred, C, P=kf.M, M=kf.M,
                                       start=start))
        info["L"], info["observer_poles"] = est.gain, kf.poles
    else:
        if plant.observer_poles is not None:     # s-plane, mapped by z = e^{sT}
            obs = design.dluenberger(Phi, C, np.asarray(plant.observer_poles), form="current",
                                     dt=T)
        else:
            obs = design.dluenberger(Phi, C, default_observer_z(plant, K), form="current")
        est = CurrentEstimator(Phi, Gamma, C, obs.L)
        info["L"], info["observer_poles"] = obs.L, obs.poles
    m = plant.n_inputs
    limit = plant.limits_per_input if u_max is None else np.broadcast_to(
        np.asarray(u_max, dtype=float), (m,)).copy()
    return Policy(K=K, estimator=est, u_max=float(limit[0]) if m == 1 else limit,
                  name=name,
                  x_hat0=np.zeros(n), info=info)


def lti_controller(plant: LTIPlant, controller: str) -> np.ndarray:
    """The gain K (m, n) of ``controller`` on ``plant``: ``lqr`` the continuous design of
    ``∫ xᵀQx + 2xᵀNu + uᵀRu dt``, ``dlqr`` the discrete one with the exact sampled weights
    (:func:`~pendulum_lqg.design.sampled_cost`), or on a plant given in discrete time its own
    per-sample Q, R, N."""
    from pendulum_lqg import design

    if controller == "lqr":
        if plant.A is None or plant.B is None:
            raise ConfigError(f"policy: {plant.name!r} is given in discrete time; use dlqr")
        return design.lqr(plant.A, plant.B, plant.Q, plant.R, N=plant.N).K
    Qd, Rd, Nd = discrete_weights(plant)
    return design.dlqr(plant.Phi, plant.Gamma, Qd, Rd, N=Nd).K


def default_observer_z(plant: LTIPlant, K: np.ndarray) -> np.ndarray:
    """The default discrete observer poles: the controller's s-poles three times as fast, the
    documents' rule of thumb, ``z = z_c³`` (``e^{3sT}``) with ``z_c`` the eigenvalues of
    ``Φ − ΓK``."""
    return np.linalg.eigvals(plant.Phi - plant.Gamma @ K) ** 3


def lti_scenario(plant: LTIPlant, *, duration: float = defaults.DURATION,
                 noise_scale: float = defaults.NOISE_SCALE, simulator: str | None = None,
                 **fields: Any) -> Any:
    """The :class:`~pendulum_lqg.core.scenario.Scenario` a plant file's plant runs under (``run
    --plant``, ``bench`` with ``plant``): its own period, the ``simulator`` (default the plant's:
    a matrix plant's exact sampled model, a MuJoCo plant's MuJoCo), the noise ``scale`` (its W
    and V come from the file), and any other scenario ``fields`` (``estimate0``,
    ``force_limit``, the delays, ``dropout``)."""
    from pendulum_lqg.core.noise import NoiseModel
    from pendulum_lqg.core.scenario import Scenario

    return Scenario(control_period=plant.control_period, duration=duration,
                    plant=cast(Any, simulator or plant.default_simulator),   # checked there
                    noise=NoiseModel(scale=noise_scale), **fields)


def lti_theory(plant: LTIPlant, names: tuple[str, ...] = ("dlqr+kalman", "dlqr+luenberger"), *,
               noise_scale: float = defaults.NOISE_SCALE, duration: float = defaults.DURATION,
               estimate0: str = "zero",
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
    from pendulum_lqg.policies.closed_loop import StationaryProblem, linear_estimator
    from pendulum_lqg.policies.episode_theory import episode_start
    from pendulum_lqg.policies.theory import stationary
    from pendulum_lqg.problem.declare import positive_number

    s = NoiseModel(scale=noise_scale).scale
    duration = positive_number("duration", duration)
    burn_in = check_burn_in(burn_in, plant.control_period, duration)
    if estimate0 not in ("zero", "true"):
        raise ConfigError(f"estimate0: expected 'zero' or 'true', got {estimate0!r}")
    s2 = s * s
    x0 = np.zeros(plant.n_states) if plant.x0 is None else plant.x0
    x0_std = np.zeros(plant.n_states) if plant.x0_std is None else plant.x0_std
    out = {}
    # the loop as it is simulated: k physics steps of h per period (an LTI plant: k = 1, h = T;
    # a MuJoCo plant: its physics step), the cost integrated at h as the simulation does
    h = plant.timestep
    k = round(plant.control_period / h)
    Phi_h, Gamma_h = plant.sampled(h)
    for name in names:
        policy = design_lti_policy(plant, name)
        prob = StationaryProblem(kind="linear-zoh", Phi=Phi_h, Gamma=Gamma_h, k=k,
                                 h=h, C=plant.C, K=policy.K,
                                 estimator=linear_estimator(policy),
                                 Wd=plant.process_covariance() * s2, V=plant.V * s2,
                                 Q=plant.Q, R=plant.R, N=plant.cross_weight,
                                 inputs=tuple(plant.input_names))
        out[name] = stationary(prob, name=name, duration=duration,
                               limits={"force_limit": plant.force_limit,
                                       **_state_limits(plant)},
                               state_names=plant.state_names,
                               units=("",) * plant.n_states,
                               start=episode_start(x0, x0_std, estimate0, policy),
                               burn_in=burn_in)
    return out


def _state_limits(plant: LTIPlant) -> dict[str, float]:
    """``{"limit_<state>": |x_i| limit}`` of each state the plant file limits (the failure rule
    of its ``state_limits``; the verdict sets each state's std against its own limit)."""
    if plant.state_limits is None:
        return {}
    return {f"limit_{name}": float(lim) for name, lim in zip(plant.state_names,
                                                             plant.state_limits, strict=True)
            if np.isfinite(lim)}


def design_lti_all(plant: LTIPlant) -> dict[str, Any]:
    """Every design of ``design --lti`` on ``plant`` (what :func:`~pendulum_lqg.policies.lqg.design_all`
    is for the cart-pole), as plain arrays and design results.

    Continuous designs (a plant given by A, B only): ``lqr`` of ``∫ xᵀQx + 2xᵀNu + uᵀRu dt``,
    ``kalman`` (Kalman–Bucy with the density W of w through G — or ``Wd / T`` for a file's
    per-period ``Wd`` — and the measurement density ``V·T``), ``luenberger`` (the file's poles, or
    3× the LQR's), ``lqg`` their separation check. Discrete designs: ``dlqr`` (exact sampled
    weights), ``dkalman`` (filter gain L, predictor gain ``L_pred = Φ L``), ``dluenberger``
    (current form, the file's poles by ``z = e^{sT}`` or :func:`default_observer_z`), ``dlqg`` the
    separation check of dlqr + discrete Kalman in current form.
    """
    from pendulum_lqg import design

    T, Phi, Gamma, C = plant.control_period, plant.Phi, plant.Gamma, plant.C
    n, Vd = plant.n_states, plant.V
    out: dict[str, Any] = {
        "dt": T, "structure_discrete": design.structure(Phi, Gamma, C, discrete=True),
        "open_loop_poles_discrete": np.linalg.eigvals(Phi),
        "dkalman": design.dkalman(Phi, np.eye(n), C, plant.process_covariance(), Vd),
        "weights": {"Q": plant.Q, "R": plant.R, "N": plant.cross_weight, "W": plant.W, "V": Vd,
                    "W_per_period": plant.process_covariance()}}
    Qd, Rd, Nd = discrete_weights(plant)
    out["dlqr"] = design.dlqr(Phi, Gamma, Qd, Rd, N=Nd)
    out["weights"].update(Qd=Qd, Rd=Rd, Nd=Nd)
    poles = None if plant.observer_poles is None else np.asarray(plant.observer_poles)
    out["dluenberger"] = (design.dluenberger(Phi, C, poles, form="current", dt=T)
                          if poles is not None else
                          design.dluenberger(Phi, C, default_observer_z(plant, out["dlqr"].K),
                                             form="current"))
    out["dlqg"] = design.lqg(Phi, Gamma, C, out["dlqr"].K, out["dkalman"].L, form="current")
    if plant.A is None or plant.B is None:
        return out
    A, B = plant.A, plant.B
    W = plant.W / T if plant.W_per_period else plant.W     # a density: per period / T
    out["structure"] = design.structure(A, B, C)
    out["open_loop_poles"] = np.linalg.eigvals(A)
    out["lqr"] = design.lqr(A, B, plant.Q, plant.R, N=plant.N)
    out["kalman"] = design.kalman(A, plant.G, C, W, Vd * T)
    out["luenberger"] = design.luenberger(A, C, poles if poles is not None
                                          else 3 * out["lqr"].poles)
    out["lqg"] = design.lqg(A, B, C, out["lqr"].K, out["kalman"].L, form="continuous")
    out["weights"].update(W_density=W, V_density=Vd * T)
    return out


def discrete_weights(plant: LTIPlant) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(Qd, Rd, Nd)``: the per-period weights of the discrete LQR on ``plant``, the exact
    sampled equivalents of its continuous ``Q, R, N`` (:func:`~pendulum_lqg.design.sampled_cost`),
    or, for a plant given in discrete time, its own per-sample ``Q, R, N``."""
    from pendulum_lqg import design

    if plant.A is not None and plant.B is not None:
        Qd, Rd, Nd = design.sampled_cost(plant.A, plant.B, plant.Q, plant.R,
                                         plant.control_period, N=plant.N)
        return Qd, Rd, Nd
    return plant.Q, plant.R, plant.cross_weight
