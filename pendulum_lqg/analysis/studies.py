"""Analysis studies that are not plain grids: ``study = "margins"`` and ``study = "roa"``.

An experiment file with ``study = "NAME"`` still has a ``[grid]`` (the configurations: policies,
control periods, initial estimates …) and an optional ``[NAME]`` table of study parameters
(:data:`STUDY_PARAMS`, with defaults). ``pendulum-lqg bench FILE`` calls :func:`run_study`, which
writes into a :class:`~pendulum_lqg.bench.results.ResultsDir`:

margins
    ``summary.json`` (every loop's margins, the plant zeros, the LTR sweeps), ``margins.csv`` (one
    row per loop), ``ltr.csv``, ``nyquist.csv`` (``L(jω)`` of the loops the report plots),
    ``summary.md``.
roa
    ``units/cNNN.json`` per configuration (a resumed run skips them), ``roa_bisection.csv`` (every
    Monte Carlo batch of the bisections), ``roa_map.csv`` (the noise-free (θ₀, θ̇₀) map),
    ``summary.json``, ``summary.md``.

All files are written atomically; ``spec.json`` holds the experiment (with its seed) and
``meta.json`` the machine facts.
"""

from __future__ import annotations

import dataclasses
import json
import os
import platform
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from pendulum_lqg.bench.study_params import STUDY_PARAMS
from pendulum_lqg.boundary import read_json
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.util.jsonio import plain

Log = Callable[[str], None] | None


def run_study(spec: Any, out: Any, *, nthread: int | None = None, log: Log = None,
              ) -> dict[str, object]:
    """Run ``spec`` (an :class:`~pendulum_lqg.bench.experiments.ExperimentSpec` with ``study``) into the
    prepared results folder ``out``; returns the summary written to ``summary.json``."""
    started = time.strftime("%Y-%m-%dT%H:%M:%S%z")
    t0 = time.perf_counter()
    if spec.study == "margins":
        summary = run_margins(spec, out, log=log)
    elif spec.study == "roa":
        summary = run_roa(spec, out, nthread=nthread, log=log)
    else:
        raise ConfigError(f"study: unknown {spec.study!r}; expected one of "
                          + ", ".join(STUDY_PARAMS))
    meta = {"started": started, "finished": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
            "elapsed_s": round(time.perf_counter() - t0, 3), "python": platform.python_version(),
            "machine": platform.machine(), "cpus": os.cpu_count()}
    _write(out, "meta.json", json.dumps(meta, indent=2, sort_keys=True) + "\n")
    return summary


# ---- helpers -------------------------------------------------------------------------------------
def _write(out: Any, name: str, text: str) -> None:
    from pendulum_lqg.util.files import atomic_write

    atomic_write(out.path / name, text)


def _json(obj: object) -> str:
    return json.dumps(_plain(obj), indent=2, sort_keys=True) + "\n"


def _plain(obj: object) -> object:
    """JSON-ready copy: arrays → lists, complex → [re, im], non-finite floats → strings."""
    return plain(obj, nonfinite_as_string=True)


def _csv(rows: list[dict[str, object]]) -> str:
    from pendulum_lqg.util.files import rows_to_csv

    return rows_to_csv(rows)


def _cell(v: object) -> str:
    if isinstance(v, float):
        if not np.isfinite(v):
            return "∞" if v > 0 else ("nan" if v != v else "−∞")
        return f"{v:.3g}"
    return str(v)


