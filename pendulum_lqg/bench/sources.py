"""Where a configuration's plant comes from: the cart-pole's MJCF, or a plant given as matrices.

A :class:`~pendulum_lqg.bench.experiments.Configuration` asks its :class:`PlantSource`
(:func:`choose_source`) for its scenario, its plants, its built-in policy, its checks, its
episode columns and its theory, instead of asking which kind of plant it has:

* :class:`MJCFSource`: the MuJoCo cart-pole of ``model_file`` (default the shipped
  ``cartpole.xml``), with the scenario's ``[model]`` overrides on the simulated plant;
* :class:`LTISource`: the plant of an experiment's ``lti_file`` (:mod:`pendulum_lqg.bench.lti`).

The configuration is typed ``Any`` here: :mod:`pendulum_lqg.bench.experiments` imports this
module.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol

from pendulum_lqg.errors import PendulumLQGError

if TYPE_CHECKING:
    from pendulum_lqg.core.noise import NoiseModel
    from pendulum_lqg.core.scenario import Scenario
    from pendulum_lqg.model.overrides import ModelOverrides
    from pendulum_lqg.model.plant import Plant
    from pendulum_lqg.policies.spec import DesignSpec


class PlantSource(Protocol):
    """What a configuration asks of where its plant comes from (module docstring)."""

    def build(self, cfg: Any) -> tuple[Scenario, DesignSpec]:
        """``(Scenario, DesignSpec)`` of ``cfg`` (validated)."""
        ...

    def plants(self, cfg: Any, scenario: Scenario | None = None) -> tuple[Any, Any]:
        """``(nominal, simulated)``: the plant the designs believe in and the one simulated."""
        ...

    def validate(self, cfg: Any) -> None:
        """Refuse, while the experiment is parsed, what its units could not run."""
        ...

    def policy(self, cfg: Any, scenario: Scenario, spec: DesignSpec, nominal: Any) -> Any:
        """The policy of one unit of ``cfg`` (built-in or plug-in)."""
        ...

    def fields(self, cfg: Any) -> tuple[str, ...]:
        """The episode columns of ``cfg``."""
        ...

    def theory(self, cfg: Any) -> dict[str, Any] | None:
        """The summary's ``theory`` entry of ``cfg``, or ``None`` where the theory does not
        model its loop."""
        ...


@dataclass(frozen=True)
class MJCFSource:
    """The MuJoCo cart-pole of the configuration's ``model_file``."""

    def build(self, cfg: Any) -> tuple[Scenario, DesignSpec]:
        from pendulum_lqg.core.noise import NoiseModel
        from pendulum_lqg.core.scenario import Scenario
        from pendulum_lqg.model.overrides import ModelOverrides
        from pendulum_lqg.policies.spec import DesignSpec

        noise = NoiseModel(**cfg.noise)
        overrides = ModelOverrides.from_mapping(cfg.model)
        scenario = Scenario(noise=noise, overrides=overrides, **cfg.scenario)
        return scenario, DesignSpec(**cfg.design)

    def plants(self, cfg: Any, scenario: Scenario | None = None) -> tuple[Plant, Plant]:
        """The XML as it is, and the one simulated with the scenario's mismatch overrides (the
        same object when there are none)."""
        from pendulum_lqg.model.plant import load_plant

        if scenario is None:
            scenario, _ = self.build(cfg)
        overrides = scenario.overrides
        nominal = load_plant(cfg.model_file)
        simulated = nominal if overrides.is_empty() else load_plant(cfg.model_file,
                                                                    overrides=overrides)
        return nominal, simulated

    def validate(self, cfg: Any) -> None:
        """Check the control period against the (possibly overridden) model and design the
        built-in policy (once per distinct design)."""
        from pendulum_lqg.model.interface import steps_per_period
        from pendulum_lqg.policies.lqg import delay_periods

        scenario, spec = self.build(cfg)     # the Scenario checks the duration ceiling
        steps_per_period(simulated_plant(cfg.model_file, scenario.overrides),
                         scenario.control_period)
        if cfg.plugin is None:              # a plugin's factory runs with its units only
            designed(cfg.model_file, scenario.control_period, scenario.noise.with_scale(1.0),
                     spec, delay_periods(scenario))

    def policy(self, cfg: Any, scenario: Scenario, spec: DesignSpec, nominal: Any) -> Any:
        from pendulum_lqg.policies.loading import build_policy

        return build_policy(cfg.plugin, plant=nominal, scenario=scenario, spec=spec)

    def fields(self, cfg: Any) -> tuple[str, ...]:
        return EPISODE_FIELDS

    def theory(self, cfg: Any) -> dict[str, Any] | None:
        """:func:`~pendulum_lqg.policies.theory.policy_theory` on the simulated plant's exact
        ZOH linearisation; ``None`` for what the theory does not model."""
        from pendulum_lqg.policies.loading import build_policy
        from pendulum_lqg.policies.theory import policy_theory

        try:
            scenario, spec = cfg.build()
            nominal, simulated = cfg.plants(scenario)
            policy = build_policy(None, plant=nominal, scenario=scenario, spec=spec)
            res = policy_theory(simulated, scenario, policy)
        except PendulumLQGError:
            return None
        ep = res.episode
        episode = None if ep is None else {
            "rms_theta": ep.rms["theta"], "rms_p": ep.rms["p"], "rms_u": ep.u_rms,
            **{f"rms_est_err_{s}": v for s, v in ep.estimate_error_rms.items()},
            "cost_J": ep.cost_J, "burn_in": ep.burn_in}
        return {"plant": res.plant, "spectral_radius": res.spectral_radius, "stable": res.stable,
                "rms_theta": res.rms["theta"], "rms_p": res.rms["p"], "rms_u": res.u_std,
                "rms_est_err_theta": res.estimate_error_std["theta"],
                "rms_est_err_p_dot": res.estimate_error_std["p_dot"],
                "cost_rate": res.cost_rate, "cost_J": res.cost_J, "verdict": res.verdict,
                "episode": episode}


