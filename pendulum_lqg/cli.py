"""The ``pendulum-lqg`` command: ``design``, ``run``, ``bench``, ``perf``, ``report``.

Only argument parsing and presentation live here; every computation is a library call. Heavy
imports (numpy, MuJoCo, python-control, rich) happen inside the commands so ``--help`` is instant.
Bad input prints one line ``error: …`` naming the parameter and exits with status 2.
"""

from __future__ import annotations

import argparse
import json
import math
import re
import sys
from collections.abc import Callable, Sequence
from typing import Any, NoReturn

from pendulum_lqg.names import CONTROLLERS, OBSERVERS, PLANTS

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


def _floats(text: str) -> list[float]:
    try:
        vals = [float(t) for t in text.replace(" ", "").split(",") if t]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated numbers, got {text!r}") from None
    if not vals or not all(math.isfinite(v) for v in vals):
        raise argparse.ArgumentTypeError(f"expected finite comma-separated numbers, got {text!r}")
    return vals


def _complexes(text: str) -> list[complex]:
    try:
        vals = [complex(t.replace("i", "j")) for t in text.replace(" ", "").split(",") if t]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected comma-separated poles like -0.4,-0.5 or -1+2j,-1-2j, got {text!r}") from None
    return vals


def _int_at_least(minimum: int) -> Callable[[str], int]:
    """argparse type: an integer ≥ ``minimum``."""
    what = "a positive integer" if minimum == 1 else "a non-negative integer"

    def parse(text: str) -> int:
        try:
            v = int(text)
        except ValueError:
            v = minimum - 1
        if v < minimum:
            raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}")
        return v

    return parse


_positive_int, _nonneg_int = _int_at_least(1), _int_at_least(0)


