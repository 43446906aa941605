"""The one adapter from msgspec's errors to ``FILE: key.path: expected …, got …``."""

from __future__ import annotations

import pytest

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.problem.errors import convert
from pendulum_lqg.problem.scenario import ScenarioSettings


@pytest.mark.parametrize(("table", "message"), [
    ({"duration": 0}, "e.toml: scenario: duration: expected a finite positive number, got 0"),
    ({"x0": [1, 2]}, "e.toml: scenario: x0: expected 4 finite numbers, got [1, 2]"),
    ({"dropout": 1.0}, "e.toml: scenario: dropout: expected a probability in [0, 1), got 1.0"),
    ({"estimate0": "one"}, "e.toml: scenario: estimate0: expected 'zero' or 'true', got 'one'"),
    ({"burn_in": True}, "e.toml: scenario: burn_in: expected a finite number ≥ 0, got True"),
    ({"duraton": 1}, "e.toml: scenario: duraton: unknown key; known keys: control_period, "),
])
def test_a_bad_value_is_one_line_naming_file_and_key(table, message):
    with pytest.raises(ConfigError) as exc:
        convert(table, ScenarioSettings, where="e.toml: scenario")
    assert str(exc.value).startswith(message)


def test_a_good_table_converts_to_the_declared_types():
    s = convert({"x0": [0, 0.2, 0, 0], "theta_max": 1}, ScenarioSettings)
    assert s.x0 == (0.0, 0.2, 0.0, 0.0) and s.theta_max == 1.0 and s.duration == 10.0
