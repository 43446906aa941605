"""Issue 17 hardening: bad input of every kind ends in a one-line pendulum_lqg error (exit 2 from
the CLI, no traceback) or in a correct, finite result — never a raw solver exception, a silently
truncated complex matrix, an inf/NaN design or an endless loop."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

from pendulum_lqg import design
from pendulum_lqg.cli import main
from pendulum_lqg.errors import ConfigError, DesignError, PendulumLQGError, ShapeError

ROOT = Path(__file__).resolve().parents[1]
MODEL = ROOT / "models" / "cartpole.xml"

A_DI = np.array([[0.0, 1.0], [0.0, 0.0]])
B_DI = np.array([[0.0], [1.0]])
C_DI = np.array([[1.0, 0.0]])


def _cli(capsys, argv):
    """``main(argv)``'s exit status and its stderr (argparse's own errors exit via SystemExit)."""
    try:
        status = main(argv)
    except SystemExit as exc:
        status = exc.code
    return status, capsys.readouterr().err


def _assert_one_line_error(status, err, name):
    assert status == 2, err
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith(f"error: {name}"), err


# ---- 1. design / run flags that used to end in a traceback or never end ------------------------
@pytest.mark.parametrize(("argv", "name", "detail"), [
    (["design", "--q", "0,0,0,0"], "Q:", "no stabilising LQR"),
    (["design", "--r", "1e300"], "lqr:", "check the scaling of Q and R"),
    (["design", "--w", "1e300"], "kalman:", "check the scaling of W and V"),
    (["design", "--w", "0,0,0,0"], "W:", "no stabilising Kalman filter"),
    (["design", "--dt", "100"], "control_period:", "expected at most 1 s"),
    (["design", "--dt", "1e5"], "control_period:", "expected at most 1 s"),
    (["run", "--duration", "1e308", "--episodes", "1"], "duration:", "at most 1e+08 control"),
    (["run", "--duration", "2e6", "--episodes", "1"], "duration:", "at most 1e+08 control"),
])
def test_design_and_run_flags_end_in_one_line_errors(capsys, argv, name, detail):
    status, err = _cli(capsys, argv)
    _assert_one_line_error(status, err, name)
    assert detail in err, err


def test_timing_bounds_from_the_python_api():
    from pendulum_lqg.limits import (
        MAX_CONTROL_PERIOD,
        MAX_PERIODS,
        MAX_STEPS_PER_PERIOD,
        check_duration,
    )
    from pendulum_lqg.plant import ModelOverrides, load_plant, steps_per_period

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
    from pendulum_lqg.plant import load_plant
    from pendulum_lqg.plugins import build_policy
    from pendulum_lqg.sim import Scenario

    with pytest.raises(ConfigError, match=r"^duration: expected at most"):
        build_policy("dlqr+kalman", plant=load_plant(), scenario=Scenario(duration=1e300))


# ---- 2. the design API under garbage input -----------------------------------------------------
def test_complex_matrices_are_refused_not_cut_to_their_real_part():
    with pytest.raises(ShapeError, match=r"^A: expected a real matrix, got complex entries"):
        design.lqr(A_DI + 0j, B_DI, np.eye(2), 1.0)
    with pytest.raises(ShapeError, match=r"^Q: expected a real matrix, got complex entries"):
        design.lqr(A_DI, B_DI, np.eye(2) * (1 + 1e-3j), 1.0)
    with pytest.raises(ShapeError, match=r"^B: expected a real matrix"):
        design.zoh(A_DI, [[0.0], [1j]], 0.1)
    with pytest.raises(ShapeError, match=r"^C: expected a real matrix"):
        design.luenberger(A_DI, [[1.0, 0.5j]], [-1.0, -2.0])
    with pytest.raises(DesignError, match=r"^dt: expected a finite positive number"):
        design.zoh(A_DI, B_DI, np.complex128(0.1))


def test_overflowing_results_raise_instead_of_returning_inf():
    with pytest.raises(DesignError, match=r"^zoh: the result is not finite"):
        design.zoh(np.eye(2) * 1e3, B_DI, 10.0)           # e^{10⁴}
    with pytest.raises(DesignError, match=r"^euler: the result is not finite"):
        design.euler(np.full((2, 2), 1e300), B_DI, 1e10)
    with pytest.raises(DesignError, match=r"^finite_horizon_dlqr: the result is not finite"):
        design.finite_horizon_dlqr(np.eye(2) * 1e100, np.ones((2, 1)), np.eye(2), 1.0,
                                   np.eye(2), 10)


def test_raw_solver_errors_are_wrapped_naming_the_function():
    # a CARE whose Hamiltonian has eigenvalues on the imaginary axis: scipy raises LinAlgError
    with pytest.raises(DesignError, match=r"^Q: the cost does not weight the mode\(s\)"):
        design.lqr(A_DI, B_DI, np.zeros((2, 2)), 1.0)
    with pytest.raises(DesignError, match=r"^lqr: no solution for these data \(LinAlgError"):
        design.lqr(A_DI, B_DI, np.eye(2), 1e300)
    with pytest.raises(DesignError, match=r"^dkalman: no solution for these data"):
        design.dkalman([[1.0, 0.1], [0.0, 1.0]], np.eye(2), C_DI, np.eye(2) * 1e300, 1.0)


_SPECIALS = (np.nan, np.inf, -np.inf, 1e300, -1e300, 1e-300, 0.0)


def _garbage(rng, shape):
    """A random matrix of ``shape`` that is often wrong: non-finite entries, huge or tiny scales,
    complex entries, zeros, a wrong rank, or not a matrix at all."""
    kind = rng.integers(10)
    if kind == 0:
        return ["abc", None, [[1.0, 2.0], [3.0]], {"a": 1}][rng.integers(4)]
    if kind == 1:
        return np.zeros(shape)
    M = rng.normal(size=shape) * 10.0 ** rng.integers(-3, 4)
    if kind == 2 and M.size:
        M.flat[rng.integers(M.size)] = rng.choice(_SPECIALS)
    elif kind == 3:
        M = M * rng.choice([1e150, 1e300, 1e-300])
    elif kind == 4:
        M = M + 1j * rng.normal(size=shape) * rng.choice([1.0, 1e-12])
    elif kind == 5 and M.ndim == 2 and min(M.shape) > 1:
        M[:, 0] = M[:, 1]                       # rank deficient
    elif kind == 6:
        M = M @ M.T if M.ndim == 2 and M.shape[0] == M.shape[1] else M
    return M


def non_finite_arrays(result, path="result"):
    """Paths of the arrays and numbers in ``result`` (dataclass, tuple, array) that hold nan/inf."""
    import dataclasses

    if isinstance(result, np.ndarray):
        return [] if result.dtype.kind not in "fc" or np.all(np.isfinite(result)) else [path]
    if isinstance(result, float | complex):
        return [] if np.isfinite(result) else [path]
    if isinstance(result, tuple | list):
        return [q for i, v in enumerate(result) for q in non_finite_arrays(v, f"{path}[{i}]")]
    if dataclasses.is_dataclass(result):
        return [q for f in dataclasses.fields(result)
                for q in non_finite_arrays(getattr(result, f.name), f"{path}.{f.name}")]
    return []


def _random_call(rng):
    n, m, p = int(rng.integers(0, 5)), int(rng.integers(1, 3)), int(rng.integers(1, 3))
    if rng.random() < 0.15:                     # wrong shapes
        m, p = m + 1, p + 1
    A = _garbage(rng, (n, n))
    B = _garbage(rng, (n, m) if rng.random() < 0.9 else (n + 1, m))
    C = _garbage(rng, (p, n))
    Q = _garbage(rng, (n, n)) if rng.random() < 0.5 else np.eye(n)
    R = _garbage(rng, (m, m)) if rng.random() < 0.5 else np.eye(m)
    W, V = Q, _garbage(rng, (p, p)) if rng.random() < 0.5 else np.eye(p)
    choices = [-1.0, -2.0, -0.5, -3.0, np.nan, 1e300, -1 + 1j, -1 - 1j]
    poles = [choices[k] for k in rng.integers(len(choices), size=int(rng.integers(0, 6)))]
    dt = [0.01, 0.1, 1.0, 100.0, 0.0, -1.0, np.nan, 1e300, 1j, "x"][rng.integers(10)]
    calls = {
        "lqr": lambda: design.lqr(A, B, Q, R),
        "dlqr": lambda: design.dlqr(A, B, Q, R, alpha=[1.0, 1.5, 1e300][rng.integers(3)]),
        "kalman": lambda: design.kalman(A, B, C, W, V),
        "dkalman": lambda: design.dkalman(A, B, C, W, V),
        "kalman_tv": lambda: design.kalman_tv(A, B, C, W, V, Q, int(rng.integers(1, 30))),
        "zoh": lambda: design.zoh(A, B, dt),
        "euler": lambda: design.euler(A, B, dt),
        "sampled_cost": lambda: design.sampled_cost(A, B, Q, R, dt),
        "process_noise_covariance": lambda: design.process_noise_covariance(A, B, W, dt),
        "finite_horizon_dlqr": lambda: design.finite_horizon_dlqr(A, B, Q, R, Q,
                                                                  int(rng.integers(1, 30))),
        "luenberger": lambda: design.luenberger(A, C, poles),
        "dluenberger": lambda: design.dluenberger(A, C, poles, dt=[None, 0.1][rng.integers(2)]),
        "ackermann": lambda: design.ackermann(A, C, poles),
        "reduced_order_observer": lambda: design.reduced_order_observer(A, B, C, poles),
        "lqg": lambda: design.lqg(A, B, C, _garbage(rng, (m, n)), _garbage(rng, (n, p))),
        "structure": lambda: design.structure(A, B, C),
        "augment_delays": lambda: design.augment_delays(
            A, B, C, measurement_delay=int(rng.integers(0, 3)),
            actuator_delay=int(rng.integers(0, 3))),
    }
    name = str(rng.choice(sorted(calls)))
    return name, calls[name]


def test_random_garbage_raises_only_pendulum_lqg_errors_and_returns_only_finite_arrays():
    rng = np.random.default_rng(17)
    outcomes = {"ok": 0, "refused": 0}
    for i in range(300):
        name, call = _random_call(rng)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error", np.exceptions.ComplexWarning)
                result = call()
        except PendulumLQGError as exc:
            assert "\n" not in str(exc), (i, name, str(exc))
            outcomes["refused"] += 1
        except Exception as exc:
            pytest.fail(f"call {i} ({name}) raised {type(exc).__name__}: {exc}")
        else:
            bad = non_finite_arrays(result)
            assert not bad, (i, name, bad)
            outcomes["ok"] += 1
    assert outcomes["ok"] >= 20 and outcomes["refused"] >= 100, outcomes


def test_the_lmi_designs_wrap_solver_errors():
    with pytest.raises(DesignError, match=r"^decay: expected a real number"):
        design.lmi_observer(A_DI, C_DI, decay="fast")
    with pytest.raises(ShapeError, match=r"^A: expected a real matrix, got complex"):
        design.h2_filter(A_DI * 1j, np.eye(2), C_DI, np.eye(2), 1.0)
    for W in (np.eye(2) * 1e300, np.zeros((2, 2))):
        try:
            res = design.hinf_filter(A_DI, np.eye(2), C_DI, W, 1.0)
        except PendulumLQGError:
            continue
        assert np.all(np.isfinite(res.L))


# ---- 3. experiment files -------------------------------------------------------------------------
@pytest.mark.parametrize(("content", "message"), [
    (b'[design]\nR = "abc"\n', "design.R: expected a finite positive number, got 'abc'"),
    (b"scenario = 5\n", "scenario: expected a table, got int"),
    (b"design = [1, 2]\n", "design: expected a table, got list"),
    (b"[scenario]\nx0 = true\n", "scenario.x0: expected 4 finite numbers, got True"),
    (b"[grid]\ntheta0 = [[1, 'a']]\n", "x0: expected 4 finite numbers"),
    (b"name = 5\n", "name: expected a string, got 5"),
    (b'name = "../elsewhere"\n', "name: expected a plain name"),
    (b'name = "\xff\xfe"\n', "experiment: "),
    (b"episodes = [\n", "experiment: "),
])
def test_bad_experiment_files_name_the_file_and_the_key(tmp_path, capsys, content, message):
    path = tmp_path / "bad.toml"
    path.write_bytes(content)
    status, err = _cli(capsys, ["bench", str(path), "--out", str(tmp_path / "o")])
    _assert_one_line_error(status, err, message)
    assert str(path) in err, err
    assert not (tmp_path / "o").exists()


def test_non_utf8_and_syntax_errors_from_the_python_api(tmp_path):
    from pendulum_lqg.experiments import load_spec

    path = tmp_path / "latin1.toml"
    path.write_bytes('description = "Größe"\n'.encode("latin-1"))
    with pytest.raises(ConfigError, match=r"^experiment: .*latin1.toml is not UTF-8 text"):
        load_spec(str(path))
    path.write_text("[grid\n")
    with pytest.raises(ConfigError, match=r"^experiment: .*latin1.toml is not valid TOML"):
        load_spec(str(path))


_WRONG_TYPES = ("abc", True, [1, "a"], {"a": 1}, [[1.0]], 5)


def test_wrong_types_at_any_level_raise_one_line_config_errors():
    from pendulum_lqg import experiments as ex

    tables = {"scenario": ex.SCENARIO_KEYS, "noise": ex.NOISE_KEYS, "design": ex.DESIGN_KEYS,
              "model": ex.MODEL_KEYS}
    cases = [{key: v} for key in ex.TOP_KEYS for v in _WRONG_TYPES]
    cases += [{t: {k: v}} for t, keys in tables.items() for k in keys for v in _WRONG_TYPES]
    for key in ex.GRID_KEYS:
        for v in _WRONG_TYPES:
            extra = {"delay": {"delay_kind": ["measurement"]},
                     "delay_kind": {"delay": [0.01]}}.get(key, {})
            cases += [{"grid": {key: [v], **extra}}, {"grid": {key: v, **extra}}]
    refused = 0
    for case in cases:
        try:
            ex.parse_spec(case)
        except PendulumLQGError as exc:
            assert "\n" not in str(exc), (case, str(exc))
            refused += 1
        except Exception as exc:
            pytest.fail(f"{case!r} raised {type(exc).__name__}: {exc}")
    assert refused >= 0.8 * len(cases), (refused, len(cases))


# ---- 4. models -----------------------------------------------------------------------------------
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
    from pendulum_lqg.plant import load_plant

    assert _XML.count(old) == 1
    path = tmp_path / "edited.xml"
    path.write_text(_XML.replace(old, new))
    with pytest.raises(ConfigError) as info:
        load_plant(path)
    text = str(info.value)
    assert text.startswith("model: ") and message in text and str(path) in text, text
    assert "\n" not in text
    status, err = _cli(capsys, ["design", "--model", str(path)])
    _assert_one_line_error(status, err, "model: ")
    assert message in err


def test_a_broken_model_file_in_an_experiment_names_both_files(tmp_path, capsys):
    xml = tmp_path / "no_limit.xml"
    xml.write_text(_XML.replace(' ctrlrange="-10 10"', ""))
    toml = tmp_path / "exp.toml"
    toml.write_text('model_file = "no_limit.xml"\nepisodes = 1\n')
    status, err = _cli(capsys, ["bench", str(toml), "--out", str(tmp_path / "o")])
    _assert_one_line_error(status, err, "model: ")
    assert str(xml) in err and str(toml) in err and "ctrlrange" in err


# ---- 5. report on corrupt results ----------------------------------------------------------------
def _results_folder(tmp_path, study=None, summary=None, spec=None):
    folder = tmp_path / "res"
    folder.mkdir()
    src = {"study": study} if study else {}
    (folder / "spec.json").write_text(spec if spec is not None
                                      else json.dumps({"name": "r", "spec": src}))
    (folder / "summary.md").write_text("| a |\n|---|\n| 1 |\n")
    if study == "margins":
        (folder / "nyquist.csv").write_text("loop,re,im\nLQ (continuous),0.1,0.2\n")
        (folder / "ltr.csv").write_text("measurement,q,phase_margin_deg,min_return_difference,"
                                        "disk_margin\nfull,1,60,1,0.5\n")
    if summary is not None:
        (folder / "summary.json").write_text(summary)
    return folder


@pytest.mark.parametrize(("study", "spec", "summary", "message"), [
    (None, '{"name": "r", "spec": {', None, "spec.json is not valid JSON"),
    (None, "[1, 2]", None, "spec.json: expected a JSON object, got list"),
    (None, '{"name": "r", "spec": {"grid": 5}}', None,
     "spec.json: key 'spec.grid': expected an object, got 5"),
    (None, '{"name": "r", "spec": {"grid": {"noise_scale": 1}}}', None,
     "spec.json: key 'spec.grid.noise_scale': expected a list, got 1"),
    (None, '{"name": 5}', None, "spec.json: key 'name': expected a string, got 5"),
    (None, '{"name": "../../x"}', None, "spec.json: key 'name': expected a plain name"),
    ("margins", None, '{"loops": ', "summary.json is not valid JSON"),
    ("margins", None, '{"loops": "x"}', "summary.json: key 'loops': expected a list"),
    ("margins", None, '{"loops": [{"loop": "LQ (c)", "phase_margin_deg": "60"}]}',
     "summary.json: key 'loops[0].phase_margin_deg': expected a number, got '60'"),
    ("roa", None, "\xff", "summary.json is not valid JSON"),
    ("roa", None, '{"params": {"map_theta": "a"}}',
     "summary.json: key 'params.map_theta': expected a list"),
    ("roa", None, "", "summary.json is not valid JSON"),
])
def test_report_on_corrupt_results_names_the_file(tmp_path, capsys, study, spec, summary,
                                                   message):
    folder = _results_folder(tmp_path, study, summary, spec)
    status, err = _cli(capsys, ["report", str(folder), "--out", str(tmp_path / "rep")])
    _assert_one_line_error(status, err, "results: ")
    assert message in err and str(folder) in err, err


def test_report_json_reader_from_the_python_api(tmp_path):
    from pendulum_lqg.report import make_report

    folder = _results_folder(tmp_path, "roa", summary='{"params": 1}')
    (folder / "summary.json").write_bytes(b'{"params": "\xff"}')
    with pytest.raises(ConfigError, match=r"^results: .*summary.json is not UTF-8 text"):
        make_report([folder], tmp_path / "rep")
