"""Analysis studies: margins (Kalman inequality, LQG, LTR), sample-period ordering, ROA, report."""

from __future__ import annotations

import math
from pathlib import Path

import control
import numpy as np
import pytest

from pendulum_lqg import design
from pendulum_lqg.analysis import margins as M
from pendulum_lqg.core.noise import NoiseModel
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.model.interface import discretize_zoh
from pendulum_lqg.model.linearize import linearize
from pendulum_lqg.model.plant import load_plant

ROOT = Path(__file__).resolve().parents[2]
W_GRID = M.frequency_grid(lo=1e-3, hi=1e3, n=4000)


@pytest.fixture(scope="module")
def cartpole():
    plant = load_plant()
    lin = linearize(plant)
    K = design.lqr(lin.A, lin.B, np.eye(4), np.eye(1)).K
    V = NoiseModel.lecture().V_density(0.01)
    return plant, lin, K, V


# ---- closed forms ---------------------------------------------------------------------------------
def test_scalar_lq_loop_margins_closed_form():
    # ẋ = x + u, Q = R = 1: K = 1 + √2 (docs/theory.md §5.1), L(s) = K/(s − 1).
    K = 1 + math.sqrt(2)
    rep = M.loop_margins(M.lq_loop([[1.0]], [[1.0]], [[K]]), W_GRID)
    assert rep.closed_loop_stable
    # |1 + L(jω)| = |jω + √2| / |jω − 1|: √2 at ω = 0, → 1 from above as ω → ∞.
    assert rep.min_return_difference >= 1.0
    assert rep.min_return_difference == pytest.approx(math.sqrt((1e6 + 2) / (1e6 + 1)), rel=1e-9)
    assert rep.gain_margin_lower == pytest.approx(1 / K, rel=1e-9)           # L(0) = −K
    assert rep.gain_margin_upper == math.inf
    # |L| = 1 at ω = √(K² − 1); PM = atan ω.
    assert rep.phase_margin_deg == pytest.approx(math.degrees(math.atan(math.sqrt(K * K - 1))),
                                                 abs=1e-3)


def test_compensators_reproduce_the_lqg_closed_loop_poles(cartpole):
    _, lin, K, V = cartpole
    A, B, C = lin.A, lin.B, lin.C
    kb = design.kalman(A, np.eye(4), C, NoiseModel.lecture().W, V)
    loop = M.loop_through(M.lqg_compensator(A, B, C, K, kb.L), M.plant(A, B, C))
    Acl = np.asarray(loop.A) - np.asarray(loop.B) @ np.asarray(loop.C)
    ref = design.lqg(A, B, C, K, kb.L, form="continuous").poles
    assert np.sort_complex(np.linalg.eigvals(Acl)) == pytest.approx(np.sort_complex(ref), abs=1e-8)

    T = 0.05
    zoh = discretize_zoh(lin, T)
    Kd = design.dlqr(zoh.Phi, zoh.Gamma, np.eye(4), np.eye(1)).K
    kf = design.dkalman(zoh.Phi, np.eye(4), C, NoiseModel.lecture().W * T, NoiseModel.lecture().V)
    loop = M.loop_through(M.current_compensator(zoh.Phi, zoh.Gamma, C, Kd, kf.L, dt=T),
                          M.plant(zoh.Phi, zoh.Gamma, C, dt=T))
    A_, B_, C_, D_ = (np.asarray(m) for m in (loop.A, loop.B, loop.C, loop.D))
    Acl = A_ - B_ @ np.linalg.solve(np.eye(1) + D_, C_)
    ref = design.lqg(zoh.Phi, zoh.Gamma, C, Kd, kf.L, form="current").poles
    assert np.sort_complex(np.linalg.eigvals(Acl)) == pytest.approx(np.sort_complex(ref), abs=1e-8)


