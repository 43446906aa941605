"""``pendulum-lqg theory``: the closed loop of built-in linear policies, in closed form
(:mod:`pendulum_lqg.policies.theory`): stationary, and expected over one episode from its start;
the Scenario fields of the limit options ``run`` shares (the grammar of both is in
:mod:`pendulum_lqg.cli.parser`), and the theory lines of ``run``'s summary."""

from __future__ import annotations

import argparse
import functools
import json
import math
from typing import Any

from pendulum_lqg.model.lti import LTIPlant
from pendulum_lqg.problem import defaults

#: ``theory``'s further options of the cart-pole, refused with ``--lti`` (beside
#: :data:`~pendulum_lqg.cli.lti.CARTPOLE_OPTIONS`).
_THEORY_ONLY = {"plant": ("linear-zoh", "the file's exact sampled model is the plant"),
                "dt": (defaults.CONTROL_PERIOD, "the file's control_period"),
                "theta0": (defaults.X0[1], "the file's x0"),
                "theta_max": (defaults.THETA_MAX, "the file's state_limits"),
                "track_limit": (None, "the file's state_limits"),
                "force_limit": (None, "the file's force_limit")}


def declared_fields(args: argparse.Namespace, command: str) -> dict[str, Any]:
    """The Scenario fields of ``command``'s declared flags (:mod:`pendulum_lqg.cli.flags`): a
    setting declared for the command reaches its Scenario without a line here."""
    from pendulum_lqg.cli.flags import FLAGS
    from pendulum_lqg.core.scenario import Scenario

    return {name: getattr(args, name) for name, flag in FLAGS.items()
            if command in flag[4] and name in Scenario.__dataclass_fields__}


def cmd_theory(args: argparse.Namespace) -> int:
    from pendulum_lqg.cli.parser import jsonable, noise_from_args, spec_from_args
    from pendulum_lqg.core.scenario import Scenario
    from pendulum_lqg.model.catalog import is_cartpole
    from pendulum_lqg.model.plant import load_plant
    from pendulum_lqg.names import LECTURE_POLICIES
    from pendulum_lqg.policies.theory import lecture_theory

    if args.agent is not None:
        return _agent_theory(args)
    if args.suite is not None:
        from pendulum_lqg.errors import ConfigError

        raise ConfigError("--suite: goes with --agent linear:FILE (the theory of POLICY takes "
                          "the scenario's flags)")
    if not is_cartpole(args.plant_ref):
        return _lti_theory(args)
    plant = load_plant(args.model)
    scenario = Scenario(control_period=args.dt, plant=args.plant,
                        noise=noise_from_args(args, scale=args.noise_scale),
                        x0=(0.0, args.theta0, 0.0, 0.0), **declared_fields(args, "theory"))
    names = tuple(args.policies) or LECTURE_POLICIES
    results = lecture_theory(names, plant=plant, scenario=scenario, plant_kind=args.plant,
                             spec=spec_from_args(args))
    if args.json:
        out = {"plant": args.plant, "scenario": scenario.to_dict(),
               "policies": {name: r.to_dict() for name, r in results.items()}}
        print(json.dumps(jsonable(out), indent=2))
        return 0
    _print_table(results, f"theory — plant {scenario.plant}, T = {scenario.control_period:g} s, "
                          f"noise scale {scenario.noise.scale:g}, J over {scenario.duration:g} s; "
                          "stationary, limits off")
    _print_episode_table(results, f"expected over an episode of {scenario.duration:g} s from "
                                  f"x0 = {list(scenario.x0)}, x̂0 "
                                  f"{'= x0' if scenario.estimate0 == 'true' else '= 0'}",
                         scenario.burn_in)
    return 0


