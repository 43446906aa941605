"""Closed-loop identification with certainty-equivalent LQG (pendulum_lqg.learn.closed_loop) on the
MuJoCo cart-pole: the certainty-equivalent design on the true model is the built-in dlqr+kalman
(two paths), a reduced identification on a short lecture stabilises the linearised plant and
survives the suite's episodes, the budget is kept, and bad settings are one line."""

from __future__ import annotations

import json

import numpy as np
import pytest

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.learn.closed_loop import (
    ClosedLoopSettings,
    certainty_equivalent,
    identify_closed_loop,
)
from pendulum_lqg.scoreboard.suites import Suite, load_suite


@pytest.fixture(scope="module")
def truth():
    from pendulum_lqg.policies.loading import PolicyContext

    suite = load_suite("lecture")
    return PolicyContext.build(suite.plants()[1], suite.config.scenario)


def _loop_radius(truth, ss: dict) -> float:
    """The spectral radius of the true linearised plant closed by a state-space controller of
    ``z = [y, u_{k−1}]`` (``action_scale`` 1 N, no saturation)."""
    Ac, Bc, Cc, Dc = (np.asarray(ss[k]) for k in "ABCD")
    q = Ac.shape[0]
    urow = np.hstack([Dc[:, :2] @ truth.C, Cc, Dc[:, 2:]])
    M = np.vstack([np.hstack([truth.Phi, np.zeros((4, q + 1))]) + truth.Gamma @ urow,
                   np.hstack([Bc[:, :2] @ truth.C, Ac, Bc[:, 2:]]), urow])
    return float(np.abs(np.linalg.eigvals(M)).max())


def test_the_design_on_the_true_model_is_the_builtin_dlqr_kalman(truth):
    from pendulum_lqg.policies.loading import build_policy
    from pendulum_lqg.scoreboard.linear import lqg_state_space

    suite = load_suite("lecture")
    sc = suite.config.scenario
    info = build_policy("dlqr+kalman", plant=suite.plants()[1], scenario=sc).info
    ss = certainty_equivalent(truth.Phi, truth.Gamma, truth.A, truth.B, np.asarray(info["L"]),
                              delay=0, Q=np.diag(sc.cost_Q), R=np.array([[sc.cost_R]]),
                              dt=truth.dt)
    builtin = lqg_state_space(truth.Phi, truth.Gamma, truth.C, np.asarray(info["K"]),
                              np.asarray(info["L"]))
    for key in "ABCD":
        np.testing.assert_allclose(ss[key], builtin[key], rtol=1e-9, atol=1e-12)


def test_a_delay_adds_the_forces_in_flight_to_the_controller_state(truth):
    ss = certainty_equivalent(truth.Phi, truth.Gamma, truth.A, truth.B, np.zeros((4, 2)),
                              delay=3, Q=np.eye(4), R=np.eye(1), dt=truth.dt)
    assert np.shape(ss["A"]) == (7, 7) and np.shape(ss["D"]) == (1, 3)


@pytest.fixture(scope="module")
def reduced():
    """A reduced identification on lecture episodes of 4 s: 3 000 open-loop steps, two rounds
    of 6 closed-loop episodes, delays 0 … 1."""
    base = load_suite("lecture")
    suite = Suite(base.name, base.version, base.purpose, base.reference, 20, base.seed,
                  {**base.env, "duration": 4.0})
    settings = ClosedLoopSettings(rounds=2, episodes=6, open_loop_steps=3000, max_delay=1,
                                  validation_episodes=2)
    lines: list[str] = []
    stages: list[tuple[dict, dict]] = []
    results = identify_closed_loop(suite, root=7, settings=settings, log=lines.append,
                                   on_stage=lambda state, data: stages.append((state, data)))
    return suite, results, lines, settings, stages


