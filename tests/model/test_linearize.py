"""Linearisation of the MuJoCo model: finite differences vs analytic rigid body vs ZOH/transitionFD."""

from __future__ import annotations

import numpy as np
import pytest

from pendulum_lqg import design
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.model.linearize import (
    analytic_linearization,
    discretize_transition,
    discretize_zoh,
    linearize,
    steps_per_period,
)
from pendulum_lqg.model.overrides import ModelOverrides
from pendulum_lqg.model.plant import load_plant


def _rel(a, b):
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def test_model_parameters_come_from_the_xml(plant):
    p = plant.parameters()
    assert p["cart_mass"] == pytest.approx(1.0)
    assert p["pole_mass"] == pytest.approx(0.1)
    assert p["pole_length"] == pytest.approx(1.0)
    assert p["pole_com"] == pytest.approx(0.5)
    # uniform cylinder rod of radius 0.015 m: I = m (3r² + L²) / 12 about its centre
    assert p["pole_inertia_com"] == pytest.approx(0.1 * (3 * 0.015**2 + 1.0) / 12, rel=1e-12)
    assert p["gravity"] == pytest.approx(9.81)
    assert p["force_limit"] == 10.0 and p["track_limit"] == 2.4 and p["timestep"] == 0.001


@pytest.mark.parametrize("overrides", [ModelOverrides(),
                                       ModelOverrides(pole_mass_scale=2.0, pole_length_scale=0.5),
                                       ModelOverrides(cart_mass=3.0, pole_length=2.0)])
def test_finite_differences_match_analytic_rigid_body(overrides):
    plant = load_plant(overrides=overrides)
    fd, an = linearize(plant), analytic_linearization(plant)
    assert _rel(fd.A, an.A) < 1e-3 and _rel(fd.B, an.B) < 1e-3
    # in fact they agree to finite-difference precision
    assert _rel(fd.A, an.A) < 1e-8 and _rel(fd.B, an.B) < 1e-8
    np.testing.assert_allclose(fd.C, np.hstack([np.eye(2), np.zeros((2, 2))]), atol=1e-9)
    np.testing.assert_allclose(fd.D, 0.0, atol=1e-9)
    np.testing.assert_allclose(fd.F, an.F, rtol=1e-7, atol=1e-9)


def test_classic_cartpole_numbers(plant):
    """Closed form for a uniform rod: θ̈ = (m_c+m_p) g l θ / det M₀ etc."""
    lin = linearize(plant)
    mc, mp, lc, Ip, g = 1.0, 0.1, 0.5, 0.1 * (3 * 0.015**2 + 1.0) / 12, 9.81
    det = (mc + mp) * (Ip + mp * lc**2) - (mp * lc) ** 2
    assert lin.A[3, 1] == pytest.approx((mc + mp) * mp * g * lc / det, rel=1e-8)
    assert lin.A[2, 1] == pytest.approx(-(mp * lc) ** 2 * g / det, rel=1e-8)
    assert lin.B[2, 0] == pytest.approx((Ip + mp * lc**2) / det, rel=1e-8)
    assert lin.B[3, 0] == pytest.approx(-mp * lc / det, rel=1e-8)
    s = np.sort(np.linalg.eigvals(lin.A).real)
    np.testing.assert_allclose(s, [-np.sqrt(lin.A[3, 1]), 0, 0, np.sqrt(lin.A[3, 1])], atol=1e-6)


@pytest.mark.parametrize("dt", [0.001, 0.01, 0.05])
def test_zoh_agrees_with_composed_transition_fd(plant, dt):
    """Stated tolerance: the Euler integrator's O(h) error, |ΔΦ| ≤ 2·h·|A|·‖Φ−I‖ and Γ to 0.2 %."""
    z = discretize_zoh(linearize(plant), dt)
    t = discretize_transition(plant, dt)
    h = plant.timestep
    assert np.max(np.abs(z.Phi - t.Phi)) <= 2 * h * np.max(np.abs(linearize(plant).A)) * \
        np.max(np.abs(z.Phi - np.eye(4))) + 1e-9
    assert _rel(t.Gamma, z.Gamma) < 2e-3
    assert t.dt == pytest.approx(dt)


def test_control_period_must_be_a_multiple_of_the_step(plant):
    assert steps_per_period(plant, 0.01) == 10
    for bad in (0.0105, -0.01, 0.0, float("nan")):
        with pytest.raises(ConfigError, match="control_period"):
            steps_per_period(plant, bad)


def test_structure_of_the_cartpole(plant):
    st = linearize(plant).structure()
    assert st.controllability_rank == 4 and st.observability_rank == 4
    assert st.stabilizable and st.detectable
    assert st.uncontrollable_modes == () and st.unobservable_modes == ()
    # measuring the angle alone loses the cart position: (A, [0 1 0 0]) is not observable
    lin = linearize(plant)
    st2 = design.structure(lin.A, lin.B, [[0, 1, 0, 0]])
    assert st2.observability_rank == 2 and not st2.detectable
    assert any(abs(m) < 1e-9 for m in st2.unobservable_modes)


def test_separation_principle_on_the_cartpole(plant):
    lin = linearize(plant)
    z = discretize_zoh(lin, 0.01)
    K = design.lqr(lin.A, lin.B, np.eye(4), 1.0).K
    L = design.luenberger(lin.A, lin.C, design.DEFAULT_OBSERVER_POLES).L
    res = design.lqg(lin.A, lin.B, lin.C, K, L)
    assert res.separation_error < 1e-8
    Kd = design.dlqr(z.Phi, z.Gamma, np.eye(4), 1.0).K
    Ld = design.dkalman(z.Phi, np.eye(4), z.C, 4e-6 * np.eye(4), 0.01 * np.eye(2)).L
    res_d = design.lqg(z.Phi, z.Gamma, z.C, Kd, Ld, form="current")
    assert res_d.separation_error < 1e-9
    assert np.all(np.abs(res_d.poles) < 1)


def test_model_overrides_and_errors(tmp_path):
    heavy = load_plant(overrides=ModelOverrides(pole_mass=0.2, pole_length_scale=2.0,
                                                force_limit=20.0))
    assert heavy.pole_mass == pytest.approx(0.2)
    assert heavy.pole_length == pytest.approx(2.0) and heavy.pole_com == pytest.approx(1.0)
    assert heavy.u_max == 20.0
    with pytest.raises(ConfigError, match="pole_mass: expected a finite positive number"):
        ModelOverrides(pole_mass=-1.0)
    with pytest.raises(ConfigError, match="pole_mass: give either pole_mass or pole_mass_scale"):
        ModelOverrides(pole_mass=1.0, pole_mass_scale=2.0)
    with pytest.raises(ConfigError, match="model: unknown key 'pole_mas'; known keys: pole_mass"):
        ModelOverrides.from_mapping({"pole_mas": 1.0})
    with pytest.raises(ConfigError, match="model: file not found"):
        load_plant(tmp_path / "missing.xml")
    bad = tmp_path / "bad.xml"
    bad.write_text("<mujoco><worldbody><body></mujoco>")
    with pytest.raises(ConfigError, match="model: cannot parse"):
        load_plant(bad)
