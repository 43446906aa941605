"""Any MuJoCo model is a plant (issue 52): the plant file's linearisation checked against
independent differences of MuJoCo and against the cart-pole's own route, its designs against
SciPy, its loop against the theory, and each refusal's one line."""

from __future__ import annotations

import json
import re
import tomllib
from pathlib import Path

import mujoco
import numpy as np
import pytest
import scipy.linalg

from pendulum_lqg.bench.experiments import parse_spec
from pendulum_lqg.cli import main
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.model.catalog import load_named_plant, load_plant_at, plant_names
from pendulum_lqg.model.linearize import linearize
from pendulum_lqg.model.plant import load_plant
from pendulum_lqg.util.resources import data_dir

MODELS = data_dir("models")
DOUBLE = MODELS / "double_cartpole.toml"
CARTPOLE_XML = (MODELS / "cartpole.xml").read_text()

#: A plant file of the benchmark's cart-pole MJCF (the route of any MuJoCo model).
CARTPOLE_PLANT = """model = "cartpole.xml"
outputs = ["cart_position", "pole_angle"]
W = [1e-4, 1e-4, 1e-4, 1e-4]
V = [1e-4, 1e-4]
Q = [1, 1, 1, 1]
R = 0.1
x0 = [0, 0.05, 0, 0]
"""


def _write(tmp_path: Path, xml: str, plant: str = CARTPOLE_PLANT) -> Path:
    (tmp_path / "cartpole.xml").write_text(xml)
    path = tmp_path / "my_plant.toml"
    path.write_text(plant)
    return path


def _independent_derivatives(model: mujoco.MjModel, eps: float = 1e-5):
    """``(A, B)`` of ``ẋ = [q̇, q̈]`` about qpos0 at rest by central differences written here on
    MuJoCo's public API (a larger step than the package's 1e-6), B per unit of physical force
    (ctrl = u / gear)."""
    nq, nv = model.nq, model.nv
    data = mujoco.MjData(model)

    def f(x, u):
        mujoco.mj_resetData(model, data)
        data.qpos[:] = model.qpos0 + x[:nq]
        data.qvel[:] = x[nq:]
        data.ctrl[:] = u / model.actuator_gear[:, 0]
        mujoco.mj_forward(model, data)
        return np.concatenate([data.qvel.copy(), data.qacc.copy()])

    n = nq + nv
    A = np.column_stack([(f(eps * e, np.zeros(1)) - f(-eps * e, np.zeros(1))) / (2 * eps)
                         for e in np.eye(n)])
    B = ((f(np.zeros(n), np.array([eps])) - f(np.zeros(n), np.array([-eps]))) / (2 * eps))[:, None]
    return A, B


def test_the_double_pendulums_linearisation_equals_independent_differences_of_mujoco():
    plant = load_named_plant("double-cartpole")
    A, B = _independent_derivatives(plant.model)
    assert plant.A.shape == (6, 6) and plant.B.shape == (6, 1) and plant.C.shape == (3, 6)
    scale = np.abs(A).max()
    assert np.abs(plant.A - A).max() <= 1e-6 * scale
    assert np.abs(plant.B - B).max() <= 1e-6 * np.abs(B).max()
    np.testing.assert_array_equal(plant.C, np.eye(3, 6))        # y = [p, θ₁, θ₂]
    # two unstable modes (the two poles), real pairs ±λ as a frictionless pendulum has
    unstable = np.sort(np.linalg.eigvals(plant.A).real)[-2:]
    assert unstable.min() > 1 and np.allclose(np.sort(-np.linalg.eigvals(plant.A).real)[-2:],
                                              unstable, rtol=1e-3)


