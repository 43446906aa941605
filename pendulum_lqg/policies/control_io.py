r"""python-control in and out: a plant from a ``control.StateSpace``, and every design back as one.

In: :func:`from_statespace` turns a ``control.StateSpace`` (continuous, or discrete at its
``dt``) with the noise and the weights a file would hold into an
:class:`~pendulum_lqg.model.lti.LTIPlant`, through the same schema as a file (every error one line
naming the argument). Out: :func:`plant_statespace` (the plant, continuous or sampled),
:func:`compensator` (the LQG compensator of a built-in policy, ``y → u``),
:func:`closed_loop` (plant and compensator joined).

Sign convention (MATLAB's ``lqgreg``): the compensator's output **is** the plant's input,
``u = −K x̂`` with the observer inside, so the loop is closed with **positive** feedback,
``control.feedback(plant, comp, sign=+1)``. For a compensator ``C(z)`` in the usual negative-feedback
position (``u = −C y``) take ``-comp``. With the current-form estimator

.. math::

    \bar x_{k+1} = (\Phi - \Gamma K)\,\big[(I - LC)\,\bar x_k + L\,y_k\big], \qquad
    u_k = -K (I - LC)\,\bar x_k - K L\,y_k

(the state is the prior ``x̄``; a direct term ``−KL``), and with the predictor form
``x̂_{k+1} = (Φ − ΓK − L_p C) x̂_k + L_p y_k``, ``u_k = −K x̂_k``. The continuous LQG compensator
(:func:`continuous_compensator`) is ``x̂' = (A − BK − LC) x̂ + L y``, ``u = −K x̂``.

``control`` is imported inside the functions (the CLI does not load it at start-up).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from pendulum_lqg.boundary.fields import Where
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.model.lti import LTIPlant, lti_from_mapping


def from_statespace(sys: Any, *, W: Any = None, V: Any = None, Q: Any = None, R: Any = None,
                    N: Any = None, G: Any = None, control_period: float | None = None,
                    name: str = "statespace", **options: Any) -> LTIPlant:
    """An :class:`~pendulum_lqg.model.lti.LTIPlant` from the ``control.StateSpace`` ``sys``.

    Parameters
    ----------
    sys : ``ẋ = A x + B u``, ``y = C x`` (``dt = 0``: continuous, sampled by ZOH at
        ``control_period``) or ``x[k+1] = Φ x + Γ u`` (``dt > 0``: discrete at ``dt``, which is
        then the control period; ``dt = True`` takes ``control_period``). ``D`` must be zero (the
        loop has no direct feedthrough). Its state, input and output labels name x, u, y when
        they are identifiers (python-control's defaults ``x[0]``… are not: then ``x1``…).
    W : (q,) or (q, q) density of the process noise w (units²·s) entering through ``G``
        (default I); for a discrete ``sys`` the covariance of one period's w
    V : (p,) or (p, p) per-sample covariance of the measurement noise
    Q, R, N : weights of ``∫ xᵀQx + 2xᵀNu + uᵀRu dt`` (per sample for a discrete ``sys``);
        default ``CᵀC``, ``I``, none
    control_period : T [s] of a continuous ``sys``
    options : any other key of an LTI file (``force_limit``, ``x0``, ``x0_std``,
        ``observer_poles``, ``state_limits``, ``states``, ``inputs``, ``outputs``,
        ``description``)

    Raises :class:`~pendulum_lqg.errors.ConfigError` (one line naming the argument).
    """
    import control

    if not isinstance(sys, control.StateSpace):
        raise ConfigError(f"sys: expected a control.StateSpace, got {type(sys).__name__}")
    if np.any(np.asarray(sys.D) != 0):
        raise ConfigError("sys: expected D = 0 (no direct feedthrough from u to y), got "
                          f"max |D| = {float(np.max(np.abs(sys.D))):g}")
    dt = sys.dt
    discrete = dt is True or (dt is not None and float(dt) > 0)
    if discrete and dt is not True:
        if control_period is not None and not np.isclose(control_period, float(dt)):
            raise ConfigError(f"control_period: the discrete sys is sampled at {dt:g} s, got "
                              f"{control_period!r}")
        control_period = float(dt)
    if control_period is None:
        raise ConfigError("control_period: expected the sample period T [s] of a "
                          + ("discrete sys with dt = True" if discrete else "continuous sys"))
    data: dict[str, Any] = {"name": name, "control_period": control_period,
                            "C": np.asarray(sys.C, dtype=float)}
    data.update({"Phi": np.asarray(sys.A, dtype=float), "Gamma": np.asarray(sys.B, dtype=float)}
                if discrete else {"A": np.asarray(sys.A, dtype=float),
                                  "B": np.asarray(sys.B, dtype=float)})
    for key, value in (("W", W), ("V", V), ("Q", Q), ("R", R), ("N", N), ("G", G)):
        if value is not None:
            data[key] = np.asarray(value, dtype=float) if not np.isscalar(value) else value
    for key, labels in (("states", sys.state_labels), ("inputs", sys.input_labels),
                        ("outputs", sys.output_labels)):
        if key not in options and all(str(s).isidentifier() for s in labels):
            data[key] = [str(s) for s in labels]
    data.update(options)
    return lti_from_mapping(data, name=name, where=Where("statespace"))


def plant_statespace(plant: LTIPlant, *, discrete: bool = False) -> Any:
    """The plant as a ``control.StateSpace`` (inputs u, outputs y, named as the plant's): its
    continuous ``(A, B, C, 0)``, or with ``discrete`` (always, for a plant given in discrete
    time) the sampled ``(Φ, Γ, C, 0)`` at ``dt = T``."""
    import control

    m, p = plant.n_inputs, plant.n_outputs
    labels = {"states": list(plant.state_names), "inputs": list(plant.input_names),
              "outputs": list(plant.output_names)}
    if discrete or plant.A is None or plant.B is None:
        return control.ss(plant.Phi, plant.Gamma, plant.C, np.zeros((p, m)),
                          plant.control_period, **labels)
    return control.ss(plant.A, plant.B, plant.C, np.zeros((p, m)), **labels)


def compensator(plant: LTIPlant, policy: str | Any = "dlqr+kalman") -> Any:
    """The LQG compensator ``y → u`` of a built-in discrete policy (``dlqr``/``lqr`` +
    ``kalman``/``kalman-predictor``/``luenberger``, or a
    :class:`~pendulum_lqg.policies.lqg.Policy` of one) as a discrete ``control.StateSpace`` at
    ``dt = T``; close the loop with ``control.feedback(plant, comp, sign=+1)`` (module
    docstring). Its state is the estimator's (the prior ``x̄`` in current form, ``x̂`` in
    predictor form)."""
    import control

    from pendulum_lqg.policies.estimators import CurrentEstimator, PredictorEstimator
    from pendulum_lqg.policies.lti import design_lti_policy

    pol = design_lti_policy(plant, policy) if isinstance(policy, str) else policy
    K, est = np.asarray(pol.K), pol.estimator
    Phi, Gamma, C = plant.Phi, plant.Gamma, plant.C
    n, m, p = plant.n_states, plant.n_inputs, plant.n_outputs
    if isinstance(est, CurrentEstimator):
        L = np.asarray(est.gain)
        F = np.eye(n) - L @ C
        A_c, B_c = (Phi - Gamma @ K) @ F, (Phi - Gamma @ K) @ L
        C_c, D_c = -K @ F, -K @ L
    elif isinstance(est, PredictorEstimator):
        L = np.asarray(est.gain)
        A_c, B_c, C_c, D_c = Phi - Gamma @ K - L @ C, L, -K, np.zeros((m, p))
    else:
        raise ConfigError(f"policy: expected an observer (kalman, kalman-predictor, luenberger) "
                          f"for a compensator from y, got {pol.name!r}")
    return control.ss(A_c, B_c, C_c, D_c, plant.control_period,
                      inputs=list(plant.output_names), outputs=list(plant.input_names),
                      name=f"{pol.name}_compensator")


def continuous_compensator(plant: LTIPlant) -> Any:
    """The continuous LQG compensator of ``plant`` (continuous LQR ``K`` and Kalman–Bucy ``L`` of
    :func:`~pendulum_lqg.policies.lti.design_lti_all`): ``x̂' = (A − BK − LC) x̂ + L y``,
    ``u = −K x̂``; close with ``control.feedback(plant_statespace(plant), comp, sign=+1)``."""
    import control

    from pendulum_lqg.policies.lti import design_lti_all

    if plant.A is None or plant.B is None:
        raise ConfigError(f"plant: {plant.name!r} is given in discrete time; it has no "
                          "continuous compensator")
    d = design_lti_all(plant)
    K, L = d["lqr"].K, d["kalman"].L
    return control.ss(plant.A - plant.B @ K - L @ plant.C, L, -K,
                      np.zeros((plant.n_inputs, plant.n_outputs)),
                      inputs=list(plant.output_names), outputs=list(plant.input_names),
                      name="lqg_compensator")


def closed_loop(plant: LTIPlant, policy: str | Any = "dlqr+kalman") -> Any:
    """The sampled plant and the :func:`compensator` of ``policy`` joined,
    ``control.feedback(plant_statespace(plant, discrete=True), comp, sign=+1)``: a discrete
    system from an input added to u to y, whose poles are the LQG loop's (the separation
    principle: ``eig(Φ − ΓK) ∪`` the estimator's)."""
    import control

    return control.feedback(plant_statespace(plant, discrete=True), compensator(plant, policy),
                            sign=1)


def sorted_poles(poles: Sequence[complex] | np.ndarray) -> np.ndarray:
    """Poles in a fixed order (real part, then imaginary), for comparing two lists."""
    z = np.asarray(poles, dtype=complex)
    return z[np.lexsort((z.imag, z.real))]