# ---- margins -------------------------------------------------------------------------------------
def policy_loop(policy: Any, Phi: np.ndarray, Gamma: np.ndarray, C: np.ndarray, dt: float) -> Any:
    """Loop gain at the plant input of a runtime :class:`~pendulum_lqg.policies.lqg.Policy` at period dt.

    The plant is ``(Φ, Γ, C)`` (the exact ZOH model the physics follows); the compensator is built
    from the policy's own estimator matrices (so an Euler-designed policy keeps its model error).
    ``kalman-tv`` is represented by its steady-state gain.
    """
    from pendulum_lqg.analysis import margins as M
    from pendulum_lqg.policies.estimators import (
        CurrentEstimator,
        PredictorEstimator,
        ReducedOrderEstimator,
        TimeVaryingKalman,
        TrueState,
    )

    est, K = policy.estimator, policy.K
    P = M.plant(Phi, Gamma, C, dt=dt)
    if isinstance(est, TrueState):
        return M.lq_loop(Phi, Gamma, K, dt=dt)
    if isinstance(est, CurrentEstimator):
        comp = M.current_compensator(est.Phi, est.Gamma, est.C, K, est.gain, dt=dt)
    elif isinstance(est, TimeVaryingKalman):
        comp = M.current_compensator(est.Phi, est.Gamma, est.C, K, policy.info["L"], dt=dt)
    elif isinstance(est, PredictorEstimator):
        comp = M.predictor_compensator(est.F, est.G_u, est.G_y, K, dt=dt)
    elif isinstance(est, ReducedOrderEstimator):
        comp = M.reduced_order_compensator(est.F, est.H_y, est.H_u, est.gain, est.T_inv, K, dt=dt)
    else:  # pragma: no cover - every estimator of policy.py is handled above
        raise ConfigError(f"policy: no loop model for estimator {type(est).__name__}")
    return M.loop_through(comp, P)


def _nyquist_rows(name: str, loop: Any, omega: np.ndarray) -> list[dict[str, object]]:
    from pendulum_lqg.analysis.margins import frequency_response

    L = frequency_response(loop, omega)
    return [{"loop": name, "omega": float(w), "re": float(z.real), "im": float(z.imag)}
            for w, z in zip(omega, L, strict=True)]


def run_margins(spec: Any, out: Any, *, log: Log = None) -> dict[str, object]:
    """Continuous LQ / LQG loops, LTR sweeps (y = [p, θ] and y = p), and each configuration's
    sampled loop at its period."""
    from pendulum_lqg import design
    from pendulum_lqg.analysis import margins as M
    from pendulum_lqg.model.linearize import linearize

    prm = spec.study_params
    plugins = [cfg.values.get("policy") for cfg in spec.configurations if cfg.plugin is not None]
    if plugins:
        raise ConfigError(f"grid.policy: the margins study needs each policy's linear loop; a "
                          f"plugin ({plugins[0]}) has none — run it with bench grids or roa")
    plant = spec.configurations[0].plants()[0]
    lin = linearize(plant)
    A, B, C = lin.A, lin.B, lin.C
    scenario0, dspec0 = spec.configurations[0].build()
    noise = scenario0.noise
    V = noise.V_density(scenario0.control_period)
    w = M.frequency_grid(lo=prm["omega_min"], hi=prm["omega_max"], n=prm["n_omega"])
    w_plot = M.frequency_grid(lo=prm["omega_min"], hi=prm["omega_max"], n=prm["nyquist_points"])
    lqr = design.lqr(A, B, dspec0.Q_matrix, dspec0.R_matrix)
    kb = design.kalman(A, np.eye(4), C, noise.W, V)
    loops = {"LQ (continuous)": M.lq_loop(A, B, lqr.K),
             "LQG Kalman–Bucy (continuous)": M.loop_through(
                 M.lqg_compensator(A, B, C, lqr.K, kb.L), M.plant(A, B, C))}
    rows: list[dict[str, object]] = []
    nyq: list[dict[str, object]] = []
    for name, loop in loops.items():
        rows.append({"loop": name, "policy": name.split(" (")[0], "control_period": 0.0,
                     **M.loop_margins(loop, w).to_dict()})
        nyq += _nyquist_rows(name, loop, w_plot)
    ltr_rows, ltr_nyq = _ltr(lin, lqr.K, V, [float(q) for q in prm["q"]], w, w_plot, log)
    sampled, sampled_nyq = _sampled_loops(spec, plant, lin, scenario0.control_period, log)
    summary = {"experiment": spec.name, "study": "margins", "seed": spec.seed,
               "params": prm, "K_lqr": lqr.K, "L_kalman_bucy": kb.L, "zeros": _zeros(A, B, C),
               "loops": rows + sampled, "ltr": ltr_rows}
    _write(out, "summary.json", _json(summary))
    _write(out, "margins.csv", _csv(_uniform(rows + sampled)))
    _write(out, "ltr.csv", _csv(ltr_rows))
    _write(out, "nyquist.csv", _csv(nyq + ltr_nyq + sampled_nyq))
    _write(out, "summary.md", margins_markdown(summary))
    return summary


