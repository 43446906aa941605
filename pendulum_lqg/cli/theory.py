"""``pendulum-lqg theory``: the stationary closed loop of built-in linear policies, in closed form
(:mod:`pendulum_lqg.analysis.theory`); the Scenario fields of the limit options ``run`` shares
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
    from pendulum_lqg.analysis.theory import lecture_theory
    from pendulum_lqg.cli.parser import jsonable, noise_from_args, spec_from_args
    from pendulum_lqg.core.scenario import Scenario
    from pendulum_lqg.names import LECTURE_POLICIES
    from pendulum_lqg.plant import load_plant

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
    _print_table(results, scenario)
    return 0


def _print_table(results: dict[str, Any], scenario: Any) -> None:
    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    con = Console(highlight=False)
    con.print(escape(f"theory — plant {scenario.plant}, T = {scenario.control_period:g} s, noise "
                     f"scale {scenario.noise.scale:g}, J over {scenario.duration:g} s; stationary, "
                     "limits off"))
    t = Table()
    for col in ("policy", "radius", "std p [m]", "std θ [rad]", "std u [N]", "std θ̂−θ [rad]",
                "J"):
        t.add_column(col)
    for name, r in results.items():
        p, th = r.state_names[:2]
        t.add_row(escape(name), f"{r.spectral_radius:.4f}", _g(r.std[p]), _g(r.std[th]),
                  _g(r.u_std), _g(r.estimate_error_std[th]), _g(r.cost_J))
    con.print(t)
    con.print("every std and the cost rate: --json")
    for name, r in results.items():
        con.print(escape(f"{name}: {r.verdict}" + "".join(f" ({n})" for n in r.notes)))


def _g(v: float) -> str:
    return "∞" if math.isinf(v) else f"{v:.3g}"
