"""The command line's grammar and its conversions: every subcommand, its options, their one-line
checks (exit 2), and the arguments turned into library objects."""

from __future__ import annotations

import argparse
import re
import sys
from typing import Any, NoReturn

from pendulum_lqg.cli.score import add_call_timeout
from pendulum_lqg.cli.score import add_parsers as add_score_parsers
from pendulum_lqg.cli.train import add_train_parser
from pendulum_lqg.names import CONTROLLERS, LECTURE_POLICIES, OBSERVERS, PLANTS
from pendulum_lqg.problem import defaults
from pendulum_lqg.version import __version__

EXIT_USAGE = 2


#: The file ``run --spawn`` writes when no ``--record FILE`` is given.
DEFAULT_RECORDING = "recording.rrd"


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors, and values that start with a minus sign taken as values.

    ``--observer-poles -2,-3,-4,-5`` or ``--theta0 -0.1``: argparse's own rule treats only plain
    negative numbers (``-2``) as values; here anything that starts with ``-`` followed by a digit
    or a dot (comma lists, complex poles like ``-1+2j``) is a value too, since no option of the
    command looks like that.
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = re.compile(r"^-\.?\d")

    def error(self, message: str) -> NoReturn:  # one line, status 2, no traceback
        self.print_usage(sys.stderr)
        print(f"error: {message}", file=sys.stderr)
        raise SystemExit(EXIT_USAGE)


def Kind(kind: str, *, each: bool = False) -> Any:
    """:class:`pendulum_lqg.cli.options.Kind`, imported when a parser is built (``import
    pendulum_lqg.cli`` loads neither the flags nor their checks)."""
    from pendulum_lqg.cli.options import Kind as DeclaredKind

    return DeclaredKind(kind, each=each)


def add_flags(p: argparse.ArgumentParser, command: str) -> None:
    """The declared flags of ``command`` (:func:`pendulum_lqg.cli.options.add_flags`)."""
    from pendulum_lqg.cli.options import add_flags as add_declared

    add_declared(p, command)


def _add_design_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("design")
    g.add_argument("--plant", dest="plant_ref", default=None, metavar="NAME|FILE",
                   help="the plant: a shipped one (cartpole, double-cartpole, …; see "
                        "docs/family.md) or a plant file (TOML: an MJCF model's, or a plant "
                        "given as matrices; .npz) (default: the cart-pole). The simulator words "
                        "mujoco, linear-zoh and linear-euler are still taken here as "
                        "--simulator, for one release")
    g.add_argument("--model", default=None, metavar="XML",
                   help="the cart-pole's MJCF model file (default: the bundled "
                        "models/cartpole.xml); any other MuJoCo model is a plant file, --plant")
    g.add_argument("--dt", type=Kind("Finite"), default=defaults.CONTROL_PERIOD, metavar="T",
                   help="control period T in seconds, a whole number (≤ 10 000) of the model's "
                        f"physics steps and at most 1 s (default {defaults.CONTROL_PERIOD:g})")
    g.add_argument("--q", type=Kind("Finite", each=True), default=None, metavar="Q1,..,Q4",
                   help="diagonal of the LQR state weight Q, units of [m⁻², rad⁻², (m/s)⁻², "
                        "(rad/s)⁻²] (default 1,1,1,1)")
    g.add_argument("--r", type=Kind("Finite"), default=None, help="LQR input weight R in N⁻² (default 1)")
    g.add_argument("--observer-poles", type=Kind("Complex", each=True), default=None, metavar="P1,..,P4",
                   help="continuous-time Luenberger poles in rad/s, e.g. --observer-poles "
                        "-2,-3,-4,-5 or -1+2j,-1-2j,-3,-4 (default -0.4,-0.5,-0.6,-0.7); "
                        "discrete designs use z = exp(s·T)")
    g.add_argument("--w", type=Kind("Finite", each=True), default=None, metavar="W",
                   help="process-noise spectral density, diagonal: 4 values (m²·s, rad²·s, …) "
                        "for state noise, 2 (N²·s, N²m²·s) for force noise (default the "
                        "lecture's 4e-4 on every state)")
    g.add_argument("--v", type=Kind("Finite", each=True), default=None, metavar="V",
                   help="measurement-noise covariance per sample, diagonal (m², rad²; default "
                        "0.01,0.01)")
    g.add_argument("--process-noise", choices=("state", "force"), default="state",
                   help="where process noise enters: the state (F = I₄, lecture) or generalised "
                        "forces on slider and hinge (default state)")


