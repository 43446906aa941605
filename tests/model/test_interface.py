"""Both plants are a :class:`~pendulum_lqg.model.interface.SimulatedPlant`, with real values: the
cart-pole's linear model is the linearisation's, the LTI plant's sampled model is scipy's
matrix-exponential ZOH, and each plant's fingerprint is its own and stable."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import scipy.linalg

from pendulum_lqg.core.scenario import Scenario
from pendulum_lqg.design import zoh
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.model.interface import Layout, SimulatedPlant, steps_per_period
from pendulum_lqg.model.linearize import linearize
from pendulum_lqg.model.lti import load_lti
from pendulum_lqg.model.overrides import ModelOverrides
from pendulum_lqg.model.plant import load_plant
from pendulum_lqg.policies.lti import lti_scenario


def _expm_zoh(A: np.ndarray, B: np.ndarray, T: float) -> tuple[np.ndarray, np.ndarray]:
    """``(Φ, Γ)`` from ``expm([[A, B], [0, 0]] T)``, written out here (not the package's zoh)."""
    n, m = B.shape
    M = np.zeros((n + m, n + m))
    M[:n, :n], M[:n, n:] = A, B
    E = scipy.linalg.expm(M * T)
    return E[:n, :n], E[:n, n:]


def test_both_plants_are_simulated_plants():
    cartpole = load_plant()
    lti = load_lti("experiments/lti/double_integrator.toml")
    for plant in (cartpole, lti):
        assert isinstance(plant, SimulatedPlant)
    assert not isinstance(object(), SimulatedPlant)
    assert cartpole.simulators == ("mujoco", "linear-zoh", "linear-euler")
    assert lti.simulators == ("linear-zoh",)


def test_the_cartpole_linear_model_is_the_linearisation():
    plant = load_plant()
    lin, model = linearize(plant), plant.linear_model()
    for got, want in zip((model.A, model.B, model.C, model.D, model.F),
                         (lin.A, lin.B, lin.C, lin.D, lin.F), strict=True):
        np.testing.assert_array_equal(got, want)
    Phi, Gamma = plant.sampled(0.02)
    want_Phi, want_Gamma = zoh(lin.A, lin.B, 0.02)
    np.testing.assert_array_equal(Phi, want_Phi)
    np.testing.assert_array_equal(Gamma, want_Gamma)
    Phi, Gamma = plant.sampled(0.02, "linear-euler")
    np.testing.assert_allclose(Phi, np.eye(4) + 0.02 * lin.A, rtol=0, atol=1e-15)
    np.testing.assert_allclose(Gamma, 0.02 * lin.B, rtol=0, atol=1e-15)
    with pytest.raises(ConfigError, match=r"^plant: expected 'linear-zoh' or 'linear-euler'"):
        plant.sampled(0.02, "mujoco")


def test_the_lti_plant_samples_like_scipy_expm():
    plant = load_lti("experiments/lti/two_mass.toml")
    model = plant.linear_model()
    A, B, C, D = model.A, model.B, model.C, model.D
    assert model.F is None                      # a matrix plant has no joint forces
    np.testing.assert_array_equal(A, plant.A)
    np.testing.assert_array_equal(C, plant.C)
    np.testing.assert_array_equal(D, np.zeros((plant.n_outputs, plant.n_inputs)))
    T = plant.control_period
    Phi, Gamma = plant.sampled(T)
    want_Phi, want_Gamma = _expm_zoh(A, B, T)
    np.testing.assert_allclose(Phi, want_Phi, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(Gamma, want_Gamma, rtol=1e-10, atol=1e-12)
    Phi2, Gamma2 = plant.sampled(T / 2)                  # another period: from (A, B)
    want_Phi, want_Gamma = _expm_zoh(A, B, T / 2)
    np.testing.assert_allclose(Phi2, want_Phi, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(Gamma2, want_Gamma, rtol=1e-10, atol=1e-12)


def test_a_discrete_lti_plant_has_no_continuous_model():
    plant = load_lti("experiments/lti/ogata_discrete.toml")
    assert plant.discrete
    Phi, Gamma = plant.sampled(plant.control_period)
    assert Phi is plant.Phi and Gamma is plant.Gamma
    with pytest.raises(ConfigError, match=r"^A: the LTI plant .* is given in discrete time"):
        plant.linear_model()


def test_layouts_and_limits_come_from_the_plant():
    cartpole = load_plant()
    scenario = Scenario()
    lay = cartpole.layout(scenario)
    assert isinstance(lay, Layout)
    assert lay.states == ("p", "theta", "p_dot", "theta_dot") and lay.C is None
    assert cartpole.limits(scenario) == (scenario.theta_max, cartpole.track_limit, cartpole.u_max)
    lti = load_lti("experiments/lti/double_integrator.toml")
    sc = lti_scenario(lti)
    lay = lti.layout(sc)
    assert lay.states == lti.state_names and lay.n == lti.n_states and lay.settle is None
    theta_max, track, u_max = lti.limits(sc)
    assert math.isinf(theta_max) and math.isinf(track) and u_max == lti.u_max
    with pytest.raises(ConfigError, match=r"^plant: an LTI plant runs as its own exact sampled"):
        lti.layout(sc.replace(plant="linear-euler"))


def test_fingerprints_differ_between_plants_and_are_stable():
    cartpole, heavier = load_plant(), load_plant(overrides=ModelOverrides(pole_mass_scale=1.1))
    di = load_lti("experiments/lti/double_integrator.toml")
    two = load_lti("experiments/lti/two_mass.toml")
    prints = [p.fingerprint() for p in (cartpole, heavier, di, two)]
    assert len(set(prints)) == 4
    assert all(len(p) == 64 and int(p, 16) >= 0 for p in prints)
    assert load_plant().fingerprint() == prints[0]                  # stable across loads
    assert load_lti("experiments/lti/double_integrator.toml").fingerprint() == prints[2]
    moved = dataclasses.replace(di, x0=np.asarray(di.x0) + 1.0)
    assert moved.fingerprint() != prints[2]


def test_steps_per_period_is_the_interface_s_and_the_detours_are_gone():
    import importlib.util

    from pendulum_lqg.core.noise import NoiseModel
    from pendulum_lqg.model import plant as model_plant

    assert not hasattr(model_plant, "steps_per_period")           # no re-export
    assert not hasattr(model_plant.Plant, "get_state")
    assert not hasattr(NoiseModel, "n_process")
    for gone in ("pendulum_lqg.core.layout", "pendulum_lqg.core.defaults"):
        assert importlib.util.find_spec(gone) is None, gone
    assert steps_per_period(load_plant(), 0.02) == round(0.02 / load_plant().timestep)


def test_the_physics_factory_steps_a_plant_only_by_its_simulators():
    from pendulum_lqg.core.physics import LinearPhysics, make_physics

    lti = load_lti("experiments/lti/two_mass.toml")
    with pytest.raises(ConfigError, match=r"^plant: expected one of linear-zoh for this plant, "
                                          r"got 'mujoco'$"):
        make_physics(lti, plant_kind="mujoco", backend="rollout", capacity=1, nthread=1, k=1)
    physics = make_physics(lti, plant_kind="linear-zoh", backend="rollout", capacity=1,
                           nthread=1, k=1)
    assert isinstance(physics, LinearPhysics)
    np.testing.assert_array_equal(physics.Phi, lti.Phi)
    np.testing.assert_array_equal(physics.Gamma, lti.Gamma)        # two inputs: Γ (n, m)
