"""A plant's own suite (pendulum_lqg.scoreboard.lti_suite.plant_suite): its definition, the
two-mass suite file as one, what it answers the learning methods, and linear controller files of
any number of outputs (their schema's one-line refusals)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.scoreboard.lti_suite import PLANT_SUITE, load_lti_suite, plant_suite

ROOT = Path(__file__).resolve().parents[2]


def test_the_plant_suite_of_a_name():
    s = plant_suite("double-cartpole")
    assert (s.name, s.reference, s.episodes, s.seed, s.version) == (
        "double-cartpole", "dlqr+kalman", 100, 2026, 1)
    assert s.scenario == PLANT_SUITE["scenario"] and s.lti_file == ROOT / "models" / \
        "double_cartpole.toml"
    assert s.env == {"plant": "double-cartpole", "duration": 10.0, "noise_scale": 1.0}
    sc = s.config.scenario
    assert sc.control_period == 0.01 and sc.duration == 10.0 and sc.estimate0 == "zero"
    simulated, design = s.plants()
    assert simulated is not design and design.layout(sc).p == 3 and design.layout(sc).n == 6


def test_the_two_mass_suite_file_is_its_plant_suite():
    by_file = load_lti_suite(ROOT / "experiments" / "lti" / "two_mass_suite.toml")
    by_plant = plant_suite(str(ROOT / "experiments" / "lti" / "two_mass.toml"))
    assert by_plant.fingerprint() == by_file.fingerprint()
    assert by_plant.lti_file == by_file.lti_file


def test_the_cartpole_has_no_plant_suite():
    with pytest.raises(ConfigError, match=r"^--plant: the cart-pole's suites are the shipped"):
        plant_suite("cartpole")


@pytest.mark.parametrize(("form", "message"), [
    ({"form": "history", "history": {"frames": 2, "weights": [0.0] * 5, "mean": [0.0] * 5,
                                     "std": [1.0] * 5}},
     "history.weights: expected frames × (outputs + 1) numbers, 2 × q with q ≥ 2"),
    ({"form": "history", "history": {"frames": 2, "weights": [0.0] * 2, "mean": [0.0] * 2,
                                     "std": [1.0] * 2}}, "got 2"),
    ({"form": "state_space", "state_space": {"A": [[0.0]], "B": [[1.0]], "C": [[1.0]],
                                             "D": [[0.0]]}},
     "state_space.B: expected n × q with q ≥ 2 columns"),
    ({"form": "state_space", "state_space": {"A": [[0.0]], "B": [[1.0, 0.0, 0.0, 0.0]],
                                             "C": [[1.0]], "D": [[0.0, 0.0, 0.0]]}},
     "state_space.D: expected a list of 1 whose items are each a list of 4"),
])
def test_a_linear_file_of_inconsistent_sizes_is_one_line(form, message, tmp_path):
    from pendulum_lqg.boundary.schemas import linear_controller

    path = tmp_path / "c.json"
    path.write_text(json.dumps({"format": "pendulum-lqg linear controller", "version": 1,
                                "action_scale": 1.0, **form}))
    with pytest.raises(ConfigError) as err:
        linear_controller(path, where_text="agent")
    assert message in str(err.value) and "\n" not in str(err.value)


def test_a_four_input_file_reads_its_outputs(tmp_path):
    from pendulum_lqg.boundary.schemas import linear_controller, linear_inputs

    path = tmp_path / "c.json"
    path.write_text(json.dumps({"format": "pendulum-lqg linear controller", "version": 1,
                                "action_scale": 1.0, "form": "history",
                                "history": {"frames": 3, "weights": [0.0] * 12,
                                            "mean": [0.0] * 12, "std": [1.0] * 12}}))
    assert linear_inputs(linear_controller(path, where_text="agent")) == 4