def add_theory_parser(sub: Any) -> None:
    """The ``theory`` subcommand."""
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
    p.add_argument("--simulator", dest="plant", choices=("linear-zoh", "linear-euler"),
                   default="linear-zoh",
                   help="the linear model: exact ZOH of the linearisation, or the lecture's "
                        "forward Euler at the control period (default linear-zoh)")
    p.add_argument("--lti", default=None, metavar="FILE",
                   help="a plant file (as --plant FILE; kept for one release); policies "
                        "dlqr/lqr + none/kalman/kalman-predictor/luenberger (default "
                        "dlqr+none, dlqr+kalman, dlqr+luenberger)")
    p.add_argument("--agent", default=None, metavar="linear:FILE",
                   help="a linear controller file (default: none; linear:FILE.json, e.g. "
                        "linear:experiments/agents/models/sysid-lqg-seed0.json) instead of "
                        "POLICY: its exact stationary J on the suite's plant linearised, and the "
                        "exact gap J/J* − 1 to the suite's reference (--suite)")
    p.add_argument("--suite", default=None, metavar="S",
                   help="with --agent: the suite whose plant, noise, period and cost the loop has "
                        "(a name or a file; default lecture)")
    add_flags(p, "theory")              # the declared settings (problem/), theory's front end
    p.add_argument("--theta0", type=Kind("Finite"), default=defaults.X0[1],
                   help=f"initial pole angle in rad of the episode the expected RMS is taken over "
                        f"(default {defaults.X0[1]:g}, as run; not with a plant file: its's x0)")
    p.add_argument("--json", action="store_true",
                   help="machine-readable output: policies.NAME.{spectral_radius, stable, std, "
                        "u_std, estimate_error_std, cost_rate, episode.{rms, u_rms, "
                        "estimate_error_rms, cost_J}, …}")
    _add_design_options(p)


def _add_design_parser(sub: Any) -> None:
    """The ``design`` subcommand."""
    p = sub.add_parser("design", help="print the linearisation and every controller/observer design",
                       description="Linearise the MuJoCo cart-pole about the upright (or read "
                                   "a plant given as matrices, --lti) and print "
                                   "continuous/discrete LQR, Kalman and Luenberger designs.")
    _add_design_options(p)
    p.add_argument("--lti", default=None, metavar="FILE",
                   help="a plant file (as --plant FILE; kept for one release; default: none, "
                        "the cart-pole): its discretisation and every design on the file's weights and noise")
    p.add_argument("--json", action="store_true",
                   help="machine-readable output (matrices as nested lists, poles as [re, im])")


