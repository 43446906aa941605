"""python-control in and out (:mod:`pendulum_lqg.policies.control_io`): a plant from a
``control.StateSpace``, its designs checked against python-control's own ``lqr``, ``dlqr``,
``lqe``, ``dlqe`` on random plants, and the compensator closed on the plant with
``control.feedback`` giving the loop eigenvalues ``design --lti`` reports."""

from __future__ import annotations

from pathlib import Path

import control
import numpy as np
import pytest

from pendulum_lqg import design
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.model.lti import load_lti
from pendulum_lqg.policies.control_io import (
    closed_loop,
    compensator,
    continuous_compensator,
    from_statespace,
    plant_statespace,
    sorted_poles,
)
from pendulum_lqg.policies.lti import design_lti_all

EXPERIMENTS = Path(__file__).resolve().parents[2] / "experiments" / "lti"


def random_plant(seed: int, n: int = 4, m: int = 2, p: int = 2):
    """A random (A, B, C) with a seeded generator (controllable and observable with probability
    one, so stabilisable and detectable), its noise and weights: full Q, a small cross term."""
    rng = np.random.default_rng(seed)
    A, B, C = rng.normal(size=(n, n)), rng.normal(size=(n, m)), rng.normal(size=(p, n))
    F = rng.normal(size=(n, n))
    Q = F @ F.T + np.eye(n)
    R = np.diag(rng.uniform(0.5, 2.0, m))
    N = 0.1 * rng.normal(size=(n, m))
    W = np.diag(rng.uniform(0.1, 1.0, n))
    V = np.diag(rng.uniform(0.01, 0.1, p))
    return control.ss(A, B, C, np.zeros((p, m))), dict(Q=Q, R=R, N=N, W=W, V=V)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_continuous_designs_match_python_controls_lqr_and_lqe(seed):
    sys, w = random_plant(seed)
    T = 0.05
    plant = from_statespace(sys, control_period=T, **w)
    d = design_lti_all(plant)
    K, _, _ = control.lqr(sys.A, sys.B, w["Q"], w["R"], w["N"])
    np.testing.assert_allclose(d["lqr"].K, K, rtol=1e-8, atol=1e-10)
    # Kalman–Bucy: process density W through G = I, measurement density V·T
    L, _, _ = control.lqe(sys.A, np.eye(4), sys.C, w["W"], w["V"] * T)
    np.testing.assert_allclose(d["kalman"].L, L, rtol=1e-8, atol=1e-10)
    Qd, Rd, Nd = design.sampled_cost(sys.A, sys.B, w["Q"], w["R"], T, N=w["N"])
    Kd, _, _ = control.dlqr(plant.Phi, plant.Gamma, Qd, Rd, Nd)
    np.testing.assert_allclose(d["dlqr"].K, Kd, rtol=1e-8, atol=1e-10)