# ---- the cart-pole ---------------------------------------------------------------------------------
def test_kalman_inequality_on_the_cartpole_lq_loop(cartpole):
    _, lin, K, _ = cartpole
    loop = M.lq_loop(lin.A, lin.B, K)
    rd = M.return_difference(loop, W_GRID)
    assert rd.min() >= 1 - 1e-9
    rep = M.loop_margins(loop, W_GRID)
    assert rep.closed_loop_stable
    assert rep.phase_margin_deg >= 60.0
    assert rep.gain_margin_upper == math.inf
    assert rep.gain_margin_lower <= 0.5          # gain margin [1/2, ∞) at least
    assert rep.disk_margin > 0.7                 # balanced disk margin of the same loop


def test_lqg_loop_has_no_guaranteed_margins(cartpole):
    _, lin, K, V = cartpole
    A, B, C = lin.A, lin.B, lin.C
    kb = design.kalman(A, np.eye(4), C, NoiseModel.lecture().W, V)
    rep = M.loop_margins(M.loop_through(M.lqg_compensator(A, B, C, K, kb.L), M.plant(A, B, C)),
                         W_GRID)
    assert rep.closed_loop_stable
    assert rep.min_return_difference < 0.25       # the Nyquist curve enters the unit disc at −1
    assert rep.phase_margin_deg < 20.0


def test_plant_zeros_and_loop_transfer_recovery(cartpole):
    _, lin, K, V = cartpole
    A, B, C = lin.A, lin.B, lin.C
    to_p, to_theta = M.channel_zeros(A, B, C)
    rhp = to_p[to_p.real > 0]
    assert rhp.size == 1 and abs(rhp[0].imag) < 1e-9 and 3.0 < rhp[0].real < 4.5
    assert np.allclose(to_theta, 0, atol=1e-6)
    assert M.transmission_zeros(A, B, C).size == 0      # y = [p, θ]: no common zero
    pole = np.max(np.linalg.eigvals(A).real)

    lq = M.loop_margins(M.lq_loop(A, B, K), W_GRID)
    sweep = M.ltr_sweep(A, B, C, K, V, [0.1, 10.0, 1e4], omega=W_GRID)
    errs = [pt.recovery_error for pt in sweep]
    assert errs[0] > errs[1] > errs[2] and errs[2] < 0.02
    assert sweep[-1].margins.phase_margin_deg == pytest.approx(lq.phase_margin_deg, abs=1.5)
    assert sweep[-1].margins.min_return_difference > 0.98

    # y = p alone: RHP zero z near the RHP pole p — no recovery, and no controller can do better
    # than min |1 + L| ≤ |p − z| / |p + z| (the sensitivity peak bound).
    bound = abs(pole - rhp[0].real) / abs(pole + rhp[0].real)
    only_p = M.ltr_sweep(A, B, C[:1], K, V[:1, :1], [0.1, 1e4], omega=W_GRID)
    for pt in only_p:
        assert pt.margins.min_return_difference <= bound
        assert pt.recovery_error > 0.9


def test_sampling_erodes_the_lq_margins(cartpole):
    _, lin, K, _ = cartpole
    pms = []
    for T in (0.01, 0.1, 0.2):
        zoh = discretize_zoh(lin, T)
        rep = M.loop_margins(M.lq_loop(zoh.Phi, zoh.Gamma, K, dt=T), M.frequency_grid(dt=T))
        assert rep.gain_margin_upper < math.inf      # sampled: a finite upper gain margin
        pms.append(rep.phase_margin_deg)
    assert pms[0] > pms[1] > pms[2]