def test_a_reduced_identification_stabilises_the_plant_and_survives(truth, reduced):
    from pendulum_lqg.scoreboard.linear import controller_file, linear_rows

    suite, results, lines, _, _ = reduced
    assert len(results) == 3 and len(lines) == 4          # open loop, two rounds, validation
    final = results[-1]
    assert _loop_radius(truth, final.state_space) < 1
    doc = controller_file("state_space", final.state_space, action_scale=1.0, env=suite.env)
    rows = linear_rows(suite, doc, name="reduced", nthread=1)
    assert sum(r["success"] for r in rows) >= 19
    # the budget: 100 bursts of 30 periods, then two rounds of 6 episodes of at most 400 periods
    assert results[0].logged_steps <= 3000 and final.logged_steps <= 3000 + 12 * 400
    assert [r.logged_steps for r in results] == sorted(r.logged_steps for r in results)
    assert final.stepped_steps >= final.logged_steps + 800  # + the validation episodes


def test_the_record_is_json_and_the_validation_sits_above_the_sensor_floor(reduced):
    _, results, *_ = reduced
    for r in results:
        json.dumps({"model": r.model, "validation": r.validation, "ss": r.state_space})
    check = results[-1].validation
    np.testing.assert_allclose(check["sensor_std"], [0.1, 0.1])
    # the sensor's noise is the floor of any predictor (up to the sampling spread of 800
    # samples), a good one comes within 10 % of it
    assert all(0.1 * 0.95 < r < 0.1 * 1.1 for r in check["innovation_rms"])
    assert check["samples"] == 800 and check["episodes"] == 2
    assert results[-1].model["delay"] in (0, 1) and len(results[-1].model["params"]) == 8


def test_item12_identification_resumed_after_a_round_gives_the_uninterrupted_rounds(reduced):
    """Issue 55 item 12: the state ``on_stage`` gives after closed-loop round 1, through JSON and
    an .npz as ``sysid-lqg``'s checkpoint stores it, continues to the rounds (models, designs,
    step counts, validation) of the run that was never stopped."""
    import io

    suite, results, _, settings, stages = reduced
    assert [state["stage"] for state, _ in stages] == [0, 1, 2]
    state, data = stages[1]
    state = json.loads(json.dumps(state))
    buffer = io.BytesIO()
    np.savez(buffer, **data)
    buffer.seek(0)
    with np.load(buffer, allow_pickle=False) as npz:
        data = {k: npz[k] for k in npz.files}
    assert data["Y"].shape == (6, 400, 2)                     # round 1's episodes
    lines: list[str] = []
    resumed = identify_closed_loop(suite, root=7, settings=settings, log=lines.append,
                                   resume=(state, data))
    assert lines[0] == "resumed after round 1" and lines[1].startswith("round 2: ")
    for a, b in zip(resumed, results, strict=True):
        assert (a.logged_steps, a.stepped_steps) == (b.logged_steps, b.stepped_steps)
        assert json.dumps(a.model, sort_keys=True) == json.dumps(b.model, sort_keys=True)
        assert a.validation == b.validation
        for key in "ABCD":
            np.testing.assert_array_equal(a.state_space[key], b.state_space[key])


def test_item12_identification_resume_of_another_plan_is_refused(reduced):
    suite, _, _, settings, stages = reduced
    state, data = stages[0]
    with pytest.raises(ConfigError, match="resume: stage 0 of a plan of 100 bursts and 6 episodes"):
        identify_closed_loop(suite, root=7, settings=settings, steps=20_000,
                             resume=(state, data))


@pytest.mark.parametrize(("field", "value"), [("dither", 0.0), ("rounds", 0), ("burst", 2),
                                              ("burst_force", 1.5), ("caution", float("nan")),
                                              ("episodes", 2.5)])
def test_bad_settings_are_one_line_naming_the_field(field, value):
    with pytest.raises(ConfigError, match=f"^{field}: expected"):
        ClosedLoopSettings(**{field: value})


def test_a_budget_too_small_for_one_episode_per_round_is_refused():
    with pytest.raises(ConfigError, match=r"^steps: expected at least 2,300 logged env steps"):
        identify_closed_loop(load_suite("lecture"), root=0, steps=1000)
