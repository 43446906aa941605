"""``pendulum-lqg score`` and ``pendulum-lqg board``: agents and policies meet LQG on the suites."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any


def add_parsers(sub: Any) -> None:
    """The ``score`` and ``board`` subcommands (``sub``: the command's subparsers)."""
    from pendulum_lqg.cli.options import Kind

    p = sub.add_parser(
        "score", help="score a policy or a Gymnasium agent on the suites (success, J, gap to LQG)",
        description="Play the suites' fixed episodes with a built-in policy (controller+observer), "
                    "a plug-in (MODULE:ATTR or path.py:ATTR) or a Gymnasium agent (--agent), and "
                    "report per suite the success rate, the mean cost J of the successes and the "
                    "optimality gap to the suite's reference LQG design.")
    p.add_argument("policy", nargs="?", default=None, metavar="POLICY",
                   help="built-in 'controller+observer' (e.g. dlqr+kalman) or plug-in MODULE:ATTR / "
                        "path.py:ATTR, run through the batch")
    p.add_argument("--agent", default=None, metavar="REF",
                   help="a Gymnasium agent instead of POLICY (default: none): MODULE:ATTR or "
                        "path.py:ATTR naming a factory f(env) -> object with reset() and act(obs); "
                        "or sb3:PATH.zip (a stable-baselines3 model, the rl extra), or "
                        "linear:FILE.json (a linear controller of a y/u history)")
    p.add_argument("--suite", action="append", default=None, metavar="NAME",
                   help="suite name or file (repeatable), or 'all' (the default): "
                        "full-state, lecture, mismatch, delayed, lossy, noisy, hard; a file "
                        "naming an lti_file is a suite of that plant (built-in policies and "
                        "linear:FILE only)")
    add_plant_option(p, "score on the plant's own suite: its plant file's scenario, 100 "
                        "episodes of 10 s seeded 2026, the reference dlqr+kalman designed on it "
                        "(built-in policies and --agent linear:FILE; not with --suite). "
                        "cartpole: the shipped suites, as without --plant")
    p.add_argument("--episodes", type=Kind("PositiveInt"), default=None, metavar="N",
                   help="episodes per suite (default: the suite's own, 100; fewer is a quick "
                        "score whose fingerprint differs from the full one)")
    p.add_argument("--normalize-action", action="store_true",
                   help="Gymnasium agents act in [-1, 1] (the env's normalize_action)")
    p.add_argument("--noise-scale", type=Kind("NonNegative"), default=None, metavar="X",
                   help="play every suite with its env's noise_scale set to X (both noises' std "
                        "times X; the designs keep the nominal noise): the noise ladder; the "
                        "suites' fingerprints then differ from the shipped ones unless X is their "
                        "own (default: each suite's own noise)")
    p.add_argument("--nthread", type=Kind("PositiveInt"), default=None,
                   help="physics threads of the batch path (default: the CPU cores, at most 8)")
    p.add_argument("--json", action="store_true", help="print the score file (JSON) instead")
    p.add_argument("--out", default=None, metavar="FILE",
                   help="also write the score file here (a new path or a regular file, replaced "
                        "only once the score is complete)")
    add_call_timeout(p)

    p = sub.add_parser("board", help="turn a folder of score files into a Markdown leaderboard",
                       description="Read the score files (*.json) of DIR and print one Markdown "
                                   "table: a row per entry, a column group per suite.")
    p.add_argument("dir", metavar="DIR", help="folder of score files (pendulum-lqg score --out)")
    p.add_argument("--out", default=None, metavar="FILE",
                   help="write the table to FILE too (a new path or a regular file)")


def add_plant_option(p: argparse.ArgumentParser, what: str) -> None:
    """``--plant NAME|FILE`` of ``score`` and ``train`` (``args.plant_ref``; checked by
    :func:`~pendulum_lqg.cli.parser.resolve_plant_option` as every front end's)."""
    p.add_argument("--plant", dest="plant_ref", default=None, metavar="NAME|FILE",
                   help="the plant: a shipped one (cartpole, double-cartpole, …; see "
                        "docs/family.md) or a plant file (TOML: an MJCF model's, or a plant "
                        f"given as matrices; .npz) (default: the cart-pole): {what}")


def add_call_timeout(p: argparse.ArgumentParser) -> None:
    """``--call-timeout S``: the watchdog of user code (:mod:`pendulum_lqg.util.watchdog`)."""
    from pendulum_lqg.cli.options import Kind

    p.add_argument("--call-timeout", type=Kind("NonNegative"), default=None, metavar="S",
                   help="stop the run, naming the call, when one call into a plug-in or agent "
                        "(factory, reset, act) has not returned after S seconds; 0: never "
                        "(default 600)")


def cmd_score(args: argparse.Namespace) -> int:
    from pendulum_lqg.scoreboard.lti_suite import names_an_lti_plant
    from pendulum_lqg.scoreboard.score import score_entry
    from pendulum_lqg.scoreboard.suites import load_suite, suite_names
    from pendulum_lqg.util.files import atomic_write, output_file
    from pendulum_lqg.util.progress import Progress
    from pendulum_lqg.util.watchdog import call_timeout

    out = None if args.out is None else output_file("--out", args.out, what="score (JSON)")
    plant = _plant_suites(args)
    wanted = args.suite or ["all"]
    names = [] if plant else suite_names() if "all" in wanted else wanted
    lti = [n for n in names if names_an_lti_plant(n)]    # a plant given as matrices
    if lti and args.plant_ref is not None:
        raise cfg_error(f"--plant: {args.plant_ref!r} plays the shipped cart-pole suites; --suite "
                        f"{lti[0]} is a suite of another plant: give one")
    suites = [load_suite(n).with_episodes(args.episodes) for n in names if n not in lti]
    with call_timeout(args.call_timeout), Progress("score", len(suites), unit="suites") as bar:
        doc = score_entry(suites, policy=args.policy, agent=args.agent,
                          normalize_action=args.normalize_action, nthread=args.nthread,
                          base_dir=Path.cwd(), noise_scale=args.noise_scale,
                          on_suite=lambda name: bar.advance(description=f"scored {name}"))
    if lti or plant:
        doc["suites"].update(_lti_entries(args, lti, plant))
    text = json.dumps(doc, indent=1, allow_nan=False)
    if out is not None:
        atomic_write(out, text + "\n")
    if args.json:
        print(text)
    else:
        _print_score(doc)
    return 0


def _plant_suites(args: argparse.Namespace) -> list[Any]:
    """``--plant NAME|FILE``'s own suite (:func:`~pendulum_lqg.scoreboard.lti_suite.plant_suite`),
    none for the cart-pole (its suites are the shipped ones); refused with ``--suite``, which
    names other suites."""
    from pendulum_lqg.model.catalog import is_cartpole
    from pendulum_lqg.scoreboard.lti_suite import plant_suite

    if is_cartpole(args.plant_ref):
        return []
    if args.suite:
        raise cfg_error(f"--plant: {args.plant_ref!r} is scored on its own suite; --suite "
                        f"{args.suite[0]} names another: give one")
    return [plant_suite(args.plant_ref)]


def _lti_entries(args: argparse.Namespace, files: list[str],
                 plant: list[Any]) -> dict[str, Any]:
    """The entries of the LTI suites among ``--suite`` and of ``--plant``'s suite
    (:mod:`pendulum_lqg.scoreboard.lti_suite`)."""
    from pendulum_lqg.scoreboard.lti_suite import load_lti_suite, lti_suite_entries

    return lti_suite_entries([*(load_lti_suite(f) for f in files), *plant], policy=args.policy,
                             agent=args.agent, episodes=args.episodes,
                             noise_scale=args.noise_scale, nthread=args.nthread)


def cfg_error(msg: str) -> Exception:
    from pendulum_lqg.errors import ConfigError

    return ConfigError(msg)


def _print_score(doc: dict[str, Any]) -> None:
    def f(v: Any, fmt: str) -> str:
        return "–" if v is None else format(v, fmt)

    print(f"score of {doc['policy']} ({doc['kind']})")
    print("| suite | episodes | success [95 % CI] | J (successes) | gap to reference [95 % CI] | "
          "exact gap: stationary, episode | reference: success, J | full-state LQR: success, J |")
    print("|---|---|---|---|---|---|---|---|")
    for name, e in doc["suites"].items():
        if not e["applicable"]:
            print(f"| {name} | {e['episodes']} | not applicable: {e['reason']} | | | | | |")
            continue
        lo, hi = e["success_ci"]
        glo, ghi = e["gap_ci"]
        gap = f(e["optimality_gap"], "+.3f") + ("" if glo is None else f" [{glo:+.3f}, {ghi:+.3f}]")
        ref, full = e["reference"], e["full_state_bound"]
        cost = f(e["cost_mean"], ".3g") + ("" if e["cost_se"] is None else f" ± {e['cost_se']:.2g}")
        print(f"| {name} | {e['episodes']} | {100 * e['success_rate']:.0f} % [{100 * lo:.0f}, "
              f"{100 * hi:.0f}] | {cost} | {gap} | {_exact_cell(e.get('exact'))} | {ref['policy']}: "
              f"{100 * ref['success_rate']:.0f} %, {f(ref['cost_mean'], '.3g')} | "
              f"{100 * full['success_rate']:.0f} %, {f(full['cost_mean'], '.3g')} |")
    sys.stdout.flush()


def _exact_cell(exact: dict[str, Any] | None) -> str:
    """The exact gap's cell (:mod:`pendulum_lqg.scoreboard.exact`): ``+0.0200, +0.0162``, the
    unstable linear loop, or – where the theory has no single linear loop (a plug-in, a
    randomised plant, delays)."""
    if exact is None or "reason" in exact:
        return "–"
    if not exact["stable"]:
        return f"unstable (radius {exact['spectral_radius']:.4f})"
    if exact["gap"] is None:         # J* = 0: a noise-free suite's stationary cost, no ratio
        return "– (the reference's J is 0)"
    return f"{exact['gap']:+.4f}, {exact['episode_gap']:+.4f}"


def cmd_board(args: argparse.Namespace) -> int:
    from pendulum_lqg.scoreboard.board import make_board
    from pendulum_lqg.util.files import atomic_write, output_file

    out = None if args.out is None else output_file("--out", args.out, what="board (Markdown)")
    table = make_board(Path(args.dir), warn=lambda line: print(line, file=sys.stderr))
    if out is not None:
        atomic_write(out, table)
    print(table, end="")
    return 0
