"""Experiments on a plant given as matrices: ``lti_file = "lti/double_integrator.toml"``.

An experiment file that names an LTI plant file (:mod:`pendulum_lqg.model.lti`, relative to the
experiment's folder) runs its grid on that plant instead of the cart-pole, through the same loop
(its :class:`~pendulum_lqg.model.interface.Layout`): the file gives the period, the initial
state, the noise, the cost weights and the limits; the experiment chooses what a scenario
chooses beside them::

    name = "double_integrator"
    lti_file = "lti/double_integrator.toml"
    episodes = 200
    [scenario]
    duration = 20.0                  # also estimate0, force_limit, the delays, dropout
    [grid]
    policy = ["dlqr+kalman", "dlqr+luenberger"]    # dlqr/lqr + none/kalman/kalman-predictor/
    noise_scale = [0.5, 1.0]                       # luenberger

The cart-pole's keys (``x0``, ``theta_max``, ``[noise]`` densities, ``[model]``, ``model_file``,
plug-ins, studies) are refused, one line each: the LTI file holds them.
"""

from __future__ import annotations

import functools
from pathlib import Path
from typing import Any

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.problem import defaults

#: What an experiment on an LTI plant may set, per table (the file holds the rest).
LTI_TABLE_KEYS: dict[str, tuple[str, ...]] = {
    "scenario": ("duration", "estimate0", "force_limit", "measurement_delay", "actuator_delay",
                 "dropout", "burn_in"),
    "noise": ("scale",),
    "design": ("controller", "observer"),
    "model": (),
}
LTI_GRID_KEYS = ("policy", "controller", "observer", "noise_scale", "duration", "estimate0",
                 "measurement_delay", "actuator_delay", "dropout", "delay", "delay_kind")


def lti_file(value: object, base_dir: Path | None) -> str | None:
    """``lti_file`` as an absolute path (relative to the experiment file's folder, else the
    current folder: :func:`~pendulum_lqg.util.resources.find_file`), checked to exist."""
    from pendulum_lqg.util.resources import find_file

    if value is None:
        return None
    if not isinstance(value, str) or not value:
        raise ConfigError(f"lti_file: expected a path to an LTI plant file (TOML or .npz), got "
                          f"{value!r}")
    path = find_file(value, base_dir)
    if not path.is_file():
        raise ConfigError(f"lti_file: no file {value!r}")
    return str(path)


def plant_key(data: dict[str, Any], base_dir: Path | None) -> str | None:
    """The plant file of an experiment as an absolute path, ``None`` for the cart-pole: its
    ``plant`` (a shipped NAME or a plant FILE, :mod:`pendulum_lqg.model.catalog`) or the alias
    ``lti_file`` (kept one release), not both."""
    from pendulum_lqg.model.catalog import is_cartpole, plant_path, shipped_plants

    if "plant" not in data:
        return lti_file(data.get("lti_file"), base_dir)
    if "lti_file" in data:
        raise ConfigError("lti_file: not with plant (lti_file is the old name of plant)")
    value = data["plant"]
    if not isinstance(value, str) or not value.strip():
        raise ConfigError(f"plant: expected a plant name or a plant file, got {value!r}")
    if is_cartpole(value):
        return None
    if value.replace("_", "-") in shipped_plants() and Path(value).suffix == "":
        return str(plant_path(value))
    return lti_file(value, base_dir)


def check_lti_experiment(data: dict[str, Any]) -> None:
    """Refuse what an experiment on an LTI plant cannot set, one line naming the key."""
    for key in ("model_file", "study"):
        if key in data:
            raise ConfigError(f"{key}: not with lti_file (the LTI file is the plant)")
    for table, known in LTI_TABLE_KEYS.items():
        for key in data.get(table, {}):
            if key not in known:
                raise ConfigError(f"{table}.{key}: not with lti_file (the LTI file holds it); "
                                  f"[{table}] takes " + (", ".join(known) or "nothing"))
    from pendulum_lqg.policies.loading import is_plugin_ref

    for key in data.get("grid", {}):
        if key not in LTI_GRID_KEYS:
            raise ConfigError(f"grid.{key}: not with lti_file; the grid takes "
                              + ", ".join(LTI_GRID_KEYS))
    for value in data.get("grid", {}).get("policy", []):
        if is_plugin_ref(value):
            raise ConfigError(f"grid.policy: {value!r}: a plug-in takes the cart-pole's "
                              "PolicyContext; with lti_file the built-in dlqr/lqr + none/kalman/"
                              "kalman-predictor/luenberger")


