"""A configuration asks its plant source (:mod:`pendulum_lqg.bench.sources`): the cart-pole's
MJCF or an ``lti_file``, chosen once by :func:`~pendulum_lqg.bench.sources.choose_source`."""

from __future__ import annotations

from pendulum_lqg.bench.experiments import load_spec
from pendulum_lqg.bench.results import config_fields, markdown_table, summarize_configs
from pendulum_lqg.bench.sources import EPISODE_FIELDS, MJCF, LTISource, MJCFSource, choose_source
from pendulum_lqg.model.interface import SimulatedPlant
from pendulum_lqg.model.lti import LTIPlant
from pendulum_lqg.model.plant import Plant


def test_choose_source_by_the_lti_file():
    assert choose_source(None) is MJCF and isinstance(MJCF, MJCFSource)
    assert choose_source("/x/plant.toml") == LTISource("/x/plant.toml")


def test_an_lti_experiment_asks_its_lti_source():
    spec = load_spec("double_integrator", episodes=2)
    cfg = spec.configurations[0]
    assert isinstance(cfg.source, LTISource) and cfg.source.path == cfg.lti_file
    nominal, simulated = cfg.plants()
    assert nominal is simulated and isinstance(simulated, LTIPlant)
    assert isinstance(simulated, SimulatedPlant)
    assert config_fields(cfg) == cfg.source.fields(cfg) != EPISODE_FIELDS
    assert f"rms_{simulated.state_names[0]}" in config_fields(cfg)
    theory = cfg.source.theory(cfg)
    assert theory is not None and theory["plant"] == f"lti:{simulated.name}"
    summary = summarize_configs(spec, [])
    assert "LTI plant `double_integrator.toml`" in markdown_table(spec, summary)


def test_a_cartpole_experiment_asks_the_mjcf_source():
    spec = load_spec("lecture", episodes=2)
    cfg = spec.configurations[0]
    assert cfg.source is MJCF
    nominal, simulated = cfg.plants()
    assert isinstance(nominal, Plant) and isinstance(simulated, SimulatedPlant)
    assert config_fields(cfg) == EPISODE_FIELDS
    table = markdown_table(spec, summarize_configs(spec, []))
    assert "LTI plant" not in table and "RMS θ [rad]" in table
