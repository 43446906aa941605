"""``pendulum-lqg run --plant NAME|FILE``: seeded episodes of a plant given by a plant file — an
MJCF model's (:mod:`pendulum_lqg.model.mjcf`) or a plant given as matrices
(:mod:`pendulum_lqg.model.lti`) — through the same loop as the cart-pole, summarised with the
file's state names. (``--lti FILE`` is ``--plant FILE``'s old name.)"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from pendulum_lqg.cli.parser import cfg_error, jsonable
from pendulum_lqg.problem import defaults

#: Options that describe the cart-pole, shared by ``run``, ``theory`` and ``design``: with ``--lti``
#: the file says them instead (their value when not given, and what the file holds in their place).
CARTPOLE_OPTIONS = {"model": (None, "the file is the plant"),
                    "q": (None, "the file's Q"), "r": (None, "the file's R"),
                    "w": (None, "the file's W"), "v": (None, "the file's V"),
                    "observer_poles": (None, "the file's observer_poles"),
                    "process_noise": ("state", "the file's G and W")}
#: ``run``'s further options of the cart-pole.
_RUN_ONLY = {"theta0": (defaults.X0[1], "the file's x0"),
             "theta_max": (defaults.THETA_MAX, "the file's state_limits"),
             "track_limit": (None, "the file's state_limits"),
             "record": (None, "recordings draw the cart-pole"),
             "spawn": (False, "recordings draw the cart-pole"),
             "randomize": (None, "it randomises the cart-pole's model")}


def refuse_cartpole_options(args: argparse.Namespace,
                            options: dict[str, tuple[Any, str]]) -> None:
    """Refuse, one line each, an option of ``options`` (``{dest: (default, what the file holds
    instead)}``) given with a plant file (``--plant NAME|FILE``). An option given at its default
    cannot be told apart from one not given, and is not refused."""
    for option, (default, why) in options.items():
        if getattr(args, option) != default:
            raise cfg_error(f"--{option.replace('_', '-')}: not with --plant {args.plant_ref} "
                            f"({why})")


def plant_simulator(args: argparse.Namespace, plant: Any) -> str:
    """The simulator of ``run --plant``: ``--simulator`` if the plant can be stepped by it; its
    own default when the option was left at ``mujoco`` (a matrix plant's exact sampled model)."""
    if args.plant in plant.simulators:
        return str(args.plant)
    if args.plant == "mujoco":
        return str(plant.default_simulator)
    raise cfg_error(f"--simulator: the plant {plant.name!r} is simulated by "
                    f"{' or '.join(plant.simulators)}, got {args.plant!r}")


#: The scenario fields an LTI plant runs with (the others describe the cart-pole; the file holds
#: their counterparts, reported beside them in the configuration).
_SCENARIO_FIELDS = ("control_period", "duration", "estimate0", "force_limit", "plant",
                    "measurement_delay", "actuator_delay", "dropout", "burn_in")


def lti_run_setup(args: argparse.Namespace, name: str) -> tuple[Any, Any, Any, dict[str, Any]]:
    """``run`` with ``--lti FILE`` (``name``: the policy, ``controller+observer``): the plant, the
    scenario, the policy and the configuration to report; ``cmd_run`` runs them."""
    from pendulum_lqg.core.rules import limits
    from pendulum_lqg.model.catalog import load_named_plant
    from pendulum_lqg.policies.loading import build_policy, is_plugin_ref
    from pendulum_lqg.policies.lti import design_lti_policy, lti_scenario
    from pendulum_lqg.util.limits import MAX_RUN_EPISODES, check_at_most

    _check_options(args)
    plant = load_named_plant(args.plant_ref, what="--plant")
    if not math.isclose(args.dt, plant.control_period) and args.dt != 0.01:
        raise cfg_error(f"--dt: the {plant.kind_label} {plant.name!r} is sampled at "
                        f"{plant.control_period:g} s (its file's control_period); leave --dt out")
    scenario = lti_scenario(plant, duration=args.duration, noise_scale=args.noise_scale,
                            estimate0=args.estimate0, force_limit=args.force_limit,
                            measurement_delay=args.measurement_delay,
                            actuator_delay=args.actuator_delay, dropout=args.dropout,
                            actuator_tau=args.actuator_tau, burn_in=args.burn_in,
                            simulator=plant_simulator(args, plant))
    lay = plant.layout(scenario)
    u_max = limits(plant, scenario)[2]
    policy = (build_policy(name, plant=plant, scenario=scenario, base_dir=Path.cwd())
              if is_plugin_ref(name) else design_lti_policy(plant, name, u_max=u_max))
    check_at_most("--episodes", args.episodes, MAX_RUN_EPISODES,
                  "run keeps every row in memory; bench streams larger studies to disk")
    config = {"policy": name, "seed": args.seed, "episodes": args.episodes,
              "lti": str(args.plant_ref), "plant": plant.name, "kind": plant.kind_label,
              "states": list(lay.states),
              "outputs": list(lay.outputs), "x0": lay.x0.tolist(), "x0_std": lay.x0_std.tolist(),
              "force_limit": _limit(u_max),       # a switched-off limit: "inf", as in "scenario"
              "state_limits": [_limit(v) for v in np.asarray(lay.state_limits).tolist()],
              "scenario": {k: v for k, v in scenario.to_dict().items() if k in _SCENARIO_FIELDS}}
    config["scenario"]["noise"] = {"scale": scenario.noise.scale}     # W and V: the file's
    return plant, scenario, policy, config


def lti_report(args: argparse.Namespace, config: dict[str, Any], scenario: Any,
               rows: list[dict[str, Any]], *,
               theory: tuple[dict[str, Any] | None, list[str]] = (None, [])) -> int:
    """Print the summary of ``run --lti``'s episode ``rows`` (``--json``: every row too) and
    ``theory`` (:func:`pendulum_lqg.cli.theory.run_theory_lines`)."""
    from pendulum_lqg.core.metrics import summarize, summary_metrics
    from pendulum_lqg.version import SCHEMA_VERSION

    fields = tuple(rows[0])
    summary = summarize(rows, summary_metrics(fields))
    if args.json:
        out = {"schema_version": SCHEMA_VERSION, "config": config,
               "success_rate": summary["success_rate"], "success_ci95": summary["success_ci95"],
               "summary": summary, "theory": theory[0], "episodes": rows}
        print(json.dumps(jsonable(out), indent=2))
    else:
        _print_summary(config, scenario, summary, fields)
        print("\n".join(theory[1]))
    return 0


def _limit(value: Any) -> Any:
    """A limit for the configuration: ``"inf"`` for none; one per input as a list."""
    if np.ndim(value):
        return [_limit(v) for v in np.asarray(value).tolist()]
    return "inf" if math.isinf(value) else value


def _check_options(args: argparse.Namespace) -> None:
    """Refuse, one line each, the cart-pole's options given with a plant file."""
    refuse_cartpole_options(args, {**CARTPOLE_OPTIONS, **_RUN_ONLY})


def _print_summary(config: dict[str, Any], scenario: Any, s: dict[str, Any],
                   fields: tuple[str, ...]) -> None:
    from rich.console import Console
    from rich.markup import escape

    from pendulum_lqg.core.metrics import summary_metrics

    con = Console(highlight=False)
    con.print(escape(f"{config['policy']} on the {config['kind']} {config['plant']} ({config['lti']}) — "
                     f"{s['episodes']} episodes, seed {config['seed']}, "
                     f"T = {scenario.control_period:g} s, {scenario.duration:g} s, noise scale "
                     f"{scenario.noise.scale:g}, x0 = {config['x0']}, force limit "
                     f"{config['force_limit']}"))
    con.print(success_line(s))
    t = metric_table()
    for key in summary_metrics(fields):
        scale = SATURATED_SCALE if key == "saturated_fraction" else 1.0
        m, se = s[key]["mean"] * scale, s[key]["se"] * scale
        cell = "–" if m != m else (f"{m:.4g}" if se != se else f"{m:.4g} ± {se:.2g}")
        t.add_row(escape(_label(key)), cell)
    con.print(t)


#: How every run summary shows ``saturated_fraction``, on any plant: a percentage of the episode.
SATURATED_LABEL, SATURATED_SCALE = "time saturated [% of the episode]", 100.0


def _label(key: str) -> str:
    """A metric's row label: ``rms_est_err_position`` → "RMS estimate error of position"."""
    if key == "cost":
        return "J = ∫xᵀQx + uᵀRu dt (successes)"
    if key == "saturated_fraction":
        return SATURATED_LABEL
    if key == "time_to_failure":
        return "time to failure [s] (failures)"
    if key.startswith("max_abs_"):
        return f"max |{key[8:]}|"
    for prefix, text in (("rms_est_err_", "RMS estimate error of "), ("rms_", "RMS ")):
        if key.startswith(prefix):
            return text + key[len(prefix):]
    return key


def success_line(summary: dict[str, Any]) -> str:
    """The run summary's first line: successes, the rate with its Wilson interval, the failures
    (rich markup, escaped where it holds data). Shared by ``run`` on any plant."""
    from rich.markup import escape

    s = summary
    lo, hi = s["success_ci95"]
    return (f"success: {s['successes']}/{s['episodes']} = {s['success_rate']:.1%} "
            f"(95 % Wilson CI {lo:.1%} – {hi:.1%})"
            + escape(f"; failures: {s['failures']}" if s["failures"] else ""))


def metric_table() -> Any:
    """The empty two-column table of a run's metrics (``metric``, ``mean ± s.e.``)."""
    from rich.table import Table

    t = Table()
    t.add_column("metric")
    t.add_column("mean ± s.e.")
    return t
