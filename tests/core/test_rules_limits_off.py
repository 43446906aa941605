"""Limits that can be switched off: ``theta_max``, ``track_limit`` and ``force_limit`` at ``inf``
(Scenario, rules.limits, the loop, the Gymnasium keywords)."""

from __future__ import annotations

import numpy as np
import pytest

from pendulum_lqg.core import rules
from pendulum_lqg.core.loop import Simulator
from pendulum_lqg.core.scenario import Scenario
from pendulum_lqg.core.seeding import episode_generators
from pendulum_lqg.errors import ConfigError

INF = float("inf")


def test_limits_default_to_the_model_and_accept_inf(plant):
    assert rules.limits(plant, Scenario()) == (0.5, plant.track_limit, plant.u_max) == (0.5, 2.4, 10)
    sc = Scenario(plant="linear-zoh", theta_max=INF, track_limit="inf", force_limit=INF)
    assert rules.limits(plant, sc) == (INF, INF, INF)
    assert rules.limits(plant, Scenario(track_limit=1.0, force_limit=5))[1:] == (1.0, 5.0)
    d = sc.to_dict()                     # JSON has no ∞ and null means "the model's": "inf"
    assert (d["theta_max"], d["track_limit"], d["force_limit"]) == ("inf", "inf", "inf")
    assert Scenario(**{k: d[k] for k in ("plant", "theta_max", "track_limit")}) == \
        sc.replace(force_limit=None)
    assert Scenario().to_dict()["track_limit"] is None


@pytest.mark.parametrize("field, value", [("theta_max", 0), ("theta_max", -INF),
                                          ("track_limit", float("nan")), ("force_limit", "big"),
                                          ("force_limit", True)])
def test_bad_limits_name_the_field(field, value):
    with pytest.raises(ConfigError, match=f"^{field}: expected a positive number or inf"):
        Scenario(**{field: value})


def test_mujoco_refuses_limits_its_physics_cannot_reach(plant):
    with pytest.raises(ConfigError, match="track_limit: inf is beyond the MuJoCo model's slider"):
        Simulator(plant, Scenario(track_limit=INF))
    with pytest.raises(ConfigError, match="force_limit: 20 is beyond"):
        Simulator(plant, Scenario(force_limit=20))


def test_unbounded_linear_loop_neither_saturates_nor_fails(plant):
    """A 100 N push far beyond the ±2.4 m track and θ_max: with every limit off the linear plant
    runs on, and the force is applied as requested."""
    sc = Scenario(plant="linear-zoh", theta_max=INF, track_limit=INF, force_limit=INF,
                  duration=2.0, noise=Scenario().noise.with_scale(0.0))
    with Simulator(plant, sc, backend="step") as sim:
        sim.reset(episode_generators([0]))
        for _ in range(sim.n_periods):
            sim.measure()
            res = sim.step(np.array([100.0]))
            assert res.requested[0] == 100.0 and not res.failed[0]
        assert abs(sim.x[0, 0]) > 2.4 and abs(sim.x[0, 1]) > 0.5
    with Simulator(plant, sc.replace(force_limit=None), backend="step") as sim:
        sim.reset(episode_generators([0]))
        sim.measure()
        assert sim.step(np.array([100.0])).requested[0] == plant.u_max


def test_gymnasium_keywords_switch_limits_off():
    import gymnasium as gym

    import pendulum_lqg

    env = gym.make(pendulum_lqg.ENV_ID, plant="linear-euler", theta_max=INF, track_limit=INF,
                   force_limit=INF)
    assert env.action_space.high[0] == np.inf
    env.reset(seed=0)
    _, _, terminated, _, info = env.step(np.array([1e3], dtype=np.float32))
    assert not terminated and info["force"] == 1e3
    with pytest.raises(ConfigError, match="normalize_action: needs a finite force_limit"):
        gym.make(pendulum_lqg.ENV_ID, plant="linear-euler", force_limit=INF,
                 normalize_action=True)