def test_design_json_of_the_double_pendulum_is_the_plants_model_and_scipys_lqr(capsys):
    assert main(["design", "--plant", "double-cartpole", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    plant = load_named_plant("double-cartpole")
    np.testing.assert_allclose(np.array(out["A"]), plant.A, rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.array(out["B"]), plant.B, rtol=0, atol=1e-12)
    Q = np.diag(plant.Q) if np.ndim(plant.Q) == 1 else plant.Q
    R = np.atleast_2d(plant.R)
    P = scipy.linalg.solve_continuous_are(plant.A, plant.B, Q, R)
    K = np.linalg.solve(R, plant.B.T @ P)
    np.testing.assert_allclose(np.array(out["K_lqr"]), K, rtol=1e-6)
    # the ZOH of (A, B) and MuJoCo's own transition derivatives agree to the integrator's O(h)
    assert out["zoh_vs_transition_fd_max_abs"] < 0.05


def test_the_cartpoles_plant_file_linearises_as_the_cartpoles_own_route(tmp_path):
    """The cart-pole MJCF through the plant-file route equals model/linearize.py's (A, B, C)."""
    plant = load_plant_at(_write(tmp_path, CARTPOLE_XML))
    ref = linearize(load_plant())
    np.testing.assert_allclose(plant.A, ref.A, rtol=1e-7, atol=1e-9)
    np.testing.assert_allclose(plant.B, ref.B, rtol=1e-7, atol=1e-9)
    np.testing.assert_allclose(plant.C, ref.C, atol=0)
    assert plant.state_names[:2] == ("slider", "hinge") or list(plant.state_names[:2]) == [
        "slider", "hinge"]


def test_a_gear_of_two_gives_the_same_plant_per_newton(tmp_path):
    """gear 2, ctrlrange ±5: the same ±10 N and the same B per newton as gear 1, ctrlrange ±10,
    on both routes (issue 52: force, saturation and J were off by the gear)."""
    geared = CARTPOLE_XML.replace('gear="1" ctrlrange="-10 10"', 'gear="2" ctrlrange="-5 5"')
    assert geared != CARTPOLE_XML
    one = load_plant_at(_write(tmp_path, CARTPOLE_XML))
    (tmp_path / "g").mkdir()
    two = load_plant_at(_write(tmp_path / "g", geared))
    np.testing.assert_allclose(two.B, one.B, rtol=1e-9)
    assert two.limits_per_input.tolist() == one.limits_per_input.tolist() == [10.0]
    cart_one = linearize(load_plant(tmp_path / "cartpole.xml"))
    cart_two = linearize(load_plant(tmp_path / "g" / "cartpole.xml"))
    np.testing.assert_allclose(cart_two.B, cart_one.B, rtol=1e-9)
    assert load_plant(tmp_path / "g" / "cartpole.xml").u_max == 10.0


def _run_json(capsys, *argv: str) -> dict:
    assert main(["run", *argv, "--json"]) == 0
    return json.loads(capsys.readouterr().out)


def test_the_double_pendulum_runs_the_same_floats_on_the_rollout_and_step_backends(capsys):
    args = ("--plant", "double-cartpole", "--episodes", "4", "--duration", "2")
    rollout = _run_json(capsys, *args)
    step = _run_json(capsys, *args, "--backend", "step")
    assert json.dumps(rollout["episodes"]) == json.dumps(step["episodes"])
    assert "rms_theta2" in rollout["summary"]


def test_plant_file_and_lti_alias_give_the_same_rows(capsys):
    di = "experiments/lti/double_integrator.toml"
    a = _run_json(capsys, "--plant", di, "--episodes", "3")
    b = _run_json(capsys, "--lti", di, "--episodes", "3")
    assert json.dumps(a["episodes"]) == json.dumps(b["episodes"])


@pytest.mark.slow
def test_the_double_pendulum_is_stabilised_and_its_rms_is_the_theorys(capsys):
    """200 episodes of 10 s: ≥ 99 % survive; 40 of 60 s: the RMS of each angle within 5 % of the
    stationary theory (the loop's transient from x0 is a small part of 60 s)."""
    short = _run_json(capsys, "--plant", "double-cartpole", "--episodes", "200",
                      "--duration", "10")
    assert short["summary"]["success_rate"] >= 0.99
    long = _run_json(capsys, "--plant", "double-cartpole", "--episodes", "40",
                     "--duration", "60")
    assert main(["theory", "--plant", "double-cartpole", "--json"]) == 0
    theory = json.loads(capsys.readouterr().out)
    rms = theory["policies"]["dlqr+kalman"]["rms"]
    for state in ("theta1", "theta2"):
        sim = long["summary"][f"rms_{state}"]["mean"]
        assert abs(sim / rms[state] - 1) < 0.05, (state, sim, rms[state])


def test_the_shipped_family_is_named():
    assert {"cartpole", "double-cartpole"} <= set(plant_names())


_REFUSALS = [
    ("no actuator", lambda x: re.sub(r"<actuator>.*?</actuator>", "", x, flags=re.S),
     CARTPOLE_PLANT, "model: cartpole.xml: expected at least one actuator"),
    ("gear 0", lambda x: x.replace('gear="1"', 'gear="0"'), CARTPOLE_PLANT,
     "needs a positive gear, found 0"),
    ("RK4", lambda x: x.replace('integrator="Euler"', 'integrator="RK4"'), CARTPOLE_PLANT,
     "the RK4 integrator is not supported"),
    ("sensor missing", lambda x: x, CARTPOLE_PLANT.replace('"pole_angle"', '"tip_angle"'),
     "outputs: sensor 'tip_angle' not found in cartpole.xml (its sensors: cart_position, "
     "pole_angle)"),
    ("not an equilibrium", lambda x: x.replace("</mujoco>", '<keyframe><key name="tilted" '
                                               'qpos="0 0.3"/></keyframe></mujoco>'),
     CARTPOLE_PLANT + 'equilibrium = "tilted"\n',
     "the model's keyframe 'tilted' is no equilibrium"),
    ("no keyframe", lambda x: x, CARTPOLE_PLANT + 'equilibrium = "down"\n',
     "equilibrium: expected the name of a keyframe of the model (it has none), got 'down'"),
    ("undetectable", lambda x: x, CARTPOLE_PLANT.replace('["cart_position", "pole_angle"]',
                                                         '["pole_angle"]').replace(
        "V = [1e-4, 1e-4]", "V = [1e-4]"), "outputs: the linearisation is not detectable"),
    ("x0 of the wrong length", lambda x: x, CARTPOLE_PLANT.replace("x0 = [0, 0.05, 0, 0]",
                                                                   "x0 = [0, 0.05]"), "x0"),
    ("Q of the wrong length", lambda x: x, CARTPOLE_PLANT.replace("Q = [1, 1, 1, 1]",
                                                                  "Q = [1, 1, 1]"), "Q"),
    ("unknown key", lambda x: x, CARTPOLE_PLANT + "A = [[0]]\n", "unknown key 'A'"),
]


@pytest.mark.parametrize("case, edit, plant, message", _REFUSALS, ids=[r[0] for r in _REFUSALS])
def test_a_bad_plant_file_is_refused_with_one_line(tmp_path, capsys, case, edit, plant, message):
    path = _write(tmp_path, edit(CARTPOLE_XML), plant)
    with pytest.raises(ConfigError) as exc:
        load_plant_at(path)
    text = str(exc.value)
    assert "\n" not in text and text.startswith((f"plant: {path}", "lti:"))
    if message is not None:
        assert message in text, text
    assert main(["design", "--plant", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and "Traceback" not in err and err.count("\n") == 1


def test_the_cartpole_refuses_a_model_with_a_second_link_and_points_to_a_plant_file(tmp_path):
    double = (MODELS / "double_cartpole.xml")
    with pytest.raises(ConfigError, match=r"a plant of its own: --plant FILE\.toml"):
        load_plant(double)
    one_joint = CARTPOLE_XML.replace('name="hinge"', 'name="pivot"').replace('joint="hinge"',
                                                                             'joint="pivot"')
    (tmp_path / "cartpole.xml").write_text(one_joint)
    with pytest.raises(ConfigError, match=r"no joint named 'hinge'.*--plant FILE\.toml"):
        load_plant(tmp_path / "cartpole.xml")


def _bench(tmp_path: Path, name: str, plant_line: str) -> bytes:
    exp = tmp_path / f"{name}.toml"
    exp.write_text(f'name = "{name}"\n{plant_line}\nepisodes = 4\nseed = 0\n[scenario]\n'
                   'duration = 2.0\n[grid]\npolicy = ["dlqr+kalman"]\n')
    assert main(["bench", str(exp), "--out", str(tmp_path / name)]) == 0
    return (tmp_path / name / "episodes.csv").read_bytes()


def test_bench_takes_the_experiment_key_plant_and_lti_file_as_its_alias(tmp_path):
    di = str(Path("experiments/lti/double_integrator.toml").resolve())
    assert _bench(tmp_path, "a", f'plant = "{di}"') == _bench(tmp_path, "b", f'lti_file = "{di}"')
    double = _bench(tmp_path, "c", 'plant = "double-cartpole"')
    assert b"rms_theta2" in double.splitlines()[0]
    exp = tmp_path / "both.toml"
    exp.write_text(f'name = "both"\nplant = "{di}"\nlti_file = "{di}"\n')
    with pytest.raises(ConfigError, match="lti_file: not with plant"):
        parse_spec(tomllib.loads(exp.read_text()))


def test_item6_theory_sets_each_limited_state_against_its_limit(capsys):
    """Issue 55 item 6: a state the plant file limits is set against that limit, not "(no
    limit)"; its σ-distance is limit / std of the stationary theory."""
    assert main(["theory", "--plant", "double-cartpole", "--json"]) == 0
    kalman = json.loads(capsys.readouterr().out)["policies"]["dlqr+kalman"]
    verdict = " ".join(kalman["verdict"].split())
    assert "no limit" not in verdict
    for state, limit in (("p", 1.8), ("theta1", 0.5), ("theta2", 0.5)):
        sigma = limit / kalman["std"][state]
        assert f"std {state} = {kalman['std'][state]:.2g} (its limit ±{limit:g} is {sigma:.1f} σ " \
               f"away)" in verdict