def _ltr(lin: Any, K: np.ndarray, V: np.ndarray, qs: list[float], w: np.ndarray,
         w_plot: np.ndarray, log: Log) -> tuple[list[dict[str, object]], list[dict[str, object]]]:
    """Loop transfer recovery (W = q²BBᵀ, V fixed) measuring y = [p, θ] and y = p: a row of
    margins per measurement and q, and the Nyquist rows of the smallest, middle and largest q
    with y = [p, θ]."""
    from pendulum_lqg import design
    from pendulum_lqg.analysis import margins as M

    A, B, C = lin.A, lin.B, lin.C
    rows: list[dict[str, object]] = []
    for label, Cm, Vm in (("y=[p,θ]", C, V), ("y=p", C[:1], V[:1, :1])):
        for pt in M.ltr_sweep(A, B, Cm, K, Vm, qs, omega=w):
            rows.append({"measurement": label, "q": pt.q, "recovery_error": pt.recovery_error,
                         **pt.margins.to_dict()})
        if log:
            log(f"LTR {label}: q = {qs[0]:g} … {qs[-1]:g}")
    nyq: list[dict[str, object]] = []
    for q in (qs[0], qs[len(qs) // 2], qs[-1]):
        kf = design.kalman(A, np.eye(4), C, q * q * (B @ B.T), V)
        nyq += _nyquist_rows(f"LTR q={q:g}", M.loop_through(
            M.lqg_compensator(A, B, C, K, kf.L), M.plant(A, B, C)), w_plot)
    return rows, nyq


def _sampled_loops(spec: Any, plant: Any, lin: Any, T0: float, log: Log,
                   ) -> tuple[list[dict[str, object]], list[dict[str, object]]]:
    """Each configuration's sampled loop (its policy on the exact ZOH plant at its period): a row
    of margins each, and the Nyquist rows of those at the first configuration's period ``T0``."""
    from pendulum_lqg.analysis import margins as M
    from pendulum_lqg.model.interface import discretize_zoh
    from pendulum_lqg.policies.lqg import design_policy

    prm = spec.study_params
    rows: list[dict[str, object]] = []
    nyq: list[dict[str, object]] = []
    for cfg in spec.configurations:
        scenario, dspec = cfg.build()
        T = scenario.control_period
        policy = design_policy(plant, T, scenario.noise, dspec, linear=lin)
        zoh = discretize_zoh(lin, T)
        loop = policy_loop(policy, zoh.Phi, zoh.Gamma, lin.C, T)
        wd = M.frequency_grid(lo=prm["omega_min"], hi=prm["omega_max"], n=prm["n_omega"], dt=T)
        name = f"{policy.name} ({dspec.discretization}, T={T:g})"
        rows.append({"loop": name, "policy": policy.name, "control_period": T,
                     "discretization": dspec.discretization, "config": cfg.index,
                     **M.loop_margins(loop, wd).to_dict()})
        if log:
            log(f"margins {name}")
        if T == T0:
            nyq += _nyquist_rows(name, loop, M.frequency_grid(
                lo=prm["omega_min"], hi=prm["omega_max"], n=prm["nyquist_points"], dt=T))
    return rows, nyq


def _zeros(A: np.ndarray, B: np.ndarray, C: np.ndarray) -> dict[str, np.ndarray]:
    """The open-loop poles, the zeros of force → p and force → θ, and the transmission zeros of
    y = [p, θ]."""
    from pendulum_lqg.analysis import margins as M

    chans = M.channel_zeros(A, B, C)
    return {"force_to_p": chans[0], "force_to_theta": chans[1],
            "transmission_zeros_y=[p,θ]": M.transmission_zeros(A, B, C),
            "open_loop_poles": np.linalg.eigvals(A)}


def _uniform(rows: list[dict[str, object]]) -> list[dict[str, object]]:
    keys: list[str] = []
    for r in rows:
        keys += [k for k in r if k not in keys]
    return [{k: r.get(k, "") for k in keys} for r in rows]


def _zeros_text(z: object) -> str:
    arr = np.asarray(z, dtype=complex).ravel()
    if arr.size == 0:
        return "none"
    return ", ".join(f"{v.real:.4g}" if abs(v.imag) < 1e-9 else f"{v.real:.4g}{v.imag:+.4g}j"
                     for v in arr)


def margins_markdown(summary: dict[str, Any]) -> str:
    z = summary["zeros"]
    head = ["loop", "closed loop stable", "min abs(1+L)", "GM lower", "GM upper", "PM [deg]",
            "disk margin α", "disk GM", "disk PM [deg]"]
    lines = [f"**{summary['experiment']}** — stability margins at the plant input "
             "(loop broken at the cart force)", "",
             f"Open-loop poles: {_zeros_text(z['open_loop_poles'])}. Zeros force→p: "
             f"{_zeros_text(z['force_to_p'])}; force→θ: {_zeros_text(z['force_to_theta'])}; "
             f"transmission zeros of y = [p, θ]: {_zeros_text(z['transmission_zeros_y=[p,θ]'])}.",
             "", "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in summary["loops"]:
        lines.append("| " + " | ".join([r["loop"], str(r["closed_loop_stable"])] + [_cell(r[k]) for k in (
            "min_return_difference", "gain_margin_lower", "gain_margin_upper", "phase_margin_deg",
            "disk_margin", "disk_gain_margin", "disk_phase_margin_deg")]) + " |")
    lines += ["", "Loop transfer recovery: W = q²BBᵀ, V fixed (continuous Kalman–Bucy + LQR).", "",
              "| measurement | q | recovery error | min abs(1+L) | GM lower | GM upper | PM [deg] | "
              "disk margin α |", "|---|---|---|---|---|---|---|---|"]
    for r in summary["ltr"]:
        lines.append("| " + " | ".join([r["measurement"]] + [_cell(r[k]) for k in (
            "q", "recovery_error", "min_return_difference", "gain_margin_lower",
            "gain_margin_upper", "phase_margin_deg", "disk_margin")]) + " |")
    return "\n".join(lines) + "\n"


# ---- region of attraction ------------------------------------------------------------------------
def run_roa(spec: Any, out: Any, *, nthread: int | None = None, log: Log = None,
            ) -> dict[str, object]:
    """Per configuration: the bisection for the largest θ₀ (noisy, ``spec.episodes`` per batch)
    and the noise-free (θ₀, θ̇₀) map. Finished configurations are kept in ``units/`` and skipped
    by a resumed run."""
    prm = spec.study_params
    t_lo, t_hi, t_n = prm["map_theta"]
    d_lo, d_hi, d_n = prm["map_theta_dot"]
    thetas = np.linspace(t_lo, t_hi, int(t_n))
    theta_dots = np.linspace(d_lo, d_hi, int(d_n))
    results = []
    for cfg in spec.configurations:
        unit = out.units_dir / f"c{cfg.index:03d}.json"
        if unit.exists():
            results.append(read_json(unit, where="unit"))   # regular, size and nesting bounded
            continue
        entry = _roa_entry(spec, cfg, thetas, theta_dots, nthread)
        _write(out, f"units/c{cfg.index:03d}.json", _json(entry))
        results.append(json.loads(_json(entry)))
        if log:
            log(f"[{cfg.index + 1}/{len(spec.configurations)}] {cfg.label}: θ* = "
                f"{entry['theta_star']:.3f} rad, map recovered "
                f"{entry['map_recovered_fraction']:.0%}")
    bis_rows, map_rows = _roa_rows(results, thetas, theta_dots)
    summary = {"experiment": spec.name, "study": "roa", "seed": spec.seed,
               "episodes_per_batch": spec.episodes, "params": prm,
               "configurations": [{k: v for k, v in r.items() if k not in ("map", "evaluations")}
                                  for r in results]}
    _write(out, "roa_bisection.csv", _csv(bis_rows))
    _write(out, "roa_map.csv", _csv(map_rows))
    _write(out, "summary.json", _json(summary))
    _write(out, "summary.md", roa_markdown(summary))
    return summary


def _roa_entry(spec: Any, cfg: Any, thetas: np.ndarray, theta_dots: np.ndarray,
               nthread: int | None) -> dict[str, Any]:
    """One configuration's unit: the bisection for θ* under noise and the noise-free map."""
    from pendulum_lqg.analysis.roa import bisect_theta, success_map
    from pendulum_lqg.policies.loading import build_policy

    prm = spec.study_params
    scenario, dspec = cfg.build()
    nominal, simulated = cfg.plants(scenario)
    policy = build_policy(cfg.plugin, plant=nominal, scenario=scenario, spec=dspec)
    bis = bisect_theta(simulated, scenario, policy, seed=spec.seed, episodes=spec.episodes,
                       level=prm["level"], theta_lo=prm["theta_lo"],
                       theta_hi=prm["theta_hi"], tolerance=prm["tolerance"], nthread=nthread)
    quiet = scenario.replace(noise=dataclasses.replace(scenario.noise, scale=0.0))
    smap = success_map(simulated, quiet, policy, thetas, theta_dots, seed=spec.seed,
                       settle_fraction=prm["settle_fraction"], nthread=nthread)
    return {"index": cfg.index, "values": cfg.values, "label": cfg.label,
            "policy": policy.name, "estimate0": scenario.estimate0,
            "theta_star": bis.theta_star, "theta_fail": bis.theta_fail,
            "censored": bis.censored, "evaluations": [e.to_dict() for e in bis.evaluations],
            "map_recovered_fraction": float(smap["recovered"].mean()),
            "map": {k: v.astype(float).tolist() for k, v in smap.items()}}


def _roa_rows(results: list[dict[str, Any]], thetas: np.ndarray, theta_dots: np.ndarray,
              ) -> tuple[list[dict[str, object]], list[dict[str, object]]]:
    """The rows of ``roa_bisection.csv`` (one per evaluation) and ``roa_map.csv`` (one per map
    point) of every configuration."""
    bis_rows: list[dict[str, object]] = []
    map_rows: list[dict[str, object]] = []
    for r in results:
        for e in r["evaluations"]:
            bis_rows.append({"config": r["index"], "policy": r["policy"],
                             "estimate0": r["estimate0"], **e})
        for i, th in enumerate(thetas):
            for j, thd in enumerate(theta_dots):
                map_rows.append({"config": r["index"], "policy": r["policy"],
                                 "estimate0": r["estimate0"], "theta0": round(float(th), 9),
                                 "theta_dot0": round(float(thd), 9),
                                 "survived": bool(r["map"]["survived"][i][j]),
                                 "recovered": bool(r["map"]["recovered"][i][j]),
                                 "cost": float(f"{r['map']['cost'][i][j]:.6g}")})
    return bis_rows, map_rows


def roa_markdown(summary: dict[str, Any]) -> str:
    prm = summary["params"]
    lines = [f"**{summary['experiment']}** — region of attraction: largest |θ₀| with ≥ "
             f"{prm['level']:.0%} of {summary['episodes_per_batch']} noisy episodes surviving "
             f"(bisection to {prm['tolerance']} rad, seed {summary['seed']}), and the share of the "
             "noise-free (θ₀, θ̇₀) map that recovers", "",
             "| policy | x̂₀ | θ* [rad] | θ* [deg] | first failing θ₀ [rad] | map recovered |",
             "|---|---|---|---|---|---|"]
    for c in summary["configurations"]:
        star = float(c["theta_star"])
        star_txt = f"≥ {star:.3f}" if c["censored"] and star > 0 else f"{star:.3f}"
        fail = c["theta_fail"]
        fail_txt = "–" if isinstance(fail, str) else f"{float(fail):.3f}"
        lines.append(f"| {c['policy']} | {c['estimate0']} | {star_txt} | "
                     f"{np.degrees(star):.1f} | {fail_txt} | {c['map_recovered_fraction']:.0%} |")
    return "\n".join(lines) + "\n"
