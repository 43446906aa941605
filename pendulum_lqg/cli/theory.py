"""``pendulum-lqg theory``: the stationary closed loop of built-in linear policies, in closed form
(:mod:`pendulum_lqg.analysis.theory`), and the limit options ``run`` shares."""

from __future__ import annotations

import argparse
import json
import math
from collections.abc import Callable
from typing import Any


def _limit(text: str) -> float:
    """argparse type: a positive number of the limit's unit, or ``inf`` (no limit)."""
    try:
        v = float(text)
    except ValueError:
        v = -1.0
    if not v > 0:                                    # also refuses nan
        raise argparse.ArgumentTypeError(f"expected a positive number or inf, got {text!r}")
    return v


def add_limit_options(p: argparse.ArgumentParser) -> None:
    """``--theta-max``, ``--track-limit``, ``--force-limit`` (``inf`` switches one off)."""
    g = p.add_argument_group("limits (inf switches a limit off; core/rules.py applies them)")
    g.add_argument("--theta-max", type=_limit, default=0.5, metavar="RAD",
                   help="failure when |θ| exceeds this, in rad (default 0.5)")
    g.add_argument("--track-limit", type=_limit, default=None, metavar="M",
                   help="failure when |p| reaches this, in m (default: the MJCF slider range, "
                        "±2.4 m; beyond it only on a linear plant)")
    g.add_argument("--force-limit", type=_limit, default=None, metavar="N",
                   help="saturation |u| ≤ this, in N (default: the MJCF ctrlrange, ±10 N; "
                        "beyond it only on a linear plant)")


def limit_fields(args: argparse.Namespace) -> dict[str, Any]:
    """The Scenario fields of the limit options."""
    return {"theta_max": args.theta_max, "track_limit": args.track_limit,
            "force_limit": args.force_limit}


def add_parser(sub: Any, add_design_options: Callable[[argparse.ArgumentParser], None],
               number: Callable[[str], float]) -> None:
    """The ``theory`` subcommand."""
    from pendulum_lqg.names import LECTURE_POLICIES

    p = sub.add_parser(
        "theory", help="stationary closed loop of linear policies in closed form (no simulation)",
        description="For each built-in linear policy on the linearised, discretised plant: the "
                    "closed loop of plant and estimator under the scenario's noise, its "
                    "eigenvalues and spectral radius, and from one discrete Lyapunov equation "
                    "the stationary std of p, θ, ṗ, θ̇, u and of the estimation error, the cost "
                    "rate and the J it implies. The limits are off in the theory; the verdict "
                    "compares the spread with them.")
    p.add_argument("policies", nargs="*", metavar="POLICY",
                   help="built-in policies 'controller+observer' (default: the lecture study's "
                        + ", ".join(LECTURE_POLICIES) + ")")
    p.add_argument("--plant", choices=("linear-zoh", "linear-euler"), default="linear-zoh",
                   help="the linear plant: exact ZOH of the linearisation, or the lecture's "
                        "forward Euler at the control period (default linear-zoh)")
    p.add_argument("--noise-scale", type=number, default=1.0,
                   help="multiplies both noises' standard deviations (default 1)")
    p.add_argument("--duration", type=number, default=10.0,
                   help="episode length in s for the implied J (default 10)")
    p.add_argument("--json", action="store_true",
                   help="machine-readable output: policies.NAME.{spectral_radius, stable, std, "
                        "u_std, estimate_error_std, cost_rate, …}")
    add_limit_options(p)
    add_design_options(p)


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