# ---- studies through the one simulation core --------------------------------------------------------
def test_sample_period_ordering_discrete_survives_where_emulation_fails():
    from pendulum_lqg.bench.experiments import parse_spec, run_unit

    spec = parse_spec({
        "name": "sp_small", "episodes": 1, "seed": 0,
        "scenario": {"duration": 5.0},
        "grid": {"policy": ["lqr+none", "dlqr+none"], "control_period": [0.25, 0.3],
                 "noise_scale": [0.0]},
    })
    ok = {}
    for unit in spec.units():
        rows = run_unit(unit, nthread=1)
        v = unit.config.values
        ok[(v["policy"], v["control_period"])] = bool(rows[0]["success"])
    T_fail = min(T for (p, T), s in ok.items() if p == "lqr+none" and not s)
    assert ok[("lqr+none", 0.25)]                          # emulation still works at 0.25 s …
    assert T_fail == 0.3                                   # … and fails at 0.3 s
    assert all(s for (p, T), s in ok.items() if p == "dlqr+none" and T <= T_fail)


def test_roa_bisection_brackets_the_noise_free_boundary():
    from pendulum_lqg.analysis.roa import bisect_theta, success_count
    from pendulum_lqg.core.scenario import Scenario
    from pendulum_lqg.policies.lqg import DesignSpec, design_policy

    plant = load_plant()
    sc = Scenario(duration=3.0, noise=NoiseModel.lecture(scale=0.0), theta_max=1.5)
    policy = design_policy(plant, sc.control_period, sc.noise,
                           DesignSpec(controller="dlqr", observer="none"))
    res = bisect_theta(plant, sc, policy, seed=0, episodes=1, theta_hi=1.2, tolerance=0.05)
    assert not res.censored
    assert 0.2 < res.theta_star < res.theta_fail <= res.theta_star + 0.05
    assert success_count(plant, sc, policy, res.theta_star, seed=0, episodes=1).successes == 1
    assert success_count(plant, sc, policy, res.theta_fail, seed=0, episodes=1).successes == 0


def test_study_specs_parse_and_reject_unknown_keys():
    from pendulum_lqg.bench.experiments import load_spec, parse_spec

    for name in ("margins", "roa", "mismatch", "sample_period"):
        spec = load_spec(name)
        assert spec.configurations
    assert load_spec("margins").study == "margins"
    assert load_spec("roa").study_params["level"] == 0.95
    with pytest.raises(ConfigError, match="unknown key 'levl'"):
        parse_spec({"study": "roa", "roa": {"levl": 0.9}, "grid": {"policy": ["dlqr+none"]}})
    with pytest.raises(ConfigError, match="study"):
        parse_spec({"study": "nope"})
    with pytest.raises(ConfigError, match="needs study"):
        parse_spec({"margins": {"q": [1.0]}})


# ---- the report on the committed small results ------------------------------------------------------
# slow: the quick loop has test_report_on_fresh_results (tests/analysis/test_studies.py)
@pytest.mark.slow
@pytest.mark.skipif(not (ROOT / "results_small" / "margins" / "summary.json").is_file(),
                    reason="committed small results absent")
def test_report_on_the_committed_small_results(tmp_path):
    from pendulum_lqg.cli import main

    assert main(["report", str(ROOT / "results_small"), "--out", str(tmp_path)]) == 0
    text = (tmp_path / "report.md").read_text()
    expected = ["margins_nyquist.png", "margins_ltr.png", "margins_sampled.png",
                "noise_success_vs_noise_scale.png", "noise_estimation_error.png",
                "noise_cost_distribution.png", "sample_period_success_vs_control_period.png"]
    if (ROOT / "results_small" / "roa" / "summary.json").is_file():
        expected += ["roa_maps.png", "roa_theta_star.png"]
    if (ROOT / "results_small" / "mismatch" / "summary.json").is_file():
        expected += ["mismatch_curves.png", "mismatch_success_grid.png"]
    for name in expected:
        png = tmp_path / name
        assert png.is_file() and png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", name
        assert f"]({name})" in text
    assert main(["report", str(tmp_path / "nothing-here")]) == 2