def _add_run_parser(sub: Any) -> None:
    """The ``run`` subcommand: the policy and the episodes, then sensing, the backend and
    the outputs, then the limits and the design options."""
    p = sub.add_parser("run", help="run seeded noisy episodes of one policy and summarise them",
                       description="Run seeded episodes of one policy (built-in or your own "
                                   "plugin) in the noisy MuJoCo loop and print their summary.")
    p.add_argument("--policy", default=None, metavar="NAME",
                   help="the policy: a built-in 'controller+observer' (e.g. dlqr+kalman) or your "
                        "own plugin MODULE:ATTR or path/to/file.py:ATTR, a factory taking a "
                        "pendulum_lqg.PolicyContext (docs/plugins.md); "
                        "default dlqr+kalman")
    p.add_argument("--controller", choices=CONTROLLERS, default=None,
                   help="built-in controller (default dlqr); not with --policy")
    p.add_argument("--observer", choices=OBSERVERS, default=None,
                   help="built-in observer (default kalman); not with --policy")
    p.add_argument("--episodes", type=Kind("PositiveInt"), default=100,
                   help="number of episodes (default 100)")
    p.add_argument("--seed", type=Kind("NonNegativeInt"), default=0,
                   help="the run's seed; episode k draws from episode_seed(seed, k) (default 0)")
    add_flags(p, "run")                 # the declared settings (problem/), run's front end
    p.add_argument("--theta0", type=Kind("Finite"), default=defaults.X0[1],
                   help=f"initial pole angle in rad, e.g. --theta0 -0.1 (default {defaults.X0[1]:g})")
    p.add_argument("--simulator", dest="plant", choices=PLANTS, default="mujoco",
                   help="how the plant is simulated: MuJoCo, or the model's linearisation "
                        "discretised exactly (linear-zoh) or by the lecture's forward Euler at the "
                        "control period (linear-euler) (default mujoco)")
    p.add_argument("--lti", default=None, metavar="FILE",
                   help="a plant file (as --plant FILE; kept for one release; default: none): "
                        "its own period, "
                        "x0, noise, cost and limits; policies dlqr/lqr + none/kalman/"
                        "kalman-predictor/luenberger")
    _add_sensing_options(p)
    p.add_argument("--backend", choices=("rollout", "step"), default="rollout",
                   help="batched MuJoCo (mujoco.batch) or a plain mj_step loop; bit-identical results "
                        "(default rollout)")
    p.add_argument("--nthread", type=Kind("NonNegativeInt"), default=None,
                   help="physics threads (default: the CPU cores available, at most 8)")
    p.add_argument("--record", metavar="FILE.rrd", default=None,
                   help="write a Rerun recording of every episode to FILE.rrd (default: none)")
    p.add_argument("--spawn", action="store_true",
                   help="also stream the recording to a native Rerun viewer; the file is written "
                        f"all the same (--record, default {DEFAULT_RECORDING}); without a display, "
                        "or with no viewer listening within 5 s, only the file is written")
    _add_plot_options(p)
    p.add_argument("--json", action="store_true",
                   help="machine-readable output: configuration, summary and every episode row")
    add_call_timeout(p)
    _add_design_options(p)


def _add_sensing_options(p: argparse.ArgumentParser) -> None:
    """``run``'s randomised plants (the delays, sample losses and lag are declared flags)."""
    g = p.add_argument_group("randomised plants")
    g.add_argument("--randomize", action="append", default=None, metavar="KEY=LO:HI",
                   help="per-episode uniform scale of a parameter of the simulated plant, e.g. "
                        "pole_mass_scale=0.8:1.2 (repeatable; keys pole_mass_scale, "
                        "pole_length_scale, cart_mass_scale; default: none)")


def _add_plot_options(p: argparse.ArgumentParser) -> None:
    """``run --plot``: the picture of one episode."""
    g = p.add_argument_group("picture of an episode")
    g.add_argument("--plot", metavar="FILE", default=None,
                   help="draw one episode to FILE (.png, .svg or .pdf): p, θ, ṗ, θ̇ with the "
                        "estimate ± 2σ, the measurement y and the force u with its saturation "
                        "(default: none)")
    g.add_argument("--plot-episode", type=Kind("NonNegativeInt"), default=0, metavar="K",
                   help="the episode --plot draws, 0 … --episodes − 1 (default 0, the first)")