def _number(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not math.isfinite(v):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return v




def _add_design_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("design")
    g.add_argument("--model", default=None, metavar="XML",
                   help="MJCF model file (default: the bundled models/cartpole.xml)")
    g.add_argument("--dt", type=_number, default=0.01, metavar="T",
                   help="control period T in seconds, a whole number (≤ 10 000) of the model's "
                        "physics steps and at most 1 s (default 0.01)")
    g.add_argument("--q", type=_floats, default=None, metavar="Q1,..,Q4",
                   help="diagonal of the LQR state weight Q, units of [m⁻², rad⁻², (m/s)⁻², "
                        "(rad/s)⁻²] (default 1,1,1,1)")
    g.add_argument("--r", type=_number, default=None, help="LQR input weight R in N⁻² (default 1)")
    g.add_argument("--observer-poles", type=_complexes, default=None, metavar="P1,..,P4",
                   help="continuous-time Luenberger poles in rad/s, e.g. --observer-poles "
                        "-2,-3,-4,-5 or -1+2j,-1-2j,-3,-4 (default -0.4,-0.5,-0.6,-0.7); "
                        "discrete designs use z = exp(s·T)")
    g.add_argument("--w", type=_floats, default=None, metavar="W",
                   help="process-noise spectral density, diagonal: 4 values (m²·s, rad²·s, …) "
                        "for state noise, 2 (N²·s, N²m²·s) for force noise (default the "
                        "lecture's 4e-4 on every state)")
    g.add_argument("--v", type=_floats, default=None, metavar="V",
                   help="measurement-noise covariance per sample, diagonal (m², rad²; default "
                        "0.01,0.01)")
    g.add_argument("--process-noise", choices=("state", "force"), default="state",
                   help="where process noise enters: the state (F = I₄, lecture) or generalised "
                        "forces on slider and hinge (default state)")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="pendulum-lqg",
                     description="LQG control of a MuJoCo cart-pole under noise: designs, noisy "
                                 "closed-loop runs and benchmarks. Negative numbers and lists are "
                                 "given as they are: --observer-poles -2,-3,-4,-5.")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    p = sub.add_parser("design", help="print the linearisation and every controller/observer design",
                       description="Linearise the MuJoCo cart-pole about the upright and print "
                                   "continuous/discrete LQR, Kalman and Luenberger designs.")
    _add_design_options(p)
    p.add_argument("--json", action="store_true",
                   help="machine-readable output (matrices as nested lists, poles as [re, im])")

    p = sub.add_parser("run", help="run seeded noisy episodes of one policy and summarise them",
                       description="Run seeded episodes of one policy (built-in or your own "
                                   "plugin) in the noisy MuJoCo loop and print their summary.")
    p.add_argument("--policy", default=None, metavar="NAME",
                   help="the policy: a built-in 'controller+observer' (e.g. dlqr+kalman) or your "
                        "own plugin MODULE:ATTR or path/to/file.py:ATTR, a factory taking a "
                        "pendulum_lqg.PolicyContext (README: Benchmark your own controller); "
                        "default dlqr+kalman")
    p.add_argument("--controller", choices=CONTROLLERS, default=None,
                   help="built-in controller (default dlqr); not with --policy")
    p.add_argument("--observer", choices=OBSERVERS, default=None,
                   help="built-in observer (default kalman); not with --policy")
    p.add_argument("--episodes", type=_positive_int, default=100,
                   help="number of episodes (default 100)")
    p.add_argument("--seed", type=_nonneg_int, default=0,
                   help="the run's seed; episode k draws from episode_seed(seed, k) (default 0)")
    p.add_argument("--duration", type=_number, default=10.0,
                   help="episode length in s, at most 10⁸ control periods (default 10)")
    p.add_argument("--noise-scale", type=_number, default=1.0,
                   help="multiplies both noises' standard deviations (0 = noise-free; default 1); "
                        "the estimators stay designed for the nominal noise")
    p.add_argument("--theta0", type=_number, default=0.1,
                   help="initial pole angle in rad, e.g. --theta0 -0.1 (default 0.1)")
    p.add_argument("--estimate0", choices=("zero", "true"), default="zero",
                   help="initial estimate: x̂₀ = 0 or the true x₀ (default zero)")
    p.add_argument("--plant", choices=PLANTS, default="mujoco",
                   help="the simulated plant: MuJoCo, or the model's linearisation discretised "
                        "exactly (linear-zoh) or by the lecture's forward Euler at the control "
                        "period (linear-euler) (default mujoco)")
    g = p.add_argument_group("sensing and actuation")
    g.add_argument("--measurement-delay", type=_number, default=0.0, metavar="S",
                   help="age of the measurement the policy receives, in s (a whole number of "
                        "control periods; default 0)")
    g.add_argument("--actuator-delay", type=_number, default=0.0, metavar="S",
                   help="delay of the force, in s (a whole number of control periods; default 0)")
    g.add_argument("--dropout", type=_number, default=0.0, metavar="P",
                   help="probability that a measurement sample is lost (the policy gets nan; "
                        "default 0)")
    g.add_argument("--actuator-tau", type=_number, default=0.0, metavar="S",
                   help="time constant of a first-order lag of the force, in s (default 0: none)")
    g.add_argument("--randomize", action="append", default=None, metavar="KEY=LO:HI",
                   help="per-episode uniform scale of a parameter of the simulated plant, e.g. "
                        "pole_mass_scale=0.8:1.2 (repeatable; keys pole_mass_scale, "
                        "pole_length_scale, cart_mass_scale; default: none)")
    p.add_argument("--backend", choices=("rollout", "step"), default="rollout",
                   help="batched MuJoCo (mujoco.batch) or a plain mj_step loop; bit-identical results "
                        "(default rollout)")
    p.add_argument("--nthread", type=_nonneg_int, default=None,
                   help="physics threads (default: the CPU cores available, at most 8)")
    p.add_argument("--record", metavar="FILE.rrd", default=None,
                   help="write a Rerun recording of every episode to FILE.rrd (default: none)")
    p.add_argument("--spawn", action="store_true",
                   help="also stream the recording to a native Rerun viewer; the file is written "
                        f"all the same (--record, default {DEFAULT_RECORDING}); without a display, "
                        "or with no viewer listening within 5 s, only the file is written")
    p.add_argument("--json", action="store_true",
                   help="machine-readable output: configuration, summary and every episode row")
    _add_design_options(p)

    p = sub.add_parser("bench", help="run an experiment grid (experiments/*.toml)",
                       description="Run an experiment: a grid of configurations × seeded episodes "
                                   "(or an analysis study), written unit by unit into a results "
                                   "folder and summarised. README: the experiment file format.")
    p.add_argument("experiment",
                   help="a shipped experiment (lecture, noise, plugins, …), NAME.toml in the "
                        "current folder, or a path to a TOML file")
    p.add_argument("--episodes", type=_positive_int, default=None,
                   help="episodes per configuration (default: the file's)")
    p.add_argument("--seed", type=_nonneg_int, default=None, help="seed (default: the file's)")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="results folder (default results/<name> under the current folder)")
    p.add_argument("--model", default=None, metavar="XML",
                   help="your own cart-pole MJCF (README: the model contract) instead of the "
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
    p.add_argument("--nthread", type=_nonneg_int, default=None,
                   help="physics threads (default: the CPU cores available, at most 8)")
    p.add_argument("--executor", choices=("local", "ray"), default="local",
                   help="where work units run: this process (default) or Ray tasks (needs the "
                        "extra: pip install 'pendulum-lqg[ray]'); results are byte-identical")
    p.add_argument("--address", default=None, metavar="ADDR",
                   help="with --executor ray: join the cluster at 'auto' or HOST:PORT (default: "
                        "start a local Ray instance for the run)")
    p.add_argument("--quiet", action="store_true",
                   help="no progress bar or per-unit lines (the table is still printed)")

    p = sub.add_parser("report", help="turn results folders into a Markdown report with PNG figures",
                       description="Read results folders written by `pendulum-lqg bench` (grids and "
                                   "the margins / roa studies) and write report.md with tables and "
                                   "PNG figures.")
    p.add_argument("results", nargs="+", metavar="RESULTS",
                   help="results folders, or a folder holding several (e.g. results_small)")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="report folder (default: <RESULTS>/report for one folder argument, else "
                        "report/)")

    p = sub.add_parser("perf", help="throughput: closed loop vs bare MuJoCo physics, memory",
                       description="Time the batched noisy DLQR + Kalman loop against bare "
                                   "MuJoCo physics of the same batch (open-loop mujoco.rollout "
                                   "and mujoco.batch calls, the faster as the baseline), "
                                   "alternating, and optionally the peak memory of long benches.")
    p.add_argument("--episodes", type=_positive_int, default=1024,
                   help="episodes in the batch (default 1024)")
    p.add_argument("--duration", type=_number, default=2.0,
                   help="seconds simulated per episode (default 2)")
    p.add_argument("--nthread", type=_nonneg_int, default=None,
                   help="physics threads (default: the CPU cores available, at most 8)")
    p.add_argument("--repeats", type=_positive_int, default=5,
                   help="raw / closed-loop pairs, alternating; medians are compared (default 5)")
    p.add_argument("--memory", action="store_true",
                   help="also measure peak memory of 1000-episode benches of 2 s and 10 s")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    return parser


