"""Timing bounds of a scenario from the Python API, checked before any loop starts."""

from __future__ import annotations

import pytest

from pendulum_lqg.errors import ConfigError


def test_timing_bounds_from_the_python_api():
    from pendulum_lqg.model.interface import steps_per_period
    from pendulum_lqg.model.overrides import ModelOverrides
    from pendulum_lqg.model.plant import load_plant
    from pendulum_lqg.util.limits import (
        MAX_CONTROL_PERIOD,
        MAX_PERIODS,
        MAX_STEPS_PER_PERIOD,
        check_duration,
    )

    plant = load_plant()
    assert steps_per_period(plant, MAX_CONTROL_PERIOD) == round(MAX_CONTROL_PERIOD / 1e-3)
    with pytest.raises(ConfigError, match=r"^control_period: expected at most 1 s"):
        steps_per_period(plant, 1.001)
    with pytest.raises(ConfigError, match=r"^control_period: expected a finite positive number"):
        steps_per_period(plant, 0.01 + 0j)
    fine = load_plant(overrides=ModelOverrides(timestep=1e-5))   # 1 s = 100 000 steps of 10 µs
    assert steps_per_period(fine, MAX_STEPS_PER_PERIOD * 1e-5) == MAX_STEPS_PER_PERIOD
    with pytest.raises(ConfigError, match=r"^control_period: expected at most 10000 physics"):
        steps_per_period(fine, 0.5)
    assert check_duration(MAX_PERIODS * 0.01, 0.01) == MAX_PERIODS * 0.01
    for bad in (1e308, MAX_PERIODS * 0.0101, float("inf"), -1.0, True, "10"):
        with pytest.raises(ConfigError, match=r"^duration: expected"):
            check_duration(bad, 0.01)


def test_a_run_with_an_endless_duration_is_refused_before_the_loop():
    from pendulum_lqg.core.scenario import Scenario
    from pendulum_lqg.model.plant import load_plant
    from pendulum_lqg.policies.loading import build_policy

    with pytest.raises(ConfigError, match=r"^duration: expected at most"):
        build_policy("dlqr+kalman", plant=load_plant(), scenario=Scenario(duration=1e300))


# ---- 2. the design API under garbage input -----------------------------------------------------


@pytest.mark.parametrize(("T", "message"), [
    (1e-320, "control_period: expected at least 1e-06 s (the floor), got 1e-320 s"),
    (1e-7, "control_period: expected at least 1e-06 s (the floor), got 1e-07 s"),
    (2.0, "control_period: expected at most 1 s (the ceiling), got 2.0 s"),
])
def test_a_control_period_out_of_bounds_is_blamed_before_the_duration(T, message):
    from pendulum_lqg.core.scenario import Scenario

    with pytest.raises(ConfigError) as err:
        Scenario(control_period=T)                 # the default 10 s would be > 10⁸ periods
    assert str(err.value) == message
