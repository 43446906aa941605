"""``pendulum-lqg run``, ``bench``, ``report`` and ``perf``: each a function of the parsed arguments."""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from pendulum_lqg.cli.parser import DEFAULT_RECORDING, cfg_error, jsonable, noise_from_args, spec_from_args
from pendulum_lqg.cli.theory import declared_fields, run_theory_lines


# ---- run -----------------------------------------------------------------------------------------
def scenario_from_args(args: argparse.Namespace) -> Any:
    """The :class:`~pendulum_lqg.core.scenario.Scenario` of ``run``'s options (the cart-pole)."""
    from pendulum_lqg.core.scenario import Scenario
    from pendulum_lqg.model.overrides import Randomization

    noise = noise_from_args(args, scale=args.noise_scale)
    return Scenario(control_period=args.dt, noise=noise, x0=(0.0, args.theta0, 0.0, 0.0),
                    plant=args.plant,
                    randomize=Randomization.from_mapping(_randomize(args.randomize)),
                    **declared_fields(args, "run"))


def cmd_run(args: argparse.Namespace) -> int:
    from pendulum_lqg.core.metrics import summarize
    from pendulum_lqg.model.catalog import is_cartpole
    from pendulum_lqg.model.plant import load_plant
    from pendulum_lqg.policies.loading import build_policy, is_plugin_ref, split_builtin
    from pendulum_lqg.util.limits import MAX_RECORDED_EPISODES, MAX_RUN_EPISODES, check_at_most

    if args.policy is not None and (args.controller or args.observer):
        raise cfg_error("--policy: give either --policy or --controller/--observer, not both")
    name = (args.policy if args.policy is not None   # --policy '' is refused, not the default
            else f"{args.controller or 'dlqr'}+{args.observer or 'kalman'}")
    if not is_cartpole(args.plant_ref):          # a plant file (or a shipped one): the same loop
        return _run_plant_file(args, name)
    plant = load_plant(args.model)
    scenario = scenario_from_args(args)
    plugin = is_plugin_ref(name)
    spec = spec_from_args(args, *(("dlqr", "kalman") if plugin else split_builtin(name)))
    policy = build_policy(name if plugin else None, plant=plant, scenario=scenario, spec=spec)
    recording = args.record is not None or args.spawn
    check_at_most("--episodes", args.episodes, MAX_RUN_EPISODES,
                  "run keeps every row in memory; bench streams larger studies to disk")
    _check_plot_args(args)
    if recording:
        check_at_most("--episodes", args.episodes, MAX_RECORDED_EPISODES,
                      "episodes recorded with --record/--spawn, whose trajectories are kept")
        _check_recording_target(args)
    with _watchdog(args):
        res = _run_in_batches(plant, scenario, policy, args, trajectory=recording)
    summary = summarize(res.rows)
    config = {"policy": policy.name, "seed": args.seed, "episodes": args.episodes,
              "backend": args.backend, "scenario": scenario.to_dict(),
              "design": None if plugin else _dataclass_dict(spec), "model": str(plant.path)}
    from pendulum_lqg.version import SCHEMA_VERSION

    theory, theory_lines = run_theory_lines(plant, scenario, policy)
    out = {"schema_version": SCHEMA_VERSION, "config": config, "success_rate":
           summary["success_rate"], "success_ci95": summary["success_ci95"], "summary": summary,
           "theory": theory, "episodes": res.rows}
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
    if args.plot is not None:
        _plot_episode(plant, scenario, policy, args, res.trajectories)
    if args.json:
        print(json.dumps(jsonable(out), indent=2))
    else:
        _print_summary(policy.name, config, summary, theory_lines)
    return 0


def _run_plant_file(args: argparse.Namespace, name: str) -> int:
    """``run --plant NAME|FILE``: the episodes of policy ``name`` on the file's plant, and the
    theory; with ``--plot``, the picture of one episode."""
    from pendulum_lqg.cli.lti import lti_report, lti_run_setup

    lti, lti_sc, lti_policy, lti_config = lti_run_setup(args, name)
    _check_plot_args(args)
    with _watchdog(args):
        lti_res = _run_in_batches(lti, lti_sc, lti_policy, args, trajectory=False)
    if args.plot is not None:
        _plot_episode(lti, lti_sc, lti_policy, args, None)
    th = run_theory_lines(lti, lti_sc, lti_policy)
    return lti_report(args, lti_config, lti_sc, lti_res.rows, theory=th)