# ---- helpers -------------------------------------------------------------------------------------
def _jsonable(obj: Any) -> Any:
    from pendulum_lqg.jsonio import plain

    return plain(obj)


def _noise_from_args(args: argparse.Namespace, scale: float = 1.0) -> Any:
    from pendulum_lqg.noise import NoiseModel

    kw: dict[str, Any] = {"process": args.process_noise, "scale": scale}
    if args.w is not None:
        kw["process_density"] = args.w
    elif args.process_noise == "force":
        raise _cfg_error("--w: force noise needs its density (N²·s, N²m²·s), e.g. --w 0.01,0.001")
    if args.v is not None:
        kw["measurement_variance"] = args.v
    return NoiseModel(**kw)


def _cfg_error(msg: str) -> Exception:
    from pendulum_lqg.errors import ConfigError

    return ConfigError(msg)


def _spec_from_args(args: argparse.Namespace, controller: str = "dlqr", observer: str = "kalman",
                    ) -> Any:
    """The built-in designs' options (weights, observer poles) from the command line."""
    from pendulum_lqg.policy import DesignSpec

    kw: dict[str, Any] = {"controller": controller, "observer": observer}
    if args.q is not None:
        kw["Q"] = tuple(args.q)
    if args.r is not None:
        kw["R"] = args.r
    if args.observer_poles is not None:
        kw["observer_poles"] = tuple(args.observer_poles)
    return DesignSpec(**kw)