def _agent_theory(args: argparse.Namespace) -> int:
    """``theory --agent linear:FILE [--suite S]``: the controller file's exact stationary J on
    the suite's plant linearised, J* of the suite's reference and the exact gap
    (:mod:`pendulum_lqg.scoreboard.exact`)."""
    from pendulum_lqg.cli.parser import jsonable
    from pendulum_lqg.errors import ConfigError
    from pendulum_lqg.model.catalog import is_cartpole
    from pendulum_lqg.scoreboard.exact import exact_linear
    from pendulum_lqg.scoreboard.linear import linear_agent
    from pendulum_lqg.scoreboard.suites import load_suite

    if not args.agent.startswith("linear:"):
        raise ConfigError(f"--agent: expected linear:FILE.json (a linear controller file), got "
                          f"{args.agent!r}")
    if args.policies or not is_cartpole(args.plant_ref):
        raise ConfigError("--agent: give POLICY, --plant or --agent, not more than one")
    factory = linear_agent(args.agent.removeprefix("linear:"))
    suite = load_suite(args.suite if args.suite is not None else "lecture")
    res = exact_linear(suite, factory.doc)
    if args.json:
        print(json.dumps(jsonable({"agent": args.agent, "suite": suite.name,
                                   "reference": suite.reference, **res.to_dict()}), indent=2))
        return 0
    print(f"theory of {args.agent} on suite {suite.name} (its plant linearised, limits off; "
          f"J over {suite.config.scenario.duration:g} s)")
    verdict = "stable" if res.stable else "unstable: the linear loop's states grow without bound"
    print(f"spectral radius {res.spectral_radius:.6f}: {verdict}")
    if res.stable:
        print(f"stationary J {res.J:.6g}, J* ({suite.reference}) {res.J_opt:.6g}: exact gap "
              f"{res.gap:+.6f}")
        print(f"over one episode from x0: E[J] {res.episode_J:.6g}, E[J*] {res.episode_J_opt:.6g}: "
              f"gap {res.episode_gap:+.6f} (what score's Monte Carlo gap estimates)")
    return 0


def _lti_theory(args: argparse.Namespace) -> int:
    """``theory --lti FILE``: the built-in policies on a plant given as matrices."""
    from pendulum_lqg.cli.parser import jsonable
    from pendulum_lqg.model.catalog import load_named_plant
    from pendulum_lqg.policies.lti import lti_theory

    _check_lti_options(args)
    plant = load_named_plant(args.plant_ref, what="--plant")
    names = tuple(args.policies) or ("dlqr+none", "dlqr+kalman", "dlqr+luenberger")
    results = lti_theory(plant, names, noise_scale=args.noise_scale, duration=args.duration,
                         estimate0=args.estimate0, burn_in=args.burn_in)
    if args.json:
        out = {"plant": plant.name, "lti": str(args.plant_ref), "control_period": plant.control_period,
               "policies": {name: r.to_dict() for name, r in results.items()}}
        print(json.dumps(jsonable(out), indent=2))
        return 0
    _print_table(results, f"theory — {plant.kind_label} {plant.name} ({args.plant_ref}), T = "
                          f"{plant.control_period:g} s, noise scale {args.noise_scale:g}, "
                          f"J over {args.duration:g} s; stationary")
    x0 = [0.0] * plant.n_states if plant.x0 is None else [float(v) for v in plant.x0]
    _print_episode_table(results, f"expected over an episode of {args.duration:g} s from x0 = "
                                  f"{x0}, x̂0 {'= x0' if args.estimate0 == 'true' else '= 0'}",
                         args.burn_in)
    return 0


def _check_lti_options(args: argparse.Namespace) -> None:
    """Refuse, one line each, the cart-pole's options given with ``--lti``."""
    from pendulum_lqg.cli.lti import CARTPOLE_OPTIONS, refuse_cartpole_options

    refuse_cartpole_options(args, {**CARTPOLE_OPTIONS, **_THEORY_ONLY})


def _print_table(results: dict[str, Any], header: str) -> None:
    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    con = Console(highlight=False)
    con.print(escape(header))
    t = Table()
    first = next(iter(results.values()))
    shown = first.state_names[:2]                  # the first two states (one for a 1-state plant)
    unit = dict(zip(first.state_names, first.units, strict=True))
    t.add_column("policy", no_wrap=True)          # a policy's name is never cut
    u = next(iter(first.u_std_by_input), "u")    # several inputs: the first one's column
    for col in ("radius", *(_head("std", s, unit[s]) for s in shown), f"std {u}",
                _head("std error of", shown[-1], unit[shown[-1]]), "J"):
        t.add_column(escape(col))
    for name, r in results.items():
        t.add_row(escape(name), f"{r.spectral_radius:.4f}", *(_cell(r.std[s]) for s in shown),
                  _cell(r.u_std), _cell(r.estimate_error_std[shown[-1]]), _cell(r.cost_J))
    con.print(t)
    con.print("every std and the cost rate: --json")
    for name, r in results.items():
        con.print(escape(f"{name}: {r.verdict}" + "".join(f" ({n})" for n in r.notes)))