def _watchdog(args: argparse.Namespace) -> Any:
    """The watchdog of the plug-in's calls (``--call-timeout``)."""
    from pendulum_lqg.util.watchdog import call_timeout

    return call_timeout(args.call_timeout)


def _check_recording_target(args: argparse.Namespace) -> None:
    """The recording's file, checked before any episode runs: not '' or a folder, and a new path
    or a regular file (never a device or a FIFO)."""
    from pendulum_lqg.record.writer import recording_path
    from pendulum_lqg.util.files import output_file

    output_file("--record", recording_path(args.record if args.record is not None
                                           else DEFAULT_RECORDING), what="recording")


def _check_plot_args(args: argparse.Namespace) -> None:
    """``--plot`` / ``--plot-episode`` checked before anything runs."""
    if args.plot is None:
        if args.plot_episode != 0:
            raise cfg_error("--plot-episode: needs --plot FILE (the picture it selects)")
        return
    from pendulum_lqg.analysis.episode_plot import check_plot_path

    check_plot_path(args.plot)
    if args.plot_episode >= args.episodes:
        raise cfg_error(f"--plot-episode: expected an episode of this run, 0 … {args.episodes - 1}, "
                        f"got {args.plot_episode}")


def _plot_episode(plant: Any, scenario: Any, policy: Any, args: argparse.Namespace,
                  trajectories: list[Any] | None) -> None:
    """Draw episode ``--plot-episode`` to ``--plot``. Without a recording its trajectory is
    run again on its own: an episode's result does not depend on the batch it ran in."""
    from pendulum_lqg.analysis.episode_plot import episode_title, plot_episode, save_episode_plot
    from pendulum_lqg.core.runner import run_episodes

    k = args.plot_episode
    mine = [tr for tr in trajectories or [] if tr.episode == k]
    if not mine:
        mine = run_episodes(plant, scenario, policy, seed=args.seed, episodes=[k],
                            backend=args.backend, nthread=args.nthread,
                            trajectory=True).trajectories or []
    fig = plot_episode(mine[0], plant=plant, scenario=scenario,
                       title=f"{policy.name}: {episode_title(mine[0])}")
    path = save_episode_plot(fig, args.plot)
    print(f"plot: {path} (episode {k})", file=sys.stderr)


def _randomize(items: list[str] | None) -> dict[str, list[float]]:
    """``--randomize KEY=LO:HI`` options as the ``randomize`` mapping of a Scenario."""
    out: dict[str, list[float]] = {}
    for item in items or []:
        key, _, rng = item.partition("=")
        lo, _, hi = rng.partition(":")
        try:
            out[key.strip()] = [float(lo), float(hi)]
        except ValueError:
            raise cfg_error(f"--randomize: expected KEY=LO:HI such as pole_mass_scale=0.8:1.2, "
                             f"got {item!r}") from None
    return out


def _dataclass_dict(obj: Any) -> dict[str, Any]:
    import dataclasses

    return dataclasses.asdict(obj)