# ---- design --------------------------------------------------------------------------------------
def cmd_design(args: argparse.Namespace) -> int:
    import numpy as np

    from pendulum_lqg.plant import load_plant
    from pendulum_lqg.policy import design_all

    plant = load_plant(args.model)
    noise = _noise_from_args(args)
    spec = _spec_from_args(args)
    d = design_all(plant, args.dt, noise, spec)
    lin, zoh, fd = d["linear"], d["zoh"], d["transition_fd"]
    st, std = d["structure"], d["structure_discrete"]
    data = {
        "model": str(plant.path), "parameters": plant.parameters(), "dt": d["dt"],
        "steps_per_period": d["steps_per_period"],
        "A": lin.A, "B": lin.B, "C": lin.C, "D": lin.D, "F_generalised_forces": lin.F,
        "open_loop_poles": d["open_loop_poles"],
        "Phi": zoh.Phi, "Gamma": zoh.Gamma,
        "Phi_transition_fd": fd.Phi, "Gamma_transition_fd": fd.Gamma,
        "zoh_vs_transition_fd_max_abs": max(float(np.max(np.abs(zoh.Phi - fd.Phi))),
                                            float(np.max(np.abs(zoh.Gamma - fd.Gamma)))),
        "structure": {"controllability_rank": st.controllability_rank,
                      "observability_rank": st.observability_rank,
                      "uncontrollable_modes_pbh": st.uncontrollable_modes,
                      "unobservable_modes_pbh": st.unobservable_modes,
                      "stabilizable": st.stabilizable, "detectable": st.detectable,
                      "discrete_stabilizable": std.stabilizable,
                      "discrete_detectable": std.detectable},
        "weights": d["weights"],
        "K_lqr": d["lqr"].K, "K_lqr_poles": d["lqr"].poles, "P_lqr": d["lqr"].P,
        "K_dlqr": d["dlqr"].K, "K_dlqr_poles": d["dlqr"].poles, "P_dlqr": d["dlqr"].P,
        "L_kalman": d["kalman"].L, "L_kalman_poles": d["kalman"].poles, "P_kalman": d["kalman"].P,
        "L_dkalman": d["dkalman"].L, "L_dkalman_poles": d["dkalman"].poles,
        "L_dkalman_predictor": d["dkalman"].L_pred, "M_dkalman": d["dkalman"].M,
        "P_dkalman": d["dkalman"].P,
        "L_luenberger": d["luenberger"].L, "L_luenberger_poles": d["luenberger"].poles,
        "L_dluenberger": d["dluenberger"].L, "L_dluenberger_poles": d["dluenberger"].poles,
        "separation": {"continuous_max_error": d["lqg"].separation_error,
                       "discrete_max_error": d["dlqg"].separation_error,
                       "continuous_closed_loop_poles": d["lqg"].poles,
                       "discrete_closed_loop_poles": d["dlqg"].poles},
    }
    for key in [k for k in data if k.endswith("_poles")]:
        data[key] = np.asarray(data[key], dtype=complex)      # always [re, im] pairs in JSON
    if args.json:
        print(json.dumps(_jsonable(data), indent=2))
        return 0
    _print_design(data, plant)
    return 0


def _mat(M: Any, indent: int = 4) -> str:
    import numpy as np

    M = np.atleast_2d(np.asarray(M, dtype=float))
    cells = [[f"{v:.6g}" for v in row] for row in M]
    width = max(len(c) for row in cells for c in row)
    pad = " " * indent
    return "\n".join(pad + "[" + "  ".join(c.rjust(width) for c in row) + "]" for row in cells)


def _poles(p: Any) -> str:
    import numpy as np

    p = np.asarray(p, dtype=complex)
    p = p[np.lexsort((p.imag, p.real))]
    out = []
    for z in p:
        out.append(f"{z.real:.6g}" if abs(z.imag) < 1e-12 else f"{z.real:.6g}{z.imag:+.6g}j")
    return ", ".join(out) or "none"


