"""Bring your own controller: PolicyContext, plugin loading, scoring on the built-ins' episodes."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from scipy.linalg import expm

import pendulum_lqg
from pendulum_lqg.bench.experiments import load_spec, parse_spec, run_unit
from pendulum_lqg.cli import main
from pendulum_lqg.core.metrics import summarize
from pendulum_lqg.core.noise import NoiseModel
from pendulum_lqg.core.runner import run_episodes
from pendulum_lqg.core.scenario import Scenario
from pendulum_lqg.errors import PluginError
from pendulum_lqg.model.plant import load_plant
from pendulum_lqg.policies.loading import PolicyContext, build_policy
from pendulum_lqg.util.resources import data_dir

HERE = Path(__file__).resolve().parents[1]
PLUGINS = HERE / "plugins" / "lqg_plugins.py"
EXAMPLES = data_dir("experiments")


def _same(a, b) -> bool:
    """Rows equal to the last bit (nan included)."""
    return json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)


def _run(plant, name, episodes=range(20), scenario=None, **kw):
    scenario = scenario or Scenario(duration=5.0)
    policy = build_policy(name, plant=plant, scenario=scenario, **kw)
    return run_episodes(plant, scenario, policy, seed=3, episodes=episodes).rows


def test_policy_context_holds_the_lecture_models(plant):
    ctx = PolicyContext.build(plant, Scenario())
    assert pendulum_lqg.PolicyContext is PolicyContext
    assert ctx.dt == 0.01 and ctx.u_max == 10.0
    np.testing.assert_allclose(ctx.W, 4e-4 * np.eye(4), rtol=1e-12)       # density, state form
    np.testing.assert_allclose(ctx.V, 0.01 * np.eye(2), rtol=1e-12)       # per sample
    np.testing.assert_allclose(ctx.Phi, expm(ctx.A * ctx.dt), atol=1e-12)
    np.testing.assert_allclose(ctx.C, [[1, 0, 0, 0], [0, 1, 0, 0]])
    assert ctx.B.shape == (4, 1) and ctx.Q.shape == (4, 4) and ctx.R.shape == (1, 1)
    # force noise: W in state form is G W_in Gᵀ with G the generalised-force input map
    force = Scenario(noise=NoiseModel(process="force", process_density=(0.01, 0.001)))
    fctx = PolicyContext.build(plant, force)
    np.testing.assert_allclose(fctx.W, fctx.G @ np.diag([0.01, 0.001]) @ fctx.G.T)


def test_policy_context_u_max_is_the_scenarios_force_limit(plant):
    # the limit in force (rules.limits), not the model's ctrlrange: 4 N on MuJoCo, ∞ on a linear
    # plant with saturation switched off
    assert PolicyContext.build(plant, Scenario(force_limit=4.0)).u_max == 4.0
    off = Scenario(plant="linear-zoh", force_limit=float("inf"))
    assert PolicyContext.build(plant, off).u_max == float("inf")


@pytest.mark.parametrize("observer", ["kalman", "luenberger", "full_state"])
def test_builtin_behind_the_plugin_protocol_gives_the_builtins_episodes_bit_for_bit(plant, observer):
    ref = {"kalman": "dlqr+kalman", "luenberger": "dlqr+luenberger", "full_state": "dlqr+none"}
    builtin = _run(plant, ref[observer])
    plugin = _run(plant, f"{PLUGINS}:builtin_{observer}")
    assert _same(builtin, plugin)             # same seeds, same noise streams, same metrics


def test_plugin_without_select_is_scored_like_one_with_select(plant):
    # Luenberger under noise: episodes end at different periods, so the core must keep feeding
    # the whole batch to a plugin that cannot drop rows
    rows_select = _run(plant, f"{PLUGINS}:builtin_luenberger", episodes=range(12),
                       scenario=Scenario(duration=10.0))
    rows_fixed = _run(plant, f"{PLUGINS}:builtin_luenberger_no_select", episodes=range(12),
                      scenario=Scenario(duration=10.0))
    assert len({r["time_to_failure"] for r in rows_select}) > 3   # really staggered endings
    assert _same(rows_select, rows_fixed)


@pytest.mark.parametrize("episodes", [pytest.param(24, id="24"),
                                      pytest.param(200, id="200", marks=pytest.mark.slow)])
def test_dlqr_kalman_rebuilt_from_the_context_alone_matches_the_builtin(plant, episodes):
    """The shipped template re-implements DLQR + steady Kalman with scipy only; on the lecture's
    200 seeded noisy episodes (24 in the quick loop) it reaches the built-in's success rate and
    its cost within 1 %."""
    scenario = Scenario()
    builtin = summarize(_run(plant, "dlqr+kalman", range(episodes), scenario))
    plugin = summarize(_run(plant, f"{EXAMPLES / 'plugin_lqg.py'}:make", range(episodes), scenario))
    assert builtin["success_rate"] == plugin["success_rate"] == 1.0
    assert plugin["cost"]["mean"] == pytest.approx(builtin["cost"]["mean"], rel=0.01)
    assert plugin["rms_est_err_theta"]["mean"] == pytest.approx(
        builtin["rms_est_err_theta"]["mean"], rel=0.01)


def test_example_plugin_stabilises_noise_free_and_noisy(plant):
    name = f"{EXAMPLES / 'plugin_example.py'}:make"
    for scale in (0.0, 1.0):
        s = summarize(_run(plant, name, range(40), Scenario(noise=NoiseModel.lecture(scale=scale))))
        assert s["success_rate"] == 1.0
        assert np.isfinite(s["rms_est_err_p_dot"]["mean"])       # it exposes x_hat


def test_non_finite_force_ends_only_that_episode_as_diverged(plant):
    rows = _run(plant, f"{PLUGINS}:nan_force", episodes=range(4))
    clean = _run(plant, "dlqr+kalman", episodes=range(4))
    assert rows[1]["failure_reason"] == "diverged" and not rows[1]["success"]
    assert rows[1]["time_to_failure"] == pytest.approx(0.041)     # 1st physics step, 5th period
    assert np.isfinite(rows[1]["cost"])
    for i in (0, 2, 3):
        assert _same(rows[i], clean[i])


@pytest.mark.parametrize(("attr", "message"), [
    ("raises", "act raised RuntimeError: controller exploded on purpose"),
    ("wrong_shape", "act returned shape (20, 2); expected (20,) forces in newtons"),
    ("text_force", "act returned str; expected an array of 20 forces"),
    ("no_act", "the factory returned object, which has no reset() method"),
    ("factory_raises", "the factory raised KeyError: 'missing gain'"),
    ("NOT_CALLABLE", "NOT_CALLABLE is not callable"),
    ("missing", "has no attribute 'missing'"),
])
def test_broken_plugins_give_one_line_errors_naming_the_plugin(plant, attr, message):
    with pytest.raises(PluginError) as err:
        _run(plant, f"{PLUGINS}:{attr}")
    text = str(err.value)
    assert message in text and f"{PLUGINS}:{attr}" in text and "\n" not in text


def test_module_plugins_and_missing_modules(plant, monkeypatch):
    monkeypatch.syspath_prepend(str(HERE / "plugins"))
    assert _same(_run(plant, "lqg_plugins:builtin_kalman"), _run(plant, "dlqr+kalman"))
    with pytest.raises(PluginError, match="cannot import module 'no_such_module'"):
        _run(plant, "no_such_module:make")
    with pytest.raises(PluginError, match="no file"):
        _run(plant, "missing/file.py:make")


def test_cli_run_with_a_plugin_and_errors_exit_2(capsys):
    assert main(["run", "--policy", f"{EXAMPLES / 'plugin_example.py'}:make", "--episodes", "6",
                 "--duration", "2", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["config"]["policy"].endswith("plugin_example.py:make")
    assert out["config"]["design"] is None and out["success_rate"] == 1.0
    assert main(["run", "--policy", f"{PLUGINS}:raises", "--episodes", "2"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: policy ") and "RuntimeError" in err and "\n" not in err
    assert main(["run", "--policy", "dlqr+kalman", "--observer", "kalman"]) == 2
    assert "--policy" in capsys.readouterr().err


def test_grid_plugin_paths_are_relative_to_the_experiment_file(tmp_path, plant):
    (tmp_path / "ctrl").mkdir()
    (tmp_path / "ctrl" / "mine.py").write_text(PLUGINS.read_text())
    toml = tmp_path / "mine.toml"
    toml.write_text('name = "mine"\nepisodes = 6\nseed = 3\n[scenario]\nduration = 5.0\n'
                    '[grid]\npolicy = ["dlqr+kalman", "ctrl/mine.py:builtin_kalman"]\n')
    spec = load_spec(str(toml))
    builtin, plugin = spec.configurations
    assert builtin.plugin is None
    assert plugin.plugin == f"{(tmp_path / 'ctrl' / 'mine.py').resolve()}:builtin_kalman"
    assert plugin.values["policy"] == "ctrl/mine.py:builtin_kalman"     # as written, for tables
    rows_b, rows_p = (run_unit(u) for u in spec.units())
    strip = [{k: v for k, v in r.items() if k not in ("config", "policy")} for r in rows_b]
    assert _same(strip, [{k: v for k, v in r.items() if k not in ("config", "policy")}
                         for r in rows_p])
    with pytest.raises(PluginError, match="no file"):
        parse_spec({"grid": {"policy": ["nowhere.py:make"]}}, base_dir=tmp_path)


def test_plugins_experiment_is_shipped_and_parses():
    spec = load_spec("plugins")
    names = [c.values["policy"] for c in spec.configurations]
    assert "plugin_example.py:make" in names and "dlqr+kalman" in names
    assert all(Path(c.plugin.rpartition(":")[0]).is_file() for c in spec.configurations
               if c.plugin)


# ---- your own cart-pole model ---------------------------------------------------------------------
def _heavier_pole_model(tmp_path: Path) -> Path:
    xml = (data_dir("models") / "cartpole.xml").read_text()
    pole = 'size="0.015" mass="0.1"/>'
    assert xml.count(pole) == 1                # the pole geom of the shipped model
    path = tmp_path / "heavy_pole.xml"
    path.write_text(xml.replace(pole, 'size="0.015" mass="0.2"/>'))
    return path


def test_bench_with_your_own_model(tmp_path, capsys):
    model = _heavier_pole_model(tmp_path)
    assert load_plant(model).pole_mass == pytest.approx(0.2)
    toml = tmp_path / "small.toml"
    toml.write_text('name = "small"\nepisodes = 4\nseed = 1\n[scenario]\nduration = 2.0\n'
                    '[grid]\npolicy = ["dlqr+kalman"]\n')
    assert main(["bench", str(toml), "--out", str(tmp_path / "own"), "--quiet",
                 "--model", str(model)]) == 0
    assert main(["bench", str(toml), "--out", str(tmp_path / "shipped"), "--quiet"]) == 0
    capsys.readouterr()
    own = json.loads((tmp_path / "own" / "spec.json").read_text())
    shipped = json.loads((tmp_path / "shipped" / "spec.json").read_text())
    assert own["spec"]["model_file"] == str(model.resolve())
    assert own["fingerprint"] != shipped["fingerprint"]
    assert (tmp_path / "own" / "episodes.csv").read_text() != \
        (tmp_path / "shipped" / "episodes.csv").read_text()
    # the same model under another name gives the shipped model's episodes byte for byte
    copy = tmp_path / "copy.xml"
    copy.write_text((data_dir("models") / "cartpole.xml").read_text())
    toml.write_text(toml.read_text().replace("seed = 1\n", 'seed = 1\nmodel_file = "copy.xml"\n'))
    assert main(["bench", str(toml), "--out", str(tmp_path / "copy"), "--quiet"]) == 0
    assert (tmp_path / "copy" / "episodes.csv").read_bytes() == \
        (tmp_path / "shipped" / "episodes.csv").read_bytes()
    with pytest.raises(Exception, match="model_file: no file"):
        parse_spec({"model_file": "nowhere.xml"}, base_dir=tmp_path)


def test_a_model_whose_geoms_have_other_names_works_until_an_override_needs_them(tmp_path,
                                                                                 capsys):
    xml = (data_dir("models") / "cartpole.xml").read_text()
    renamed = xml.replace('name="cart" class="cart"', 'name="chassis" class="cart"', 1) \
                 .replace('name="pole" class="pole"', 'name="rod" class="pole"', 1)
    assert renamed.count('name="rod"') == 1 and renamed.count('name="chassis"') == 1
    path = tmp_path / "renamed.xml"
    path.write_text(renamed)
    shipped, mine = load_plant(), load_plant(path)
    assert mine.parameters() == pytest.approx(shipped.parameters(), rel=1e-12)
    assert main(["run", "--model", str(path), "--episodes", "3", "--duration", "1", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["success_rate"] == 1.0
    from pendulum_lqg.errors import ConfigError
    from pendulum_lqg.model.overrides import ModelOverrides

    with pytest.raises(ConfigError, match="the override pole_mass_scale needs a geom named 'pole'"):
        load_plant(path, overrides=ModelOverrides(pole_mass_scale=2.0))
    with pytest.raises(ConfigError, match="the override cart_mass needs a geom named 'cart'"):
        load_plant(path, overrides=ModelOverrides(cart_mass=2.0))