def _print_summary(name: str, config: dict[str, Any], s: dict[str, Any],
                   theory_lines: list[str]) -> None:
    from rich.console import Console
    from rich.markup import escape

    from pendulum_lqg.cli.lti import SATURATED_LABEL, SATURATED_SCALE, metric_table, success_line

    con = Console(highlight=False)
    sc = config["scenario"]
    con.print(escape(f"{name} — {s['episodes']} episodes, seed {config['seed']}, "
                     f"T = {sc['control_period']} s, {sc['duration']} s, noise scale "
                     f"{sc['noise']['scale']}, x0 = {list(sc['x0'])}"))
    extras = {k: sc[k] for k in ("measurement_delay", "actuator_delay", "dropout", "actuator_tau",
                                 "randomize") if sc.get(k)}
    if extras:
        con.print(escape("sensing and actuation: " + ", ".join(f"{k} = {v}"
                                                                 for k, v in extras.items())))
    con.print(success_line(s))
    t = metric_table()
    rows = [("cost", "J = ∫xᵀQx + uᵀRu dt (successes)", 1.0), ("rms_theta", "RMS θ [rad]", 1.0),
            ("max_abs_theta", "max |θ| [rad]", 1.0), ("rms_p", "RMS p [m]", 1.0),
            ("max_abs_p", "max |p| [m]", 1.0), ("rms_u", "RMS u [N]", 1.0),
            ("max_abs_u", "max |u| [N]", 1.0),
            ("saturated_fraction", SATURATED_LABEL, SATURATED_SCALE),
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
    print("\n".join(theory_lines))


def _run_in_batches(plant: Any, scenario: Any, policy: Any, args: argparse.Namespace, *,
                    trajectory: bool) -> Any:
    """``run_episodes`` over ``--episodes`` in batches (memory flat in the episode count; the rows
    do not depend on the batching), with its progress on stderr (:mod:`pendulum_lqg.util.progress`)."""
    from pendulum_lqg.core.runner import BatchResult, run_episodes
    from pendulum_lqg.model.interface import steps_per_period
    from pendulum_lqg.util import limits
    from pendulum_lqg.util.progress import Progress

    steps = scenario.n_periods * steps_per_period(plant, scenario.control_period)
    size = max(1, min(limits.RUN_BATCH, 20_000_000 // max(steps, 1)))    # ≤ ~2·10⁷ physics steps each
    total = args.episodes
    rows: list[dict[str, Any]] = []
    trajectories: list[Any] | None = [] if trajectory else None
    with Progress("run", total, unit="episodes", enabled=sys.stderr.isatty() and total > size,
                  lines=True) as bar:
        for start in range(0, total, size):
            res = run_episodes(plant, scenario, policy, seed=args.seed,
                               episodes=range(start, min(start + size, total)),
                               backend=args.backend, nthread=args.nthread, trajectory=trajectory)
            rows += res.rows
            if trajectories is not None:
                trajectories += res.trajectories or []
            bar.advance(len(res.rows))
    return BatchResult(rows=rows, trajectories=trajectories)


# ---- bench ---------------------------------------------------------------------------------------
def cmd_bench(args: argparse.Namespace) -> int:
    from pathlib import Path

    from pendulum_lqg.bench.executors import make_executor
    from pendulum_lqg.bench.experiments import load_spec
    from pendulum_lqg.bench.results import ResultsDir
    from pendulum_lqg.bench.sweep import SweepInterrupted, run_sweep

    spec = load_spec(args.experiment, episodes=args.episodes, seed=args.seed,
                     model_file=args.model)
    out = ResultsDir(args.out or Path("results") / spec.name)
    log = None if args.quiet else (lambda msg: print(msg, file=sys.stderr))
    if spec.study is not None:
        if args.executor != "local":
            raise cfg_error(f"--executor: the {spec.study} study runs on the local executor")
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
    from pendulum_lqg.bench.sweep import sigterm_as_interrupt

    log = None if args.quiet else (lambda msg: print(msg, file=sys.stderr))
    try:
        with sigterm_as_interrupt():
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

    from pendulum_lqg.analysis.report import make_report

    paths = [Path(p) for p in args.results]
    out = Path(args.out) if args.out else (paths[0] / "report" if len(paths) == 1
                                           else Path("report"))
    report = make_report(paths, out)
    print(f"report: {report}", file=sys.stderr)
    return 0


# ---- perf ----------------------------------------------------------------------------------------
def cmd_perf(args: argparse.Namespace) -> int:
    from pendulum_lqg.bench.perf import run_perf

    result = run_perf(episodes=args.episodes, duration=args.duration, nthread=args.nthread,
                      repeats=args.repeats, memory=args.memory,
                      log=lambda msg: print(msg, file=sys.stderr))
    if args.json:
        print(json.dumps(jsonable(result), indent=2))
    else:
        for line in result["report"]:
            print(line)
    return 0