def _print_design(d: dict[str, Any], plant: Any) -> None:
    par = d["parameters"]
    s = d["structure"]
    w = d["weights"]
    lines = [
        f"pendulum_lqg design — {d['model']}",
        "model (read from the XML): " + ", ".join(f"{k}={v:.6g}" for k, v in par.items()),
        "state x = [p, θ, ṗ, θ̇], input u = cart force [N], output y = [p, θ]; "
        f"T = {d['dt']:g} s = {d['steps_per_period']} physics steps",
        "",
        "Linearisation about the upright (central differences of mj_forward)",
    ]
    for key in ("A", "B", "C", "D"):
        lines += [f"  {key} =", _mat(d[key])]
    lines += [f"  open-loop poles: {_poles(d['open_loop_poles'])}",
              f"  controllability: rank {s['controllability_rank']}/4, PBH-uncontrollable modes: "
              f"{_poles(s['uncontrollable_modes_pbh'])}, stabilisable: {s['stabilizable']}",
              f"  observability:   rank {s['observability_rank']}/4, PBH-unobservable modes: "
              f"{_poles(s['unobservable_modes_pbh'])}, detectable: {s['detectable']}",
              "", f"Discrete model at T = {d['dt']:g} s (exact ZOH)"]
    for key in ("Phi", "Gamma"):
        lines += [f"  {key} =", _mat(d[key])]
    lines += [f"  max |ZOH − composed mjd_transitionFD| = {d['zoh_vs_transition_fd_max_abs']:.3g}"
              " (the Euler integrator's O(h) error)", ""]
    lines += ["Weights and noise",
              f"  Q = diag{tuple(float(v) for v in w['Q'].diagonal())}, R = {float(w['R'][0, 0]):g}"
              "; DLQR uses their exact sampled-data equivalents (Qd, Rd, Nd)",
              f"  process noise density W = diag{tuple(float(v) for v in w['W'].diagonal())} "
              "(units²·s), per sample Qd = W·T",
              f"  measurement covariance V = diag{tuple(float(v) for v in w['V'].diagonal())} per "
              "sample (Kalman–Bucy uses the density V·T)", ""]
    rows = [
        ("Continuous LQR, u = −K x", "K_lqr", "K_lqr_poles", "s"),
        ("Discrete LQR (ZOH model, sampled cost)", "K_dlqr", "K_dlqr_poles", "z"),
        ("Kalman–Bucy (continuous)", "L_kalman", "L_kalman_poles", "s"),
        ("Discrete Kalman, filter (current-estimate) gain L", "L_dkalman", "L_dkalman_poles", "z"),
        ("Discrete Kalman, predictor gain L_pred = Φ L (python-control dlqe)",
         "L_dkalman_predictor", "L_dkalman_poles", "z"),
        ("Luenberger (continuous poles)", "L_luenberger", "L_luenberger_poles", "s"),
        ("Luenberger (discrete, current form, z = exp(sT))", "L_dluenberger",
         "L_dluenberger_poles", "z"),
    ]
    for title, gain, poles, plane in rows:
        lines += [title, _mat(d[gain]), f"    poles ({plane}): {_poles(d[poles])}", ""]
    sep = d["separation"]
    lines.append("Separation principle: eig(LQG loop) = eig(A − BK) ∪ eig(A − LC), max mismatch "
                 f"{sep['continuous_max_error']:.2g} (continuous LQR + Kalman–Bucy), "
                 f"{sep['discrete_max_error']:.2g} (DLQR + discrete Kalman, current form)")
    print("\n".join(lines))