@functools.lru_cache(maxsize=16)
def lti_plant(path: str) -> Any:
    """The plant of an experiment's ``lti_file`` (read once per path while a grid runs)."""
    from pendulum_lqg.model.catalog import load_plant_at

    return load_plant_at(path)


def lti_build(cfg: Any) -> tuple[Any, Any]:
    """``(Scenario, DesignSpec)`` of a configuration on an LTI plant."""
    from pendulum_lqg.policies.lqg import DesignSpec
    from pendulum_lqg.policies.lti import lti_scenario

    fields = dict(cfg.scenario)
    scenario = lti_scenario(lti_plant(cfg.lti_file), noise_scale=cfg.noise.get("scale", defaults.NOISE_SCALE),
                            duration=fields.pop("duration", 10.0), **fields)
    return scenario, DesignSpec(**cfg.design)


def lti_policy(cfg: Any, scenario: Any, spec: Any) -> Any:
    """The configuration's built-in policy designed on its LTI plant, saturating to the limit in
    force."""
    from pendulum_lqg.core.rules import limits
    from pendulum_lqg.policies.lti import design_lti_policy

    plant = lti_plant(cfg.lti_file)
    return design_lti_policy(plant, f"{spec.controller}+{spec.observer}",
                             u_max=limits(plant, scenario)[2])


def lti_fields(cfg: Any) -> tuple[str, ...]:
    """The episode columns of a configuration on an LTI plant (named after its states)."""
    from pendulum_lqg.core.metrics import layout_fields

    scenario, _ = lti_build(cfg)
    return layout_fields(lti_plant(cfg.lti_file).layout(scenario))


def lti_theory_entry(cfg: Any) -> dict[str, Any] | None:
    """The summary's ``theory`` entry of a configuration on an LTI plant: the stationary loop
    (:func:`pendulum_lqg.policies.lti.lti_theory`) in the Monte Carlo's column names; ``None`` with
    delays or dropout (the theory does not model them)."""
    from pendulum_lqg.policies.lti import lti_theory

    scenario, spec = lti_build(cfg)
    if scenario.measurement_delay or scenario.actuator_delay or scenario.dropout:
        return None
    name = f"{spec.controller}+{spec.observer}"
    plant = lti_plant(cfg.lti_file)
    res = lti_theory(plant, (name,), noise_scale=scenario.noise.scale,
                     duration=scenario.duration, estimate0=scenario.estimate0,
                     burn_in=scenario.burn_in)[name]
    out: dict[str, Any] = {"plant": f"lti:{plant.name}", "spectral_radius": res.spectral_radius,
                           "stable": res.stable}
    for s in plant.state_names:
        out[f"rms_{s}"] = res.rms[s]
        out[f"rms_est_err_{s}"] = res.estimate_error_std[s]
    if plant.n_inputs == 1:             # the theory's u_std is one input's
        out["rms_u"] = res.u_std
    out.update({f"rms_{u}": v for u, v in res.u_std_by_input.items()})
    out.update(cost_rate=res.cost_rate, cost_J=res.cost_J, verdict=res.verdict)
    ep = res.episode                 # expected over the episode from x₀, x̂₀ (after the burn-in)
    out["episode"] = {**{f"rms_{s}": v for s, v in ep.rms.items()},
                      **({"rms_u": ep.u_rms} if plant.n_inputs == 1 else {}),
                      **{f"rms_{u}": v for u, v in ep.u_rms_by_input.items()},
                      **{f"rms_est_err_{s}": v for s, v in ep.estimate_error_rms.items()},
                      "cost_J": ep.cost_J, "burn_in": ep.burn_in}
    return out
