"""Suites of a plant given as matrices (pendulum_lqg.scoreboard.lti_suite): the reference scores
exactly 1, another design against it, what is not applicable, and the file's one-line errors."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest

from pendulum_lqg.cli import main
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.scoreboard.lti_suite import (
    load_lti_suite,
    lti_suite_entries,
    lti_suite_entry,
    names_an_lti_plant,
)

SUITE = Path(__file__).resolve().parents[2] / "experiments" / "lti" / "two_mass_suite.toml"


@pytest.fixture(scope="module")
def suite():
    return dataclasses.replace(load_lti_suite(SUITE), episodes=12)


def test_the_reference_scores_exactly_one(suite):
    """The reference against itself: the same rows, so score 1.0 exactly, gap 0, its interval a
    point; the full-state bound costs less."""
    e = lti_suite_entry(suite, suite.reference)
    assert e["score_mean"] == 1.0 and e["score_ci"] == [1.0, 1.0]
    assert e["optimality_gap"] == 0.0 and e["success_rate"] == 1.0
    assert e["full_state_bound"]["cost_mean"] < e["cost_mean"]
    assert [r["episode"] for r in e["rows"]] == list(range(12))


def test_another_design_is_scored_on_the_same_episodes(suite):
    """dlqr+luenberger on the same seeds: its own J, a gap to the reference on all 12 episodes;
    the seeds are the reference's."""
    cache: dict = {}
    ref = lti_suite_entry(suite, suite.reference, cache)
    e = lti_suite_entry(suite, "dlqr+luenberger", cache)
    assert e["gap_episodes"] == 12 and e["cost_mean"] != ref["cost_mean"]
    assert [r["seed"] for r in e["rows"]] == [r["seed"] for r in ref["rows"]]
    assert e["fingerprint"] == ref["fingerprint"]


def test_agents_and_plugins_are_not_applicable(suite):
    out = lti_suite_entries([suite], policy=None, agent="x.py:make")
    assert out["two-mass"]["applicable"] is False
    assert "Gymnasium agent" in out["two-mass"]["reason"]
    out = lti_suite_entries([suite], policy="my.py:Ctrl", agent=None)
    assert "plug-in" in out["two-mass"]["reason"]


def test_score_command_takes_an_lti_suite_file(capsys):
    assert names_an_lti_plant(str(SUITE)) and not names_an_lti_plant("lecture")
    assert main(["score", "dlqr+kalman", "--suite", str(SUITE), "--episodes", "4", "--json"]) == 0
    e = json.loads(capsys.readouterr().out)["suites"]["two-mass"]
    assert e["applicable"] and e["score_mean"] == 1.0 and e["episodes"] == 4


@pytest.mark.parametrize("text, message", [
    ('name = "x"\npurpose = "p"\nlti_file = "two_mass.toml"\nreference = "dlqr+kalman"\n'
     'episodes = 3\ncolour = 1\n', "unknown key 'colour'"),
    ('name = "x"\npurpose = "p"\nlti_file = "two_mass.toml"\nreference = "dlqr+kalman"\n',
     "episodes: missing"),
    ('name = "x"\npurpose = "p"\nlti_file = "two_mass.toml"\nreference = "dlqr+kalman"\n'
     'episodes = 3\n[scenario]\nduration = -1.0\n', "scenario.duration: expected a finite"),
])
def test_a_bad_suite_file_is_one_line_naming_the_key(tmp_path, text, message):
    path = tmp_path / "s.toml"
    path.write_text(text)
    with pytest.raises(ConfigError, match=message) as exc:
        load_lti_suite(path)
    assert str(path) in str(exc.value) and "\n" not in str(exc.value)
