"""The suites' design plant and fingerprint: the reference is the optimum for the plant played where
a suite fixes its plant, the nominal MJCF's design where it randomises it; the fingerprint is
computed once per suite and is the one the committed score files carry."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from pendulum_lqg.cli import main
from pendulum_lqg.core.runner import run_episodes
from pendulum_lqg.model.plant import load_plant
from pendulum_lqg.policies.loading import build_policy
from pendulum_lqg.scoreboard import episodes as ep
from pendulum_lqg.scoreboard import suites
from pendulum_lqg.scoreboard.score import score_entry
from pendulum_lqg.scoreboard.suites import (
    NOMINAL_MJCF,
    NOMINAL_WITH_OVERRIDES,
    PLANT_PLAYED,
    Suite,
    load_suite,
    suite_names,
)

ROOT = Path(__file__).resolve().parents[2]
#: another cart-pole: the pole 1.6 times heavier, the cart 0.7 times as heavy
POLE_SCALE, CART_SCALE = 1.6, 0.7
CART_GEOM = '<geom name="cart" class="cart" type="box" size="0.2 0.1 0.06" mass="1.0"/>'
POLE_GEOM = ('<geom name="pole" class="pole" type="cylinder" fromto="0 0 0 0 0 1.0" '
             'size="0.015" mass="0.1"/>')


def _suite_file(folder: Path, name: str, env: str) -> Path:
    path = folder / f"{name}.toml"
    path.write_text(f'name = "{name}"\nversion = 1\npurpose = "another cart-pole"\n'
                    f'reference = "dlqr+kalman"\nepisodes = 8\nseed = 11\n\n[env]\n'
                    f'duration = 4.0\n{env}', encoding="utf-8")
    return path


def _heavy_mjcf(folder: Path) -> Path:
    """models/cartpole.xml with the masses the overrides give: ``repr`` of the products the spec
    edit computes (1.0·0.7, 0.1·1.6), so the compiled models are the same doubles."""
    xml = (ROOT / "models" / "cartpole.xml").read_text(encoding="utf-8")
    assert CART_GEOM in xml and POLE_GEOM in xml          # the XML this test edits
    xml = xml.replace(CART_GEOM, CART_GEOM.replace('mass="1.0"', f'mass="{1.0 * CART_SCALE!r}"'))
    xml = xml.replace(POLE_GEOM, POLE_GEOM.replace('mass="0.1"', f'mass="{0.1 * POLE_SCALE!r}"'))
    path = folder / "heavy.xml"
    path.write_text(xml, encoding="utf-8")
    return path


OVERRIDES = (f"\n[env.model_overrides]\npole_mass_scale = {POLE_SCALE}\n"
             f"cart_mass_scale = {CART_SCALE}\n")
#: the same plant as a randomisation of one value: a fixed model error the designer does not know
FIXED_DRAW = (f"\n[env.randomize]\npole_mass_scale = [{POLE_SCALE}, {POLE_SCALE}]\n"
              f"cart_mass_scale = [{CART_SCALE}, {CART_SCALE}]\n")


def _score(capsys, suite: Path) -> dict:
    assert main(["score", "dlqr+kalman", "--suite", str(suite), "--json"]) == 0
    (entry,) = json.loads(capsys.readouterr().out)["suites"].values()
    return entry


def test_fixed_overrides_score_as_the_same_plant_given_by_model_path(tmp_path, capsys):
    overridden = _score(capsys, _suite_file(tmp_path, "over", OVERRIDES))
    by_file = _score(capsys, _suite_file(tmp_path, "file",
                                         f'model_path = "{_heavy_mjcf(tmp_path)}"\n'))
    # the same compiled model, the same design, the same noise streams: the same floats
    assert overridden["rows"] == by_file["rows"]
    assert overridden["cost_mean"] == by_file["cost_mean"] == overridden["reference"]["cost_mean"]
    assert overridden["reference"] == by_file["reference"]
    assert overridden["success_rate"] == 1.0 and overridden["optimality_gap"] == 0.0
    assert overridden["designed_on"] == by_file["designed_on"] == PLANT_PLAYED
    # designed on the nominal MJCF instead (the same plant as a fixed draw), the Kalman design
    # is another one: its J on the same episodes is higher
    mismatched = _score(capsys, _suite_file(tmp_path, "draw", FIXED_DRAW))
    assert mismatched["designed_on"] == NOMINAL_MJCF
    assert mismatched["cost_mean"] > 1.2 * overridden["cost_mean"]


def test_the_design_plant_holds_the_overrides_and_never_a_draw(tmp_path):
    nominal = load_plant()
    both = suites.load_suite(str(_suite_file(
        tmp_path, "both", OVERRIDES + "\n[env.randomize]\npole_length_scale = [0.8, 1.2]\n")))
    assert both.designed_on == NOMINAL_WITH_OVERRIDES
    simulated, design = both.plants()
    assert simulated is not design
    for plant in (simulated, design):
        assert plant.pole_mass == pytest.approx(POLE_SCALE * nominal.pole_mass, rel=1e-15)
        assert plant.cart_mass == pytest.approx(CART_SCALE * nominal.cart_mass, rel=1e-15)
        assert plant.pole_length == nominal.pole_length                   # no draw
    fixed = suites.load_suite(str(_suite_file(tmp_path, "fixed", OVERRIDES)))
    assert fixed.designed_on == PLANT_PLAYED
    assert fixed.plants()[1].pole_mass == pytest.approx(POLE_SCALE * nominal.pole_mass, rel=1e-15)


def test_mismatch_is_still_designed_on_the_nominal_mjcf():
    suite = load_suite("mismatch").with_episodes(4)
    assert suite.designed_on == NOMINAL_MJCF == load_suite("hard").designed_on
    assert {load_suite(n).designed_on for n in suite_names() if n not in ("mismatch", "hard")} \
        == {PLANT_PLAYED}
    nominal = load_plant()
    design = suite.plants()[1]
    assert (design.pole_mass, design.pole_length, design.cart_mass) == \
        (nominal.pole_mass, nominal.pole_length, nominal.cart_mass)
    # the reference's rows are those of the filter designed on the MJCF as it is, played on the
    # randomised plant
    scenario = suite.config.scenario
    policy = build_policy(suite.reference, plant=nominal, scenario=scenario)
    res = run_episodes(suite.plants()[0], scenario, policy, seed=suite.seed,
                       episodes=range(suite.episodes))
    assert [r["cost"] for r in ep.policy_rows(suite, suite.reference)] == \
        [r["cost"] for r in res.rows]


def test_the_env_paths_design_on_the_suites_plant(tmp_path):
    """The Gymnasium twins — the LQG agent and a plug-in through the env — are designed on the
    same plant as the batch: their rows equal the batch's on a suite with fixed overrides."""
    suite = load_suite(str(_suite_file(tmp_path, "over", OVERRIDES))).with_episodes(3)
    reference = ep.policy_rows(suite, suite.reference)
    assert ep.agent_rows(suite, ep.reference_agent) == reference
    plugin = str(ROOT / "experiments" / "plugin_lqg.py") + ":make"
    assert ep.agent_rows(suite, ep.plugin_agent(plugin)) == ep.policy_rows(suite, plugin)


