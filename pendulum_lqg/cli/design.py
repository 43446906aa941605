"""``pendulum-lqg design``: the linearised model and every design, printed or as JSON; with
``--lti FILE`` the same for a plant given as matrices (:mod:`pendulum_lqg.model.lti`)."""

from __future__ import annotations

import argparse
import json
from typing import Any

from pendulum_lqg.cli.parser import jsonable, noise_from_args, spec_from_args


# ---- design --------------------------------------------------------------------------------------
def cmd_design(args: argparse.Namespace) -> int:
    import numpy as np

    from pendulum_lqg.model.catalog import is_cartpole
    from pendulum_lqg.model.plant import load_plant
    from pendulum_lqg.policies.lqg import design_all

    if not is_cartpole(args.plant_ref):
        return _design_plant_file(args)
    plant = load_plant(args.model)
    noise = noise_from_args(args)
    spec = spec_from_args(args)
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
        print(json.dumps(jsonable(data), indent=2))
        return 0
    _print_design(data, plant)
    return 0


def _matrix_lines(M: Any, indent: int = 4) -> str:
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
        lines += [f"  {key} =", _matrix_lines(d[key])]
    lines += [f"  open-loop poles: {_poles(d['open_loop_poles'])}",
              f"  controllability: rank {s['controllability_rank']}/4, PBH-uncontrollable modes: "
              f"{_poles(s['uncontrollable_modes_pbh'])}, stabilisable: {s['stabilizable']}",
              f"  observability:   rank {s['observability_rank']}/4, PBH-unobservable modes: "
              f"{_poles(s['unobservable_modes_pbh'])}, detectable: {s['detectable']}",
              "", f"Discrete model at T = {d['dt']:g} s (exact ZOH)"]
    for key in ("Phi", "Gamma"):
        lines += [f"  {key} =", _matrix_lines(d[key])]
    lines += [f"  max |ZOH − composed mjd_transitionFD| = {d['zoh_vs_transition_fd_max_abs']:.3g}"
              " (the Euler integrator's O(h) error)", ""]
    lines += ["Weights and noise",
              f"  Q = diag{tuple(float(v) for v in w['Q'].diagonal())}, R = {float(w['R'][0, 0]):g}"
              "; DLQR uses their exact sampled-data equivalents (Qd, Rd, Nd)",
              f"  process noise density W = diag{tuple(float(v) for v in w['W'].diagonal())} "
              "(units²·s), per sample Qd = W·T",
              f"  measurement covariance V = diag{tuple(float(v) for v in w['V'].diagonal())} per "
              "sample (Kalman–Bucy uses the density V·T)", ""]
    lines += _gain_lines(d)
    print("\n".join(lines))


#: The designs ``design`` prints, in order: title, gain key, poles key, plane.
_GAIN_ROWS = (
        ("Continuous LQR, u = −K x", "K_lqr", "K_lqr_poles", "s"),
        ("Discrete LQR (ZOH model, sampled cost)", "K_dlqr", "K_dlqr_poles", "z"),
        ("Kalman–Bucy (continuous)", "L_kalman", "L_kalman_poles", "s"),
        ("Discrete Kalman, filter (current-estimate) gain L", "L_dkalman", "L_dkalman_poles", "z"),
        ("Discrete Kalman, predictor gain L_pred = Φ L (python-control dlqe)",
         "L_dkalman_predictor", "L_dkalman_poles", "z"),
        ("Luenberger (continuous poles)", "L_luenberger", "L_luenberger_poles", "s"),
        ("Luenberger (discrete, current form, z = exp(sT))", "L_dluenberger",
         "L_dluenberger_poles", "z"),
)


def _gain_lines(d: dict[str, Any]) -> list[str]:
    """The gains with their poles and the separation check (the designs ``d`` holds: a plant
    given in discrete time has no continuous ones)."""
    lines = []
    for title, gain, poles, plane in _GAIN_ROWS:
        if d.get(gain) is not None:
            lines += [title, _matrix_lines(d[gain]), f"    poles ({plane}): {_poles(d[poles])}",
                      ""]
    sep = d["separation"]
    cont = sep.get("continuous_max_error")
    lines.append("Separation principle: eig(LQG loop) = eig(A − BK) ∪ eig(A − LC), max mismatch "
                 + (f"{cont:.2g} (continuous LQR + Kalman–Bucy), " if cont is not None else "")
                 + f"{sep['discrete_max_error']:.2g} (DLQR + discrete Kalman, current form)")
    return lines


# ---- design --plant NAME|FILE ---------------------------------------------------------------------
def _design_plant_file(args: argparse.Namespace) -> int:
    """``design --plant NAME|FILE``: the plant, its discretisation and every design, in the
    layout and the JSON keys of the cart-pole's ``design`` (a plant given in discrete time has no
    continuous designs: their keys are absent; a MuJoCo plant adds MuJoCo's own discretisation,
    ``mjd_transitionFD``, beside the exact ZOH)."""
    import numpy as np

    from pendulum_lqg.cli.lti import CARTPOLE_OPTIONS, refuse_cartpole_options
    from pendulum_lqg.model.catalog import load_named_plant
    from pendulum_lqg.policies.lti import design_lti_all
    from pendulum_lqg.problem import defaults

    refuse_cartpole_options(args, {**CARTPOLE_OPTIONS,
                                   "dt": (defaults.CONTROL_PERIOD, "the file's control_period")})
    plant = load_named_plant(args.plant_ref, what="--plant")
    d = design_lti_all(plant)
    data = _lti_data(args.plant_ref, plant, d)
    fd = plant.transition(plant.control_period)
    if fd is not None:
        data.update(Phi_transition_fd=fd.Phi, Gamma_transition_fd=fd.Gamma,
                    zoh_vs_transition_fd_max_abs=max(float(np.max(np.abs(plant.Phi - fd.Phi))),
                                                     float(np.max(np.abs(plant.Gamma - fd.Gamma)))),
                    model=str(plant.mjcf), force_limit=plant.limits_per_input,
                    state_limits=plant.state_limits, kind=plant.kind_label)
    for key in [k for k in data if k.endswith("_poles")]:
        data[key] = np.asarray(data[key], dtype=complex)      # always [re, im] pairs in JSON
    if args.json:
        print(json.dumps(jsonable(data), indent=2))
        return 0
    _print_lti_design(data)
    return 0


