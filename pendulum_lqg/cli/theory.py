"""``pendulum-lqg theory``: the stationary closed loop of built-in linear policies, in closed form
(:mod:`pendulum_lqg.policies.theory`); the Scenario fields of the limit options ``run`` shares
(the grammar of both is in :mod:`pendulum_lqg.cli.parser`)."""

from __future__ import annotations

import argparse
import json
import math
from typing import Any


def limit_fields(args: argparse.Namespace) -> dict[str, Any]:
    """The Scenario fields of the limit options."""
    return {"theta_max": args.theta_max, "track_limit": args.track_limit,
            "force_limit": args.force_limit}


def cmd_theory(args: argparse.Namespace) -> int:
    from pendulum_lqg.cli.parser import jsonable, noise_from_args, spec_from_args
    from pendulum_lqg.core.scenario import Scenario
    from pendulum_lqg.model.plant import load_plant
    from pendulum_lqg.names import LECTURE_POLICIES
    from pendulum_lqg.policies.theory import lecture_theory

    if args.lti is not None:
        return _lti_theory(args)
    plant = load_plant(args.model)
    scenario = Scenario(control_period=args.dt, duration=args.duration, plant=args.plant,
                        noise=noise_from_args(args, scale=args.noise_scale), **limit_fields(args))
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
    return 0


def _lti_theory(args: argparse.Namespace) -> int:
    """``theory --lti FILE``: the built-in policies on a plant given as matrices."""
    from pendulum_lqg.cli.parser import jsonable
    from pendulum_lqg.model.lti import load_lti
    from pendulum_lqg.policies.lti import lti_theory

    plant = load_lti(args.lti)
    names = tuple(args.policies) or ("dlqr+none", "dlqr+kalman", "dlqr+luenberger")
    results = lti_theory(plant, names, noise_scale=args.noise_scale, duration=args.duration)
    if args.json:
        out = {"plant": plant.name, "lti": str(args.lti), "control_period": plant.control_period,
               "policies": {name: r.to_dict() for name, r in results.items()}}
        print(json.dumps(jsonable(out), indent=2))
        return 0
    _print_table(results, f"theory — LTI plant {plant.name} ({args.lti}), T = "
                          f"{plant.control_period:g} s, noise scale {args.noise_scale:g}, "
                          f"J over {args.duration:g} s; stationary")
    return 0


def _print_table(results: dict[str, Any], header: str) -> None:
    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    con = Console(highlight=False)
    con.print(escape(header))
    t = Table()
    first = next(iter(results.values()))
    a, b = first.state_names[:2]
    unit = dict(zip(first.state_names, first.units, strict=True))
    t.add_column("policy", no_wrap=True)          # a policy's name is never cut
    for col in ("radius", _head("std", a, unit[a]), _head("std", b, unit[b]), "std u",
                _head("std error of", b, unit[b]), "J"):
        t.add_column(escape(col))
    for name, r in results.items():
        p, th = r.state_names[:2]
        t.add_row(escape(name), f"{r.spectral_radius:.4f}", _cell(r.std[p]), _cell(r.std[th]),
                  _cell(r.u_std), _cell(r.estimate_error_std[th]), _cell(r.cost_J))
    con.print(t)
    con.print("every std and the cost rate: --json")
    for name, r in results.items():
        con.print(escape(f"{name}: {r.verdict}" + "".join(f" ({n})" for n in r.notes)))


def _head(what: str, name: str, unit: str) -> str:
    label = {"theta": "θ", "p": "p"}.get(name, name)
    return f"{what} {label}" + (f" [{unit}]" if unit else "")


def _cell(v: float) -> str:
    return "∞" if math.isinf(v) else f"{v:.3g}"