# ---- run -----------------------------------------------------------------------------------------
def cmd_run(args: argparse.Namespace) -> int:
    from pendulum_lqg.limits import MAX_RECORDED_EPISODES, MAX_RUN_EPISODES, check_at_most
    from pendulum_lqg.metrics import summarize
    from pendulum_lqg.plant import Randomization, load_plant
    from pendulum_lqg.plugins import build_policy, is_plugin_ref, split_builtin
    from pendulum_lqg.sim import Scenario

    if args.policy is not None and (args.controller or args.observer):
        raise _cfg_error("--policy: give either --policy or --controller/--observer, not both")
    name = args.policy or f"{args.controller or 'dlqr'}+{args.observer or 'kalman'}"
    plant = load_plant(args.model)
    noise = _noise_from_args(args, scale=args.noise_scale)
    scenario = Scenario(control_period=args.dt, duration=args.duration, noise=noise,
                        x0=(0.0, args.theta0, 0.0, 0.0), estimate0=args.estimate0,
                        plant=args.plant,
                        measurement_delay=args.measurement_delay,
                        actuator_delay=args.actuator_delay, dropout=args.dropout,
                        actuator_tau=args.actuator_tau,
                        randomize=Randomization.from_mapping(_randomize(args.randomize)))
    plugin = is_plugin_ref(name)
    spec = _spec_from_args(args, *(("dlqr", "kalman") if plugin else split_builtin(name)))
    policy = build_policy(name if plugin else None, plant=plant, scenario=scenario, spec=spec)
    recording = args.record is not None or args.spawn
    check_at_most("--episodes", args.episodes, MAX_RUN_EPISODES,
                  "run keeps every row in memory; bench streams larger studies to disk")
    if recording:
        check_at_most("--episodes", args.episodes, MAX_RECORDED_EPISODES,
                      "episodes recorded with --record/--spawn, whose trajectories are kept")
    res = _run_in_batches(plant, scenario, policy, args, trajectory=recording)
    summary = summarize(res.rows)
    config = {"policy": policy.name, "seed": args.seed, "episodes": args.episodes,
              "backend": args.backend, "scenario": scenario.to_dict(),
              "design": None if plugin else _dataclass_dict(spec), "model": str(plant.path)}
    from pendulum_lqg import SCHEMA_VERSION

    out = {"schema_version": SCHEMA_VERSION, "config": config,
           "success_rate": summary["success_rate"],
           "success_ci95": summary["success_ci95"], "summary": summary, "episodes": res.rows}
    if recording:
        from pendulum_lqg.record import record_episodes

        path = args.record if args.record is not None else DEFAULT_RECORDING
        stats = record_episodes(res.trajectories, plant=plant, scenario=scenario, policy=policy,
                                config=config, path=path, spawn=args.spawn)
        if stats.viewer_note:
            print(f"viewer: {stats.viewer_note}; open the file with: rerun {path}",
                  file=sys.stderr)
        print(f"recording: {stats.path} ({stats.episodes} episode(s), {stats.bytes:,} bytes"
              + (", streamed to the viewer" if stats.viewer_reached else "") + ")",
              file=sys.stderr)
    if args.json:
        print(json.dumps(_jsonable(out), indent=2))
    else:
        _print_summary(policy.name, config, summary)
    return 0


def _randomize(items: list[str] | None) -> dict[str, list[float]]:
    """``--randomize KEY=LO:HI`` options as the ``randomize`` mapping of a Scenario."""
    out: dict[str, list[float]] = {}
    for item in items or []:
        key, _, rng = item.partition("=")
        lo, _, hi = rng.partition(":")
        try:
            out[key.strip()] = [float(lo), float(hi)]
        except ValueError:
            raise _cfg_error(f"--randomize: expected KEY=LO:HI such as pole_mass_scale=0.8:1.2, "
                             f"got {item!r}") from None
    return out


def _dataclass_dict(obj: Any) -> dict[str, Any]:
    import dataclasses

    return dataclasses.asdict(obj)