# ---- cross-check against python-control -------------------------------------------------------------
def _closed_loop_stable_with_gain(loop, k):
    """Whether ``k·L`` in negative unity feedback is stable: python-control's own loop algebra and
    poles, independent of :func:`margins.closed_loop_stable`."""
    poles = control.feedback(k * loop, 1).poles()
    return bool(np.all(np.abs(poles) < 1)) if loop.isdtime(strict=True) else bool(
        np.all(poles.real < 0))


def _loops(cartpole):
    _, lin, K, V = cartpole
    A, B, C = lin.A, lin.B, lin.C
    kb = design.kalman(A, np.eye(4), C, NoiseModel.lecture().W, V)
    zoh = discretize_zoh(lin, 0.1)
    dk = design.dkalman(zoh.Phi, np.eye(4), C, NoiseModel.lecture().W * 0.1, 0.01 * np.eye(2))
    return {
        "LQ": (M.lq_loop(A, B, K), W_GRID),
        "LQG Kalman–Bucy": (M.loop_through(M.lqg_compensator(A, B, C, K, kb.L), M.plant(A, B, C)),
                            W_GRID),
        "LQ sampled, T = 0.1 s": (M.lq_loop(zoh.Phi, zoh.Gamma, K, dt=0.1),
                                  M.frequency_grid(dt=0.1)),
        "LQG current estimator, T = 0.1 s": (
            M.loop_through(M.current_compensator(zoh.Phi, zoh.Gamma, C, K, dk.L, dt=0.1),
                           M.plant(zoh.Phi, zoh.Gamma, C, dt=0.1)), M.frequency_grid(dt=0.1)),
    }


@pytest.mark.parametrize("name, crossings", [
    ("LQ", True), ("LQG Kalman–Bucy", True), ("LQ sampled, T = 0.1 s", True),
    ("LQG current estimator, T = 0.1 s", False)])
def test_margins_agree_with_python_control(cartpole, name, crossings):
    """The grid-interpolated margins of :func:`loop_margins` against ``control.stability_margins``
    (exact crossings of the same loop) and, for every loop, against python-control's closed loop
    at the gain margins ± 10⁻⁴ (stable inside, unstable beyond). ``stability_margins`` goes
    through the loop's transfer function, which loses precision for discrete loops: it misses a
    crossing at the Nyquist frequency π/T, is off by about 10⁻³ at T = 0.01 s (poles crowding
    z = 1), and for the sampled LQG loop reports crossings where |L| is not 1 (|L| = 0.80 at its
    ω = 5.33 rad/s), so that loop is checked by the closed loop alone."""
    loop, omega = _loops(cartpole)[name]
    rep = M.loop_margins(loop, omega)
    assert rep.closed_loop_stable and _closed_loop_stable_with_gain(loop, 1.0)
    for k, side in ((rep.gain_margin_lower, -1), (rep.gain_margin_upper, 1)):
        if 0 < k < math.inf:          # stable just inside the margin, unstable just beyond it
            assert _closed_loop_stable_with_gain(loop, k * (1 - side * 1e-4))
            assert not _closed_loop_stable_with_gain(loop, k * (1 + side * 1e-4))
    if not crossings:
        return
    gm, pm, sm, _, _, _ = control.stability_margins(loop, returnall=True)
    gm, pm, sm = (np.atleast_1d(np.asarray(v, dtype=float)) for v in (gm, pm, sm))
    below, above = gm[gm < 1], gm[(gm > 1) & (gm < 1e6)]   # ≥ 1e6: numerical ω → ∞ artefacts
    assert rep.gain_margin_lower == pytest.approx(float(np.max(below)), rel=1e-5)
    if above.size:
        assert rep.gain_margin_upper == pytest.approx(float(np.min(above)), rel=1e-5)
    assert rep.phase_margin_deg == pytest.approx(float(np.min(np.abs(pm))), rel=1e-4)
    if sm.size:
        assert rep.min_return_difference == pytest.approx(float(np.min(sm)), rel=1e-6)