@pytest.mark.parametrize("seed", [3, 4])
def test_discrete_designs_match_dlqr_and_dlqe_in_predictor_and_filter_form(seed):
    """A discrete StateSpace at its dt: dlqr on its own Q, R, N; python-control's dlqe gives
    the predictor gain ``L_pred`` (x̂[k+1|k] = Φ x̂[k|k−1] + Γu + L_pred (y − C x̂[k|k−1])) and
    the prior covariance M, from which the filter gain is ``L = M Cᵀ (C M Cᵀ + V)⁻¹``."""
    sys_c, w = random_plant(seed)
    sys = control.c2d(sys_c, 0.1)
    plant = from_statespace(sys, **w)
    assert plant.discrete and plant.control_period == 0.1
    d = design_lti_all(plant)
    K, _, _ = control.dlqr(sys.A, sys.B, w["Q"], w["R"], w["N"])
    np.testing.assert_allclose(d["dlqr"].K, K, rtol=1e-8, atol=1e-10)
    L_pred, M, _ = control.dlqe(sys.A, np.eye(4), sys.C, w["W"], w["V"])
    kf = d["dkalman"]
    np.testing.assert_allclose(kf.L_pred, L_pred, rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(kf.M, M, rtol=1e-8, atol=1e-10)
    C, V = sys.C, w["V"]
    np.testing.assert_allclose(kf.L, M @ C.T @ np.linalg.inv(C @ M @ C.T + V), rtol=1e-8,
                               atol=1e-10)


@pytest.mark.parametrize("policy", ["dlqr+kalman", "dlqr+kalman-predictor", "dlqr+luenberger"])
def test_statespace_in_compensator_out_feedback_has_the_reported_eigenvalues(policy):
    """Acceptance: plant in as a StateSpace, compensator out, ``control.feedback(plant, comp,
    sign=+1)`` has the eigenvalues of the LQG loop: ``design --lti``'s separation poles (filter
    form), and for every form ``eig(Φ − ΓK) ∪ eig`` of the estimator's error dynamics."""
    sys, w = random_plant(7)
    plant = from_statespace(sys, control_period=0.05, **w)
    comp = compensator(plant, policy)
    loop = control.feedback(plant_statespace(plant, discrete=True), comp, sign=1)
    poles = sorted_poles(loop.poles())
    d = design_lti_all(plant)
    K = d["dlqr"].K
    C, Phi, Gamma = plant.C, plant.Phi, plant.Gamma
    L = {"dlqr+kalman": d["dkalman"].L_pred, "dlqr+kalman-predictor": d["dkalman"].L_pred,
         "dlqr+luenberger": Phi @ d["dluenberger"].L}[policy]      # current form: error Φ − ΦLC
    expected = sorted_poles(np.concatenate([np.linalg.eigvals(Phi - Gamma @ K),
                                            np.linalg.eigvals(Phi - L @ C)]))
    np.testing.assert_allclose(poles, expected, rtol=0, atol=1e-9)
    if policy == "dlqr+kalman":
        np.testing.assert_allclose(poles, sorted_poles(d["dlqg"].poles), rtol=0, atol=1e-9)
        np.testing.assert_allclose(sorted_poles(closed_loop(plant, policy).poles()), poles,
                                   rtol=0, atol=1e-12)


def test_continuous_compensator_closes_to_the_continuous_lqg_poles_and_has_margins():
    plant = load_lti(EXPERIMENTS / "double_integrator.toml")
    comp = continuous_compensator(plant)
    loop = control.feedback(plant_statespace(plant), comp, sign=1)
    d = design_lti_all(plant)
    np.testing.assert_allclose(sorted_poles(loop.poles()), sorted_poles(d["lqg"].poles),
                               rtol=0, atol=1e-9)
    # the loop broken at the input: L(s) = −comp(s)·P(s); its gain margin at the phase
    # crossover is 1/|L(jω)|, which python-control's margin reports
    gm, pm, wcg, _ = control.margin(-comp * plant_statespace(plant))
    Ljw = (-comp * plant_statespace(plant))(1j * wcg)
    assert gm == pytest.approx(1 / abs(complex(np.squeeze(Ljw))), rel=1e-6)
    assert 0 < pm < 180


def test_plant_statespace_round_trip_and_labels():
    plant = load_lti(EXPERIMENTS / "two_mass.toml")
    sys = plant_statespace(plant)
    assert sys.state_labels == ["p1", "p2", "v1", "v2"] and sys.input_labels == ["f1", "f2"]
    again = from_statespace(sys, control_period=plant.control_period, W=plant.W, V=plant.V,
                            Q=plant.Q, R=plant.R, G=plant.G)
    np.testing.assert_array_equal(again.Phi, plant.Phi)
    assert again.state_names == plant.state_names and again.input_names == ("f1", "f2")
    sysd = plant_statespace(plant, discrete=True)
    assert sysd.dt == plant.control_period
    np.testing.assert_array_equal(sysd.A, plant.Phi)


@pytest.mark.parametrize("make, kwargs, message", [
    (lambda: control.ss([[0.0]], [[1.0]], [[1.0]], [[1.0]]), {"control_period": 0.1},
     "sys: expected D = 0"),
    (lambda: control.ss([[0.0]], [[1.0]], [[1.0]], [[0.0]]), {}, "control_period: expected"),
    (lambda: control.ss([[0.5]], [[1.0]], [[1.0]], [[0.0]], 0.1), {"control_period": 0.2},
     "control_period: the discrete sys is sampled at 0.1 s"),
    (lambda: control.tf([1], [1, 1]), {"control_period": 0.1}, "sys: expected a control"),
    (lambda: control.ss([[0.0]], [[1.0]], [[1.0]], [[0.0]]), {"control_period": 0.1,
                                                               "R": "one"},
     "statespace: R: expected numbers"),
])
def test_bad_statespace_inputs_name_the_argument(make, kwargs, message):
    with pytest.raises(ConfigError, match=message):
        from_statespace(make(), **kwargs)