def _print_episode_table(results: dict[str, Any], header: str, burn_in: float) -> None:
    """The expected RMS over the episode (``ClosedLoopTheory.episode``), in the table's layout:
    what the simulated ``rms_*`` of a linear loop with the limits off average to (their squares)."""
    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    con = Console(highlight=False)
    first = next(iter(results.values()))
    burn = f", RMS after {first.episode.burn_in:g} s" if burn_in else ""
    con.print(escape(header + burn))
    shown = first.state_names[:2]
    unit = dict(zip(first.state_names, first.units, strict=True))
    t = Table()
    t.add_column("policy", no_wrap=True)
    u = next(iter(first.u_std_by_input), "u")
    for col in (*(_head("RMS", s, unit[s]) for s in shown), f"RMS {u}",
                _head("RMS error of", shown[-1], unit[shown[-1]]), "E[J]"):
        t.add_column(escape(col))
    for name, r in results.items():
        ep = r.episode
        t.add_row(escape(name), *(_cell(ep.rms[s]) for s in shown), _cell(ep.u_rms),
                  _cell(ep.estimate_error_rms[shown[-1]]), _cell(ep.cost_J))
    con.print(t)


def run_theory_lines(plant: Any, scenario: Any, policy: Any) -> tuple[dict[str, Any] | None,
                                                                      list[str]]:
    """The theory beside ``run``'s Monte Carlo: the closed loop of ``policy`` on the linear model
    of ``plant`` (the linearisation for the cart-pole, the file's model for an LTI plant) with the
    limits off, as ``(to_dict() or None, lines to print)``; a loop the theory does not model
    (plug-ins, delays, dropout, lags, force noise) gives ``None`` and one line saying why."""
    from pendulum_lqg.errors import PendulumLQGError

    if getattr(policy, "K", None) is None or getattr(policy, "estimator", None) is None:
        return None, ["theory: not for this loop (a plug-in policy; the theory takes the "
                      "built-in linear ones)"]
    if not scenario.randomize.is_empty():
        return None, ["theory: not for this loop (randomised plants)"]
    try:
        res = _loop_theory(plant, scenario, policy)
    except PendulumLQGError as exc:
        return None, [f"theory: not for this loop ({exc})"]
    ep = res.episode
    after = f" after {ep.burn_in:g} s" if ep.skip else ""
    names = res.state_names
    lines = [f"theory ({res.plant} loop, limits off), expected RMS over the episode{after}: "
             + _values(names, ep.rms, ep.u_rms_by_input or {"u": ep.u_rms},
                       ep.estimate_error_rms),
             "theory, stationary std: " + _values(names, res.std,
                                                   res.u_std_by_input or {"u": res.u_std},
                                                   res.estimate_error_std)]
    return res.to_dict(), lines


@functools.singledispatch
def _loop_theory(plant: Any, scenario: Any, policy: Any) -> Any:
    """The cart-pole's stationary loop (:func:`~pendulum_lqg.policies.theory.policy_theory`)."""
    from pendulum_lqg.policies.theory import policy_theory

    return policy_theory(plant, scenario, policy)


@_loop_theory.register(LTIPlant)
def _lti_loop_theory(plant: LTIPlant, scenario: Any, policy: Any) -> Any:
    """A plant given as matrices: its own stationary loop
    (:func:`~pendulum_lqg.policies.lti.lti_theory`), of the plain sampled loop only."""
    from pendulum_lqg.errors import PendulumLQGError
    from pendulum_lqg.policies.lti import lti_theory

    name = str(policy.name)
    for field in ("measurement_delay", "actuator_delay", "dropout"):
        if getattr(scenario, field):
            raise PendulumLQGError(f"{field}: the theory covers the plain sampled loop")
    return lti_theory(plant, (name,), noise_scale=scenario.noise.scale,
                      duration=scenario.n_periods * scenario.control_period,
                      estimate0=scenario.estimate0, burn_in=scenario.burn_in)[name]


def _values(names: tuple[str, ...], x: dict[str, float], u: dict[str, float],
            err: dict[str, float]) -> str:
    """``p 0.1, θ 0.02, …, u 0.3; error p 0.01, …`` with 4 significant digits (each input by
    name)."""
    label = {"theta": "θ", "p_dot": "ṗ", "theta_dot": "θ̇"}
    states = ", ".join(f"{label.get(s, s)} {x[s]:.4g}" for s in names)
    errors = ", ".join(f"{label.get(s, s)} {err[s]:.4g}" for s in names)
    inputs = ", ".join(f"{k} {v:.4g}" for k, v in u.items())
    return f"{states}, {inputs}; estimate error {errors}"


def _head(what: str, name: str, unit: str) -> str:
    label = {"theta": "θ", "p": "p"}.get(name, name)
    return f"{what} {label}" + (f" [{unit}]" if unit else "")


def _cell(v: float) -> str:
    return "∞" if math.isinf(v) else f"{v:.3g}"