def _structure(st: Any) -> dict[str, Any]:
    return {"controllability_rank": st.controllability_rank,
            "observability_rank": st.observability_rank,
            "uncontrollable_modes_pbh": st.uncontrollable_modes,
            "unobservable_modes_pbh": st.unobservable_modes,
            "stabilizable": st.stabilizable, "detectable": st.detectable}


def _lti_data(path: str, plant: Any, d: dict[str, Any]) -> dict[str, Any]:
    """The JSON of ``design --lti`` (the cart-pole's keys where they apply)."""
    data: dict[str, Any] = {
        "lti": str(path), "plant": plant.name, "description": plant.description,
        "dt": d["dt"], "states": list(plant.state_names), "inputs": list(plant.input_names),
        "outputs": list(plant.output_names), "A": plant.A, "B": plant.B, "C": plant.C,
        "G": plant.G, "open_loop_poles": d.get("open_loop_poles"),
        "Phi": plant.Phi, "Gamma": plant.Gamma,
        "open_loop_poles_discrete": d["open_loop_poles_discrete"],
        "structure": _structure(d["structure"]) if "structure" in d else None,
        "structure_discrete": _structure(d["structure_discrete"]), "weights": d["weights"],
        "K_dlqr": d["dlqr"].K, "K_dlqr_poles": d["dlqr"].poles, "P_dlqr": d["dlqr"].P,
        "L_dkalman": d["dkalman"].L, "L_dkalman_poles": d["dkalman"].poles,
        "L_dkalman_predictor": d["dkalman"].L_pred, "M_dkalman": d["dkalman"].M,
        "P_dkalman": d["dkalman"].P,
        "L_dluenberger": d["dluenberger"].L, "L_dluenberger_poles": d["dluenberger"].poles,
        "separation": {"discrete_max_error": d["dlqg"].separation_error,
                       "discrete_closed_loop_poles": d["dlqg"].poles}}
    if "lqr" in d:
        data.update({
            "K_lqr": d["lqr"].K, "K_lqr_poles": d["lqr"].poles, "P_lqr": d["lqr"].P,
            "L_kalman": d["kalman"].L, "L_kalman_poles": d["kalman"].poles,
            "P_kalman": d["kalman"].P,
            "L_luenberger": d["luenberger"].L, "L_luenberger_poles": d["luenberger"].poles})
        data["separation"].update(continuous_max_error=d["lqg"].separation_error,
                                  continuous_closed_loop_poles=d["lqg"].poles)
    return {k: v for k, v in data.items() if v is not None}


def _print_lti_design(d: dict[str, Any]) -> None:
    n, m, p = len(d["states"]), len(d["inputs"]), len(d["outputs"])
    w = d["weights"]
    lines = [f"pendulum_lqg design — {d.get('kind', 'LTI plant')} {d['plant']} ({d['lti']})",
             *([d["description"]] if d["description"] else []),
             f"state x = [{', '.join(d['states'])}], input u = [{', '.join(d['inputs'])}], "
             f"output y = [{', '.join(d['outputs'])}]; n = {n}, m = {m}, p = {p}; "
             f"T = {d['dt']:g} s", ""]
    if "A" in d:
        s = d["structure"]
        lines.append("Continuous model ẋ = A x + B u + G w, y = C x + v")
        for key in ("A", "B", "C", "G"):
            lines += [f"  {key} =", _matrix_lines(d[key])]
        lines += [f"  open-loop poles: {_poles(d['open_loop_poles'])}",
                  f"  controllability: rank {s['controllability_rank']}/{n}, stabilisable: "
                  f"{s['stabilizable']}; observability: rank {s['observability_rank']}/{n}, "
                  f"detectable: {s['detectable']}", "",
                  f"Discrete model at T = {d['dt']:g} s (exact ZOH)"]
    else:
        lines.append(f"Discrete model x[k+1] = Φ x[k] + Γ u[k] + w, y = C x + v (T = "
                     f"{d['dt']:g} s)")
    for key in ("Phi", "Gamma") + (() if "A" in d else ("C",)):
        lines += [f"  {key} =", _matrix_lines(d[key])]
    sd = d["structure_discrete"]
    lines += [f"  open-loop poles (z): {_poles(d['open_loop_poles_discrete'])}; stabilisable: "
              f"{sd['stabilizable']}, detectable: {sd['detectable']}", "", "Weights and noise"]
    for key, what in (("Q", "Q"), ("R", "R"), ("N", "N (cross term)"),
                      ("Qd", "Qd (per period)"), ("Rd", "Rd"), ("Nd", "Nd"),
                      ("W", "W (the file's)"), ("W_per_period", "Wd = cov of one period's w"),
                      ("V", "V (per sample)"), ("V_density", "V·T (Kalman–Bucy's density)")):
        if key in w:
            lines += [f"  {what} =", _matrix_lines(w[key])]
    lines += ["", *_gain_lines(d)]
    print("\n".join(lines))