def _add_bench_parser(sub: Any) -> None:
    """The ``bench`` subcommand."""
    p = sub.add_parser("bench", help="run an experiment grid (experiments/*.toml)",
                       description="Run an experiment: a grid of configurations × seeded episodes "
                                   "(or an analysis study), written unit by unit into a results "
                                   "folder and summarised. See docs/experiment-files.md.")
    p.add_argument("experiment",
                   help="a shipped experiment (lecture, noise, plugins, …), NAME.toml in the "
                        "current folder, or a path to a TOML file")
    p.add_argument("--episodes", type=Kind("PositiveInt"), default=None,
                   help="episodes per configuration (default: the file's)")
    p.add_argument("--seed", type=Kind("NonNegativeInt"), default=None, help="seed (default: the file's)")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="results folder (default results/<name> under the current folder)")
    p.add_argument("--model", default=None, metavar="XML",
                   help="your own cart-pole MJCF (docs/model.md) instead of the "
                        "experiment's model_file or the shipped models/cartpole.xml")
    p.add_argument("--force", action="store_true",
                   help="overwrite the results already in --out (default: refuse)")
    p.add_argument("--resume", action="store_true",
                   help="complete an interrupted sweep in --out (same file, episodes and seed); "
                        "every unit on disk is checked against its SHA-256, row count, columns "
                        "and configuration first")
    p.add_argument("--on-mismatch", choices=("recompute", "refuse"), default="recompute",
                   help="with --resume: a unit file that fails its check is recomputed "
                        "(default) or stops the run naming the unit")
    p.add_argument("--allow-version-change", action="store_true",
                   help="with --resume: complete results written by other versions of "
                        "pendulum_lqg, mujoco, numpy, scipy or control (default: refuse)")
    p.add_argument("--record", metavar="DIR", default=None,
                   help="also record the worst/median/best/first-failing episode of each "
                        "configuration into DIR (default: none)")
    p.add_argument("--nthread", type=Kind("NonNegativeInt"), default=None,
                   help="physics threads (default: the CPU cores available, at most 8)")
    p.add_argument("--executor", choices=("local", "ray"), default="local",
                   help="where work units run: this process (default) or Ray tasks (needs the "
                        "extra: pip install 'pendulum-lqg[ray]'); results are byte-identical")
    p.add_argument("--address", default=None, metavar="ADDR",
                   help="with --executor ray: join the cluster at 'auto' or HOST:PORT (default: "
                        "start a local Ray instance for the run)")
    p.add_argument("--quiet", action="store_true",
                   help="no progress bar or per-unit lines (the table is still printed)")


def _add_report_parser(sub: Any) -> None:
    """The ``report`` subcommand."""
    p = sub.add_parser("report", help="turn results folders into a Markdown report with PNG figures",
                       description="Read results folders written by `pendulum-lqg bench` (grids and "
                                   "the margins / roa studies) and write report.md with tables and "
                                   "PNG figures.")
    p.add_argument("results", nargs="+", metavar="RESULTS",
                   help="results folders, or a folder holding several (e.g. results_small)")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="report folder (default: <RESULTS>/report for one folder argument, else "
                        "report/)")


def _add_perf_parser(sub: Any) -> None:
    """The ``perf`` subcommand."""
    p = sub.add_parser("perf", help="throughput: closed loop vs bare MuJoCo physics, memory",
                       description="Time the batched noisy DLQR + Kalman loop against bare "
                                   "MuJoCo physics of the same batch (open-loop mujoco.rollout "
                                   "and mujoco.batch calls, the faster as the baseline), "
                                   "alternating, and optionally the peak memory of long benches.")
    p.add_argument("--episodes", type=Kind("PositiveInt"), default=1024,
                   help="episodes in the batch (default 1024)")
    p.add_argument("--duration", type=Kind("Finite"), default=2.0,
                   help="seconds simulated per episode (default 2)")
    p.add_argument("--nthread", type=Kind("NonNegativeInt"), default=None,
                   help="physics threads (default: the CPU cores available, at most 8)")
    p.add_argument("--repeats", type=Kind("PositiveInt"), default=5,
                   help="raw / closed-loop pairs, alternating; medians are compared (default 5)")
    p.add_argument("--memory", action="store_true",
                   help="also measure peak memory of 1000-episode benches of 2 s and 10 s")
    p.add_argument("--json", action="store_true", help="machine-readable output")