def _print_summary(name: str, config: dict[str, Any], s: dict[str, Any]) -> None:
    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    con = Console(highlight=False)
    sc = config["scenario"]
    lo, hi = s["success_ci95"]
    con.print(escape(f"{name} — {s['episodes']} episodes, seed {config['seed']}, "
                     f"T = {sc['control_period']} s, {sc['duration']} s, noise scale "
                     f"{sc['noise']['scale']}, x0 = {list(sc['x0'])}"))
    extras = {k: sc[k] for k in ("measurement_delay", "actuator_delay", "dropout", "actuator_tau",
                                 "randomize") if sc.get(k)}
    if extras:
        con.print(escape("sensing and actuation: " + ", ".join(f"{k} = {v}"
                                                                 for k, v in extras.items())))
    con.print(f"success: {s['successes']}/{s['episodes']} = {s['success_rate']:.1%} "
              f"(95 % Wilson CI {lo:.1%} – {hi:.1%})"
              + escape(f"; failures: {s['failures']}" if s["failures"] else ""))
    t = Table()
    t.add_column("metric")
    t.add_column("mean ± s.e.")
    rows = [("cost", "J = ∫xᵀQx + uᵀRu dt (successes)", 1.0), ("rms_theta", "RMS θ [rad]", 1.0),
            ("max_abs_theta", "max |θ| [rad]", 1.0), ("rms_p", "RMS p [m]", 1.0),
            ("max_abs_p", "max |p| [m]", 1.0), ("rms_u", "RMS u [N]", 1.0),
            ("max_abs_u", "max |u| [N]", 1.0),
            ("saturated_fraction", "time saturated [% of the episode]", 100.0),
            ("rms_est_err_p", "RMS p̂−p [m]", 1.0), ("rms_est_err_theta", "RMS θ̂−θ [rad]", 1.0),
            ("rms_est_err_p_dot", "RMS ṗ̂−ṗ [m/s]", 1.0),
            ("rms_est_err_theta_dot", "RMS θ̇̂−θ̇ [rad/s]", 1.0)]
    # Under noise |θ| never stays inside the settling band, so the "last time outside it" is the
    # episode's end: the settling time means something only for noise-free runs.
    if sc["noise"]["scale"] == 0:
        rows.append(("settling_time", f"settling time [s] (|θ| ≤ {sc['settle_band']:g} rad "
                                      "from then on; successes)", 1.0))
    rows.append(("time_to_failure", "time to failure [s] (failures)", 1.0))
    for key, label, unit in rows:
        m, se = s[key]["mean"] * unit, s[key]["se"] * unit
        cell = "–" if m != m else (f"{m:.4g}" if se != se else f"{m:.4g} ± {se:.2g}")
        t.add_row(escape(label), cell)
    con.print(t)
    if sc["noise"]["scale"] != 0:
        con.print("settling time: not reported under noise (|θ| keeps leaving the "
                  f"{sc['settle_band']:g} rad band); run with --noise-scale 0 for it")


