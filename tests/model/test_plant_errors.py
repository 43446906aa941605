"""Models that break the MJCF contract are refused with one line naming the file."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import assert_one_line_error, run_cli

from pendulum_lqg.errors import ConfigError

ROOT = Path(__file__).resolve().parents[2]
MODEL = ROOT / "models" / "cartpole.xml"


_XML = MODEL.read_text()


@pytest.mark.parametrize(("old", "new", "message"), [
    ('    <jointpos name="pole_angle" joint="hinge"/>\n', "",
     "no sensor named 'pole_angle'"),
    ('<jointpos name="cart_position" joint="slider"/>',
     '<jointvel name="cart_position" joint="slider"/>',
     "sensor 'cart_position' must be <jointpos joint=\"slider\"/>"),
    (' ctrlrange="-10 10"', "", "actuator 'force' needs a symmetric ctrlrange (ctrllimited)"),
    ('ctrlrange="-10 10"', 'ctrlrange="-10 10" ctrllimited="false"',
     "actuator 'force' needs a symmetric ctrlrange (ctrllimited)"),
    ('ctrlrange="-10 10"', 'ctrlrange="-10 5"', "needs a symmetric ctrlrange"),
    ('gear="1"', 'gear="-1"', "actuator 'force' needs a positive gear"),
    (' range="-2.4 2.4"', "", "joint 'slider' needs a range around 0"),
    ('type="slide"', 'type="hinge"', "joint 'slider' must be of type \"slide\""),
    ('joint="slider" gear', 'joint="hinge" gear', "actuator 'force' must act on the joint"),
    ("</mujoco>", "", "cannot parse"),
])
def test_models_that_break_the_contract_are_refused(tmp_path, capsys, old, new, message):
    from pendulum_lqg.model.plant import load_plant

    assert _XML.count(old) == 1
    path = tmp_path / "edited.xml"
    path.write_text(_XML.replace(old, new))
    with pytest.raises(ConfigError) as info:
        load_plant(path)
    text = str(info.value)
    assert text.startswith("model: ") and message in text and str(path) in text, text
    assert "\n" not in text
    status, err = run_cli(capsys, ["design", "--model", str(path)])
    assert_one_line_error(status, err, "model: ")
    assert message in err


@pytest.mark.parametrize(("old", "new", "message"), [
    ('timestep="0.001"', 'timestep="0"', "<option timestep> must be a finite positive number of "
     "seconds, found 0.0"),
    ('timestep="0.001"', 'timestep="nan"', "<option timestep> must be a finite positive number"),
    ('timestep="0.001"', 'timestep="-0.001"', "<option timestep> must be a finite positive "
     "number of seconds, found -0.001"),
    ('timestep="0.001"', 'timestep="inf"', "<option timestep> must be a finite positive number"),
    ('gravity="0 0 -9.81"', 'gravity="0 0 nan"', "<option gravity> must be finite, found "
     "[0.0, 0.0, nan]"),
])
def test_a_bad_timestep_or_gravity_is_one_line_naming_the_file(tmp_path, capsys, old, new,
                                                                message):
    from pendulum_lqg.model.plant import load_plant

    assert _XML.count(old) == 1
    path = tmp_path / "options.xml"
    path.write_text(_XML.replace(old, new))
    with pytest.raises(ConfigError) as info:
        load_plant(path)
    assert str(info.value).startswith(f"model: {path}: {message}"), info.value
    for argv in (["design", "--model", str(path)], ["run", "--model", str(path), "--episodes", "1"]):
        status, err = run_cli(capsys, argv)
        assert_one_line_error(status, err, f"model: {path}: ")


def test_a_broken_model_file_in_an_experiment_names_both_files(tmp_path, capsys):
    xml = tmp_path / "no_limit.xml"
    xml.write_text(_XML.replace(' ctrlrange="-10 10"', ""))
    toml = tmp_path / "exp.toml"
    toml.write_text('model_file = "no_limit.xml"\nepisodes = 1\n')
    status, err = run_cli(capsys, ["bench", str(toml), "--out", str(tmp_path / "o")])
    assert_one_line_error(status, err, "model: ")
    assert str(xml) in err and str(toml) in err and "ctrlrange" in err


# ---- 5. report on corrupt results ----------------------------------------------------------------