def build_parser() -> argparse.ArgumentParser:
    """The ``pendulum-lqg`` command: every subcommand and its options."""
    parser = _Parser(prog="pendulum-lqg",
                     description="LQG control of a MuJoCo cart-pole under noise: designs, noisy "
                                 "closed-loop runs and benchmarks. Negative numbers and lists are "
                                 "given as they are: --observer-poles -2,-3,-4,-5.")
    parser.add_argument("--version", action="version", version=f"pendulum-lqg {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    _add_design_parser(sub)
    _add_run_parser(sub)
    _add_bench_parser(sub)
    _add_report_parser(sub)
    _add_perf_parser(sub)
    add_score_parsers(sub)
    add_theory_parser(sub)
    add_train_parser(sub)
    return parser




def resolve_plant_option(args: argparse.Namespace) -> None:
    """``--plant`` after parsing: a simulator word (``mujoco``, ``linear-zoh``, ``linear-euler``,
    its meaning before plants had names) sets ``--simulator``; ``--lti FILE`` is ``--plant FILE``.
    Afterwards ``args.plant_ref`` is the plant's NAME or FILE (``None``: the cart-pole) and
    ``args.plant`` the simulator."""
    ref = getattr(args, "plant_ref", None)
    if ref is None and getattr(args, "lti", None) is None:
        return
    if ref in PLANTS:
        if args.command in ("score", "train"):         # they play each plant's own simulator
            raise cfg_error(f"--plant: expected a plant name or a plant file, got the simulator "
                            f"word {ref!r} ({args.command} plays each plant's own simulator)")
        if ref not in ("linear-zoh", "linear-euler") and args.command == "theory":
            raise cfg_error(f"--plant: the theory's simulator is linear-zoh or linear-euler, "
                            f"got {ref!r}")
        args.plant, args.plant_ref = ref, None
        ref = None
    lti = getattr(args, "lti", None)
    if lti is not None:
        if ref is not None:
            raise cfg_error("--lti: give the plant once, --plant FILE (--lti is its old name)")
        args.plant_ref = lti
    args.lti = None


# ---- helpers -------------------------------------------------------------------------------------
def jsonable(obj: Any) -> Any:
    from pendulum_lqg.util.jsonio import plain

    return plain(obj)


def noise_from_args(args: argparse.Namespace, scale: float = defaults.NOISE_SCALE) -> Any:
    from pendulum_lqg.core.noise import NoiseModel

    kw: dict[str, Any] = {"process": args.process_noise, "scale": scale}
    if args.w is not None:
        kw["process_density"] = args.w
    elif args.process_noise == "force":
        raise cfg_error("--w: force noise needs its density (N²·s, N²m²·s), e.g. --w 0.01,0.001")
    if args.v is not None:
        kw["measurement_variance"] = args.v
    return NoiseModel(**kw)


def cfg_error(msg: str) -> Exception:
    from pendulum_lqg.errors import ConfigError

    return ConfigError(msg)


def spec_from_args(args: argparse.Namespace, controller: str = "dlqr", observer: str = "kalman",
                    ) -> Any:
    """The built-in designs' options (weights, observer poles) from the command line."""
    from pendulum_lqg.policies.lqg import DesignSpec

    kw: dict[str, Any] = {"controller": controller, "observer": observer}
    if args.q is not None:
        kw["Q"] = tuple(args.q)
    if args.r is not None:
        kw["R"] = args.r
    if args.observer_poles is not None:
        kw["observer_poles"] = tuple(args.observer_poles)
    return DesignSpec(**kw)