def test_the_kalman_observation_design_is_the_reference_filter_of_the_plant_played(tmp_path):
    from pendulum_lqg.scoreboard.obs_design import KalmanEstimates

    suite = load_suite(str(_suite_file(tmp_path, "over", OVERRIDES)))
    shown = KalmanEstimates(suite.config, False, 1).estimator
    reference = build_policy(suite.reference, plant=load_plant(_heavy_mjcf(tmp_path)),
                             scenario=suite.config.scenario).estimator
    nominal = build_policy(suite.reference, plant=load_plant(),
                           scenario=suite.config.scenario).estimator
    np.testing.assert_array_equal(shown.gain, reference.gain)
    assert not np.allclose(shown.gain, nominal.gain, rtol=1e-3)


def test_the_fingerprint_is_computed_once_per_suite_and_matches_the_committed_scores(
        monkeypatch):
    committed = json.loads((ROOT / "docs" / "leaderboard" / "scores" / "dlqr+kalman.json")
                           .read_text(encoding="utf-8"))["suites"]
    for name in suite_names():
        assert load_suite(name).fingerprint() == committed[name]["fingerprint"], name
        assert load_suite(name).designed_on == committed[name]["designed_on"], name
    loads, plants = [], []
    real_load, real_plants = suites.load_plant, Suite.plants
    monkeypatch.setattr(suites, "load_plant",
                        lambda *a, **k: loads.append(a) or real_load(*a, **k))
    monkeypatch.setattr(Suite, "plants", lambda self: plants.append(1) or real_plants(self))
    suite = load_suite("lecture").with_episodes(3)
    doc = score_entry([suite], policy="dlqr+luenberger", nthread=1)
    assert plants                                # the reference, the bound and the entry
    # two loads per plants() (the simulated and the design plant), one for the fingerprint
    assert len(loads) == 2 * len(plants) + 1
    assert doc["suites"]["lecture"]["fingerprint"] == suite.fingerprint()
    assert len(loads) == 2 * len(plants) + 1      # asked again: the cached value