@dataclass(frozen=True)
class LTISource:
    """The plant of an experiment's ``lti_file`` (an absolute path)."""

    path: str

    def build(self, cfg: Any) -> tuple[Scenario, DesignSpec]:
        from pendulum_lqg.bench.lti import lti_build

        return lti_build(cfg)

    def plants(self, cfg: Any, scenario: Scenario | None = None) -> tuple[Any, Any]:
        """The file's plant, both nominal and simulated (a file has no mismatch)."""
        from pendulum_lqg.bench.lti import lti_plant

        lti = lti_plant(self.path)
        return lti, lti

    def validate(self, cfg: Any) -> None:
        """What its loop cannot run (:meth:`~pendulum_lqg.model.lti.LTIPlant.layout`) and its
        design, refused now."""
        scenario, spec = self.build(cfg)     # the Scenario checks the duration ceiling
        self.plants(cfg)[1].layout(scenario)
        self.policy(cfg, scenario, spec, None)

    def policy(self, cfg: Any, scenario: Scenario, spec: DesignSpec, nominal: Any) -> Any:
        from pendulum_lqg.bench.lti import lti_policy

        return lti_policy(cfg, scenario, spec)

    def fields(self, cfg: Any) -> tuple[str, ...]:
        from pendulum_lqg.bench.lti import lti_fields

        return lti_fields(cfg)

    def theory(self, cfg: Any) -> dict[str, Any] | None:
        from pendulum_lqg.bench.lti import lti_theory_entry

        return lti_theory_entry(cfg)


#: The one cart-pole source (it holds nothing: the configuration names its ``model_file``).
MJCF = MJCFSource()


def choose_source(lti_file: str | None) -> PlantSource:
    """The source of a configuration: its ``lti_file``'s plant if it names one, else the
    cart-pole's MJCF."""
    return MJCF if lti_file is None else LTISource(lti_file)


@functools.lru_cache(maxsize=32)
def simulated_plant(model_file: str | None, overrides: ModelOverrides) -> Plant:
    """The plant a configuration simulates, compiled once per (file, overrides) while a grid is
    validated (a grid over noise or policies shares one model)."""
    from pendulum_lqg.model.plant import load_plant

    return load_plant(model_file, overrides=overrides)


@functools.lru_cache(maxsize=256)
def designed(model_file: str | None, control_period: float, noise: NoiseModel,
             spec: DesignSpec, delays: tuple[int, int]) -> None:
    """Design a configuration's built-in policy on the nominal plant (the design ignores the
    noise scale; a grid over noise, model scales or policies repeats few designs)."""
    from pendulum_lqg.model.overrides import ModelOverrides
    from pendulum_lqg.policies.lqg import design_policy

    design_policy(simulated_plant(model_file, ModelOverrides()), control_period, noise, spec,
                  delays=delays)


def _cartpole_fields() -> tuple[str, ...]:
    from pendulum_lqg.core.metrics import layout_fields
    from pendulum_lqg.model.plant import CARTPOLE

    return layout_fields(CARTPOLE)


#: Columns of one episode row of the cart-pole, in order (its layout's).
EPISODE_FIELDS: tuple[str, ...] = _cartpole_fields()
