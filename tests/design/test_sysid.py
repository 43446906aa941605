"""Nominal identification (pendulum_lqg.design.sysid) against the true linearised cart-pole: the
model it recovers from noise-free and noisy episodes, and the LQG it designs from the true model
against the built-in dlqr+kalman (two paths to one design)."""

from __future__ import annotations

import numpy as np
import pytest

from pendulum_lqg.design.sysid import (
    IdentifiedModel,
    identify,
    lqg_gains,
    markov_parameters,
)


@pytest.fixture(scope="module")
def truth():
    from pendulum_lqg.policies.loading import PolicyContext
    from pendulum_lqg.scoreboard.suites import load_suite

    suite = load_suite("lecture")
    return PolicyContext.build(suite.plants()[1], suite.config.scenario)


def _episodes(ctx, episodes, horizon, *, w_std, v_std, seed=0):
    """Open-loop episodes of the true (Φ, Γ, C) from x₀ = [0, 0.1, 0, 0], inputs ±5 N."""
    rng = np.random.default_rng(seed)
    x = np.tile([0.0, 0.1, 0.0, 0.0], (episodes, 1))
    Y, U = np.zeros((episodes, horizon, 2)), rng.choice([-5.0, 5.0], size=(episodes, horizon, 1))
    for k in range(horizon):
        Y[:, k] = x @ ctx.C.T + v_std * rng.standard_normal((episodes, 2))
        x = x @ ctx.Phi.T + U[:, k] @ ctx.Gamma.T + w_std * rng.standard_normal((episodes, 4))
    return Y, U, np.ones((episodes, horizon), dtype=bool)


def _markov(Phi, Gamma, C, count):
    return np.array([C @ np.linalg.matrix_power(Phi, j) @ Gamma for j in range(count)])


def test_noise_free_episodes_give_the_true_model(truth):
    Y, U, valid = _episodes(truth, 30, 12, w_std=0.0, v_std=0.0)
    G, _, residuals = markov_parameters(Y, U, valid)
    np.testing.assert_allclose(G, _markov(truth.Phi, truth.Gamma, truth.C, 11), atol=1e-12)
    assert np.abs(residuals).max() < 1e-12
    model = identify(Y, U, valid, truth.dt)
    # the basis [y, ẏ] is the true model's own: the matrices themselves, not only eigenvalues
    np.testing.assert_allclose(model.A, truth.A, atol=1e-6)
    np.testing.assert_allclose(model.B, truth.B, atol=1e-8)
    np.testing.assert_allclose(model.Phi, truth.Phi, atol=1e-9)
    np.testing.assert_array_equal(model.C, truth.C)


def test_noisy_episodes_give_the_unstable_pole_and_the_noise_within_tolerance(truth):
    """120 000 samples: the unstable pole and b within 10 %, the noise covariances within 5 % (V)
    and a factor 2 (W)."""
    # the lecture's noise: per-period state noise 4e-6 (std 0.002), measurement std 0.1
    Y, U, valid = _episodes(truth, 4000, 30, w_std=0.002, v_std=0.1, seed=1)
    model = identify(Y, U, valid, truth.dt)
    unstable = np.sqrt(truth.A[3, 1])                         # 3.97 rad/s
    poles = np.linalg.eigvals(model.A).real
    assert abs(poles.max() - unstable) < 0.1 * unstable
    np.testing.assert_allclose(model.B[2:, 0], truth.B[2:, 0], rtol=0.1)
    # Markov parameters over the horizon the data cover, within 5 % of the largest
    G_hat = _markov(model.Phi, model.Gamma, model.C, 29)
    G = _markov(truth.Phi, truth.Gamma, truth.C, 29)
    assert np.abs(G_hat - G).max() < 0.05 * np.abs(G).max()
    np.testing.assert_allclose(np.diag(model.V), [0.01, 0.01], rtol=0.05)
    assert 2e-6 < model.W[0, 0] < 8e-6


def test_lqg_on_the_true_model_is_the_builtin_design(truth):
    from pendulum_lqg.policies.loading import build_policy
    from pendulum_lqg.scoreboard.suites import load_suite

    suite = load_suite("lecture")
    sc = suite.config.scenario
    builtin = build_policy("dlqr+kalman", plant=suite.plants()[1], scenario=sc)
    model = IdentifiedModel(Phi=truth.Phi, Gamma=truth.Gamma, C=truth.C, A=truth.A, B=truth.B,
                            W=builtin.info["noise_Qd"], V=builtin.info["noise_V"],
                            markov=np.zeros((0, 2, 1)), dt=truth.dt)
    K, L = lqg_gains(model, np.diag(sc.cost_Q), np.array([[sc.cost_R]]))
    np.testing.assert_allclose(K, builtin.info["K"], rtol=1e-12)
    np.testing.assert_allclose(L, builtin.info["L"], rtol=1e-12)