def _run_in_batches(plant: Any, scenario: Any, policy: Any, args: argparse.Namespace, *,
                    trajectory: bool) -> Any:
    """``run_episodes`` over ``--episodes`` in batches (memory flat in the episode count; the rows
    do not depend on the batching), with a progress line on stderr every few seconds once a run
    takes long."""
    import time

    from pendulum_lqg import limits
    from pendulum_lqg.plant import steps_per_period
    from pendulum_lqg.sim import BatchResult, run_episodes

    steps = scenario.n_periods * steps_per_period(plant, scenario.control_period)
    size = max(1, min(limits.RUN_BATCH, 20_000_000 // max(steps, 1)))    # ≤ ~2·10⁷ physics steps each
    total = args.episodes
    rows: list[dict[str, Any]] = []
    trajectories: list[Any] | None = [] if trajectory else None
    t0 = last = time.perf_counter()
    for start in range(0, total, size):
        res = run_episodes(plant, scenario, policy, seed=args.seed,
                           episodes=range(start, min(start + size, total)), backend=args.backend,
                           nthread=args.nthread, trajectory=trajectory)
        rows += res.rows
        if trajectories is not None:
            trajectories += res.trajectories or []
        now = time.perf_counter()
        if len(rows) < total and now - last >= limits.PROGRESS_EVERY_S:
            eta = (now - t0) / len(rows) * (total - len(rows))
            print(f"run: {len(rows):,}/{total:,} episodes, {now - t0:.0f} s, about {eta:.0f} s "
                  "left", file=sys.stderr)
            last = now
    return BatchResult(rows=rows, trajectories=trajectories)


# ---- bench ---------------------------------------------------------------------------------------
def cmd_bench(args: argparse.Namespace) -> int:
    from pathlib import Path

    from pendulum_lqg.executors import make_executor
    from pendulum_lqg.experiments import load_spec
    from pendulum_lqg.results import ResultsDir
    from pendulum_lqg.sweep import SweepInterrupted, run_sweep

    spec = load_spec(args.experiment).with_overrides(episodes=args.episodes, seed=args.seed,
                                                     model_file=args.model)
    out = ResultsDir(args.out or Path("results") / spec.name)
    log = None if args.quiet else (lambda msg: print(msg, file=sys.stderr))
    if spec.study is not None:
        if args.executor != "local":
            raise _cfg_error(f"--executor: the {spec.study} study runs on the local executor")
        out.prepare(spec, force=args.force, resume=args.resume,
                    allow_version_change=args.allow_version_change)
        return _bench_study(spec, out, args)
    # `bench NAME --record DIR` after `bench NAME`: record from the finished results (nothing to
    # rerun, so no --resume needed)
    resume = args.resume or (args.record is not None and not args.force
                             and out.holds_complete(spec))
    executor = make_executor(args.executor, address=args.address, nthread=args.nthread)
    try:
        result = run_sweep(spec, out, executor=executor, resume=resume, force=args.force,
                           progress=None if not args.quiet else False, log=log,
                           record=args.record, nthread=args.nthread,
                           on_mismatch=args.on_mismatch,
                           allow_version_change=args.allow_version_change)
    except SweepInterrupted as exc:
        print(f"interrupted: {exc}; complete them with: {_resume_command(args, spec, out)}",
              file=sys.stderr)
        return 130
    if not result.complete:
        for failure in result.failures:
            print(f"error: work unit {failure.key} failed: {failure.error}", file=sys.stderr)
        print(f"incomplete: {len(result.failures)}/{result.units_total} work units failed; the "
              f"others are saved in {out.path}; rerun the failed ones with: "
              f"{_resume_command(args, spec, out)}", file=sys.stderr)
        return 1
    sys.stdout.write((out.path / "summary.md").read_text())
    print(f"\nresults: {out.path}/episodes.csv, summary.md, summary.json", file=sys.stderr)
    return 0


def _resume_command(args: argparse.Namespace, spec: Any, out: Any) -> str:
    """The command that completes this sweep (same file, episodes, seed, model, executor)."""
    parts = ["pendulum-lqg bench", args.experiment, "--resume", "--out", str(out.path)]
    if args.episodes:
        parts += ["--episodes", str(spec.episodes)]
    if args.seed is not None:
        parts += ["--seed", str(spec.seed)]
    if args.model:
        parts += ["--model", args.model]
    if args.executor != "local":
        parts += ["--executor", args.executor] + (["--address", args.address]
                                                  if args.address else [])
    return " ".join(parts)


def _bench_study(spec: Any, out: Any, args: argparse.Namespace) -> int:
    """``bench`` of an analysis study (``study = "margins" | "roa"`` in the TOML)."""
    from pendulum_lqg.analysis.studies import run_study
    from pendulum_lqg.sweep import terminate_as_interrupt

    log = None if args.quiet else (lambda msg: print(msg, file=sys.stderr))
    try:
        with terminate_as_interrupt():
            run_study(spec, out, nthread=args.nthread, log=log)
    except KeyboardInterrupt:
        print(f"interrupted: finished configurations are saved in {out.path}; complete them with: "
              f"{_resume_command(args, spec, out)}", file=sys.stderr)
        return 130
    finally:
        out.release()
    sys.stdout.write((out.path / "summary.md").read_text())
    print(f"\nresults: {out.path}/summary.md, summary.json", file=sys.stderr)
    return 0


# ---- report --------------------------------------------------------------------------------------
def cmd_report(args: argparse.Namespace) -> int:
    from pathlib import Path

    from pendulum_lqg.report import make_report

    paths = [Path(p) for p in args.results]
    out = Path(args.out) if args.out else (paths[0] / "report" if len(paths) == 1
                                           else Path("report"))
    report = make_report(paths, out)
    print(f"report: {report}", file=sys.stderr)
    return 0


# ---- perf ----------------------------------------------------------------------------------------
def cmd_perf(args: argparse.Namespace) -> int:
    from pendulum_lqg.perf import run_perf

    result = run_perf(episodes=args.episodes, duration=args.duration, nthread=args.nthread,
                      repeats=args.repeats, memory=args.memory,
                      log=lambda msg: print(msg, file=sys.stderr))
    if args.json:
        print(json.dumps(_jsonable(result), indent=2))
    else:
        for line in result["report"]:
            print(line)
    return 0


COMMANDS = {"design": cmd_design, "run": cmd_run, "bench": cmd_bench, "perf": cmd_perf,
            "report": cmd_report}


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    from pendulum_lqg.errors import PendulumLQGError

    try:
        return COMMANDS[args.command](args)
    except PendulumLQGError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except BrokenPipeError:  # e.g. `pendulum-lqg design --json | head`
        return 0
    except OSError as exc:   # a full disk, a read-only or vanished folder: files written stay
        where = f"{exc.filename}: " if exc.filename else ""
        print(f"error: cannot write or read {where}{exc.strerror or exc}", file=sys.stderr)
        return EXIT_USAGE


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
