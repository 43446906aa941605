"""Rerun recordings: written files pass ``rerun rrd verify`` and read back with the right entities,
sample counts and values (no viewer needed)."""

from __future__ import annotations

import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from pendulum_lqg.core.runner import run_episodes
from pendulum_lqg.core.scenario import Scenario
from pendulum_lqg.core.trajectory import Trajectory
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.model.plant import STATE_NAMES
from pendulum_lqg.policies.lqg import DesignSpec, design_policy
from pendulum_lqg.record import (
    episode_prefix,
    physics_samples,
    read_column,
    read_recording,
    record_episodes,
    telling_episodes,
    verify_recording,
)

SEED = 0


@pytest.fixture(scope="module")
def scenario():
    return Scenario()


def _policy(plant, scenario, observer):
    return design_policy(plant, scenario.control_period, scenario.noise,
                         DesignSpec(controller="dlqr", observer=observer))


@pytest.fixture(scope="module")
def luenberger(plant, scenario, tmp_path_factory):
    """A failing dlqr + Luenberger episode of the lecture scenario, recorded."""
    policy = _policy(plant, scenario, "luenberger")
    res = run_episodes(plant, scenario, policy, seed=SEED, episodes=range(8), trajectory=True)
    assert res.trajectories is not None
    tr = next(t for t in res.trajectories if not t.row["success"])   # most fail; take the first
    path = tmp_path_factory.mktemp("rec") / "luenberger.rrd"
    stats = record_episodes([tr], plant=plant, scenario=scenario, policy=policy,
                            config={"seed": SEED, "observer": "luenberger"}, path=path)
    return tr, policy, path, stats


@pytest.fixture(scope="module")
def kalman(plant, scenario, tmp_path_factory):
    """A succeeding dlqr + Kalman episode (10 s: 10 000 physics, 1 000 control samples)."""
    policy = _policy(plant, scenario, "kalman")
    res = run_episodes(plant, scenario, policy, seed=SEED, episodes=[0], trajectory=True)
    assert res.trajectories is not None
    tr = res.trajectories[0]
    assert tr.row["success"]
    path = tmp_path_factory.mktemp("rec") / "kalman.rrd"
    stats = record_episodes([tr], plant=plant, scenario=scenario, policy=policy,
                            config={"seed": SEED, "observer": "kalman"}, path=path)
    return tr, policy, path, stats


def _expected_entities(pre: str, *, failed: bool) -> set[str]:
    world = f"{pre}/world"
    ents = {"/config", "/summary", f"{pre}/outcome", f"{pre}/events",
            f"{world}/floor", f"{world}/rail", f"{world}/rail_stop_left",
            f"{world}/rail_stop_right", f"{world}/track_limits",
            f"{world}/cart", f"{world}/cart/cart", f"{world}/cart/pole", f"{world}/cart/pole/pole",
            f"{world}/estimate", f"{world}/estimate/cart", f"{world}/estimate/pole",
            f"{world}/estimate/pole/pole",
            f"{pre}/control/u", f"{pre}/control/limits", f"{pre}/cost/J",
            f"{pre}/estimation/innovation/p", f"{pre}/estimation/innovation/theta"}
    for n in STATE_NAMES:
        ents |= {f"{pre}/state/{n}/true", f"{pre}/state/{n}/estimate",
                 f"{pre}/estimation/error/{n}"}
    ents |= {f"{pre}/state/p/measured", f"{pre}/state/theta/measured"}
    if failed:
        ents.add(f"{world}/failure")
    return ents


# ---- files are valid recordings ---------------------------------------------------------------
@pytest.mark.parametrize("case", ["luenberger", "kalman"])
def test_rrd_verify_accepts_the_recordings(case, request):
    _, _, path, stats = request.getfixturevalue(case)
    check = verify_recording(path)
    assert check.ok, check.output
    assert stats.path == path and stats.bytes == path.stat().st_size > 0


def test_rrd_verify_rejects_a_truncated_file(kalman, tmp_path):
    _, _, path, _ = kalman
    cut = tmp_path / "cut.rrd"
    data = path.read_bytes()
    cut.write_bytes(data[: len(data) // 2])
    check = verify_recording(cut)
    assert not check.ok and check.returncode != 0


@pytest.mark.slow
@pytest.mark.parametrize(("display", "note"), [
    (None, ("viewer: no display (DISPLAY and WAYLAND_DISPLAY are unset), so no viewer was started",)),
    # a display that is not there: the spawned viewer either never listens, or (on a loaded
    # machine) listens for a moment and dies before it takes the recording — both one line —
    # or, rarely, takes the recording before it finds no window to open (seen once in CI)
    (":99", ("viewer: no Rerun viewer listened on port 9876 within 5 s",
             "viewer: the Rerun viewer did not take the recording within 10 s")),
])
def test_spawn_without_a_reachable_viewer_never_hangs_and_writes_the_file(tmp_path, display,
                                                                          note):
    """`run --record F --spawn` on a headless machine: one line, a complete file, the summary."""
    import os

    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"  # `rerun`
    if display is not None:
        env["DISPLAY"] = display
    path = tmp_path / "spawned.rrd"
    out = subprocess.run([sys.executable, "-m", "pendulum_lqg.cli", "run", "--record", str(path),
                          "--spawn", "--episodes", "1", "--duration", "1"], env=env,
                         capture_output=True, text=True, timeout=90)
    assert out.returncode == 0, out.stderr
    ours = [line for line in out.stderr.splitlines() if line.startswith(("viewer:", "recording:"))]
    recorded = [line for line in ours if line.startswith("recording:")]
    notes = [line for line in ours if line.startswith("viewer:")]
    assert len(recorded) == 1 and recorded[0].startswith(f"recording: {path} (1 episode(s), ")
    viewer_took_it = display is not None and not notes and "streamed to the viewer" in recorded[0]
    if not viewer_took_it:
        assert ours == [notes[0], recorded[0]]
        assert notes[0].startswith(note) and notes[0].endswith(f"open the file with: rerun {path}")
    assert "success: 1/1" in out.stdout
    check = verify_recording(path)
    assert check.ok, check.output


@pytest.mark.parametrize("case", ["luenberger", "kalman"])
def test_entity_tree_blueprint_and_timeline(case, request):
    tr, _, path, stats = request.getfixturevalue(case)
    c = read_recording(path)
    assert c.application_ids == ["pendulum_lqg"]
    assert c.blueprints == 1
    assert "sim_time" in c.timelines
    pre = episode_prefix(tr.episode)
    expected = _expected_entities(pre, failed=not tr.row["success"])
    # Rerun adds its own /__properties entity (recording name, start time)
    assert set(c.entity_paths) - {"/__properties"} == expected
    assert stats.entities == len(expected)


# ---- sample counts and values read back --------------------------------------------------------
@pytest.mark.parametrize("case", ["luenberger", "kalman"])
def test_row_counts_match_the_trajectory(case, request, plant):
    tr, _, path, stats = request.getfixturevalue(case)
    c = read_recording(path)
    pre = episode_prefix(tr.episode)
    n, n_phys = tr.t.size, tr.t_physics.size
    ttf = float(tr.row["time_to_failure"])
    n_alive = n_phys if np.isnan(ttf) else int(np.sum(tr.t_physics <= ttf + 0.5 * plant.timestep))
    for name in STATE_NAMES:
        assert c.rows[f"{pre}/state/{name}/true"] == n_alive + 1          # + the initial state
        assert c.rows[f"{pre}/state/{name}/estimate"] == n
        assert c.rows[f"{pre}/estimation/error/{name}"] == n
    assert c.rows[f"{pre}/world/cart"] == c.rows[f"{pre}/world/cart/pole"] == n_alive + 1
    assert c.rows[f"{pre}/world/estimate"] == n
    assert c.rows[f"{pre}/state/p/measured"] == c.rows[f"{pre}/state/theta/measured"] == n
    assert c.rows[f"{pre}/control/u"] == n
    assert c.rows[f"{pre}/cost/J"] == n + 1
    assert c.rows[f"{pre}/control/limits"] == 2
    assert stats.rows == sum(c.rows.values()) - c.rows.get("/__properties", 0)


def test_kalman_counts_for_a_full_10s_episode(kalman):
    _, _, path, _ = kalman
    c = read_recording(path)
    assert c.rows["/episode_0000/state/theta/true"] == 10_001
    assert c.rows["/episode_0000/control/u"] == 1_000


def test_values_read_back_equal_the_trajectory(kalman, plant):
    tr, _, path, _ = kalman
    pre = episode_prefix(tr.episode)
    t, theta = read_column(path, f"{pre}/state/theta/true")
    t_ref, x_ref = physics_samples(tr, plant)
    np.testing.assert_allclose(t, t_ref, atol=1e-9)
    np.testing.assert_array_equal(theta[:, 0], x_ref[:, 1])
    np.testing.assert_array_equal(theta[1:, 0], tr.states[:, 1])
    t, y = read_column(path, f"{pre}/state/p/measured")
    np.testing.assert_allclose(t, tr.t, atol=1e-9)
    np.testing.assert_array_equal(y[:, 0], tr.y[:, 0])
    _, u = read_column(path, f"{pre}/control/u")
    np.testing.assert_array_equal(u[:, 0], tr.u)
    assert np.max(np.abs(u)) <= plant.u_max
    _, lim = read_column(path, f"{pre}/control/limits")
    np.testing.assert_array_equal(lim, [[plant.u_max, -plant.u_max]] * 2)
    t_j, J = read_column(path, f"{pre}/cost/J")
    assert J[0, 0] == 0.0 and t_j[0] == 0.0
    np.testing.assert_allclose(J[-1, 0], tr.row["cost"], rtol=1e-12)
    np.testing.assert_allclose(t_j[-1], 10.0, atol=1e-9)


def test_scene_is_animated_from_the_true_state_and_the_estimate(kalman, plant):
    tr, _, path, _ = kalman
    world = f"{episode_prefix(tr.episode)}/world"
    _, x_ref = physics_samples(tr, plant)
    _, cart = read_column(path, f"{world}/cart", "Transform3D:translation")
    np.testing.assert_allclose(cart[:, 0, :], np.c_[x_ref[:, 0], np.zeros((len(x_ref), 2))])
    _, q = read_column(path, f"{world}/cart/pole", "Transform3D:quaternion")
    half = x_ref[:, 1] / 2      # about the hinge axis +y, xyzw
    np.testing.assert_allclose(q[:, 0, :], np.c_[0 * half, np.sin(half), 0 * half, np.cos(half)],
                               atol=1e-7)
    _, q_est = read_column(path, f"{world}/estimate/pole", "Transform3D:quaternion")
    np.testing.assert_allclose(q_est[:, 0, 1], np.sin(tr.x_hat[:, 1] / 2), atol=1e-7)
    # the geometry comes from the MJCF: the cart box's half sizes
    _, box = read_column(path, f"{world}/cart/cart", "Boxes3D:half_sizes")
    np.testing.assert_allclose(box[0, 0], plant.model.geom("cart").size, rtol=1e-6)


def test_kalman_error_band_is_two_sigma_of_P(kalman):
    tr, _, path, _ = kalman
    pre = episode_prefix(tr.episode)
    for i, name in enumerate(STATE_NAMES):
        _, band = read_column(path, f"{pre}/estimation/error/{name}")
        assert band.shape == (tr.t.size, 3)
        np.testing.assert_allclose(band[:, 0], tr.x_hat[:, i] - tr.x[:, i], rtol=1e-12)
        np.testing.assert_allclose(band[:, 1], 2 * np.sqrt(tr.P[:, i, i]), rtol=1e-12)
        np.testing.assert_allclose(band[:, 2], -band[:, 1])
        assert np.all(band[:, 1] > 0)
    _, nu = read_column(path, f"{pre}/estimation/innovation/theta")
    np.testing.assert_array_equal(nu[:, 0], tr.innovation[:, 1])


def test_luenberger_error_has_no_band(luenberger):
    tr, _, path, _ = luenberger
    _, err = read_column(path, f"{episode_prefix(tr.episode)}/estimation/error/theta")
    assert err.shape == (tr.t.size, 1)
    np.testing.assert_allclose(err[:, 0], tr.x_hat[:, 1] - tr.x[:, 1], rtol=1e-12)


# ---- outcome, events and the configuration document --------------------------------------------
def test_failing_episode_shows_failure_time_and_reason(luenberger, plant):
    tr, _, path, _ = luenberger
    pre = episode_prefix(tr.episode)
    reason, ttf = tr.row["failure_reason"], float(tr.row["time_to_failure"])
    assert reason in ("track_limit", "pole_fell", "diverged") and 0 < ttf < 10
    _, doc = read_column(path, f"{pre}/outcome", "TextDocument:text")
    assert f"FAILED, {reason} at t = {ttf:.3f} s" in doc[0]
    t_ev, ev = read_column(path, f"{pre}/events", "TextLog:text")
    np.testing.assert_allclose(t_ev, [ttf], atol=1e-9)
    assert ev[0] == f"episode {tr.episode} failed: {reason} at t = {ttf:.3f} s"
    t_f, label = read_column(path, f"{pre}/world/failure", "Points3D:labels")
    np.testing.assert_allclose(t_f, [ttf], atol=1e-9)
    assert label[0] == f"{reason} @ {ttf:.3f} s"
    # the true state is cut at the failure: the last logged state breaks the failure rule
    _, p = read_column(path, f"{pre}/state/p/true")
    _, th = read_column(path, f"{pre}/state/theta/true")
    last = (abs(p[-1, 0]) >= plant.track_limit, abs(th[-1, 0]) > Scenario().theta_max)
    assert any(last) or reason == "diverged"


def test_succeeding_episode_shows_success(kalman):
    tr, _, path, _ = kalman
    pre = episode_prefix(tr.episode)
    _, doc = read_column(path, f"{pre}/outcome", "TextDocument:text")
    assert doc[0].startswith(f"# Episode {tr.episode}: success (cost J = {tr.row['cost']:.4g})")
    t_ev, ev = read_column(path, f"{pre}/events", "TextLog:text")
    assert "succeeded" in ev[0]
    np.testing.assert_allclose(t_ev, [10.0], atol=1e-9)


def _code_block_after(text: str, heading: str) -> str:
    return text.split(heading, 1)[1].split("```", 2)[1]


def _numbers(block: str) -> np.ndarray:
    return np.array([float(v) for v in re.findall(r"[-+]?\d+\.\d+(?:e[-+]?\d+)?", block)])


def test_config_document_has_seed_gains_and_poles(kalman):
    _, policy, path, _ = kalman
    _, doc = read_column(path, "/config", "TextDocument:text")
    text = doc[0]
    assert "**seed**: `0`" in text
    assert "dlqr+kalman" in text
    K = np.asarray(policy.info["K"]).ravel()
    np.testing.assert_allclose(_numbers(_code_block_after(text, "controller gain K")), K, rtol=1e-5)
    L = np.asarray(policy.info["L"]).ravel()
    np.testing.assert_allclose(_numbers(_code_block_after(text, "observer gain L")), L, rtol=1e-5)
    poles = np.asarray(policy.info["observer_poles"])
    block = _code_block_after(text, "observer poles (z)")
    np.testing.assert_allclose(_numbers(block), poles.real, rtol=1e-5)
    assert "controller poles" in text
    assert '| observer | `"kalman"` |' in text               # the configuration, verbatim
    assert "| noise.measurement_variance | `[0.01, 0.01]` |" in text
    assert "track_limit" in text                             # plant parameters from the MJCF


# ---- several episodes in one recording ---------------------------------------------------------
def test_several_episodes_are_distinguishable(plant, tmp_path):
    scenario = Scenario(duration=1.0)
    policy = _policy(plant, scenario, "kalman")
    res = run_episodes(plant, scenario, policy, seed=3, episodes=[2, 5, 11], trajectory=True)
    assert res.trajectories is not None
    labels = {"best": 5, "worst": 11, "median": 5}
    path = tmp_path / "three.rrd"
    stats = record_episodes(res.trajectories, plant=plant, scenario=scenario, policy=policy,
                            config={"seed": 3}, path=path, labels=labels)
    assert verify_recording(path).ok
    c = read_recording(path)
    assert stats.episodes == 3
    for tr in res.trajectories:
        pre = episode_prefix(tr.episode)
        assert c.rows[f"{pre}/control/u"] == tr.t.size == 100
        _, theta = read_column(path, f"{pre}/state/theta/true")
        np.testing.assert_array_equal(theta[1:, 0], tr.states[:, 1])   # its own episode's data
    _, summary = read_column(path, "/summary", "TextDocument:text")
    assert "| 5 | best, median |" in summary[0] and "| 11 | worst |" in summary[0]
    assert "| 2 |  |" in summary[0]


def test_true_state_policy_has_no_estimator_entities(plant, tmp_path):
    scenario = Scenario(duration=0.5)
    policy = _policy(plant, scenario, "none")
    res = run_episodes(plant, scenario, policy, seed=0, episodes=[0], trajectory=True)
    path = tmp_path / "none.rrd"
    record_episodes(res.trajectories, plant=plant, scenario=scenario, policy=policy, config={},
                    path=path)
    ents = read_recording(path).entity_paths
    assert not [e for e in ents if "/estimation/" in e or "/estimate" in e]
    assert "/episode_0000/state/theta/measured" in ents


def test_bad_arguments(plant, scenario, kalman, tmp_path):
    tr, policy, _, _ = kalman
    with pytest.raises(ConfigError, match="path"):
        record_episodes([tr], plant=plant, scenario=scenario, policy=policy, config={})
    with pytest.raises(ConfigError, match="episode 0 appears more than once"):
        record_episodes([tr, tr], plant=plant, scenario=scenario, policy=policy, config={},
                        path=tmp_path / "x.rrd")
    with pytest.raises(ConfigError, match="at least one"):
        record_episodes([], plant=plant, scenario=scenario, policy=policy, config={},
                        path=tmp_path / "x.rrd")
    with pytest.raises(ConfigError, match=r"^record: .* is a folder; expected a file path"):
        record_episodes([tr], plant=plant, scenario=scenario, policy=policy, config={},
                        path=tmp_path)
    with pytest.raises(ConfigError, match=r"^record: expected a file path .*got ''$"):
        record_episodes([tr], plant=plant, scenario=scenario, policy=policy, config={}, path="")


# ---- speed and cost when off ------------------------------------------------------------------
def test_recording_a_10s_episode_takes_well_under_a_second(kalman, plant, scenario, tmp_path):
    tr, policy, _, _ = kalman
    assert isinstance(tr, Trajectory) and tr.t_physics.size == 10_000
    best = np.inf
    for i in range(3):
        t0 = time.perf_counter()
        stats = record_episodes([tr], plant=plant, scenario=scenario, policy=policy,
                                config={}, path=tmp_path / f"t{i}.rrd")
        best = min(best, time.perf_counter() - t0)
    print(f"\nrecording one 10 s episode (10 000 physics + 1 000 control samples, {stats.rows} "
          f"rows, {stats.bytes / 1e6:.2f} MB): {best:.3f} s")
    assert best < 0.5, f"recording took {best:.3f} s"


def test_the_package_never_imports_rerun_unless_recording():
    code = (
        "import sys, pkgutil, importlib, pendulum_lqg\n"
        "for m in pkgutil.walk_packages(pendulum_lqg.__path__, 'pendulum_lqg.'):\n"
        "    importlib.import_module(m.name)\n"
        "from pendulum_lqg.model.plant import load_plant\n"
        "from pendulum_lqg.policies.lqg import design_policy\n"
        "from pendulum_lqg import Scenario, run_episodes\n"
        "p = load_plant(); s = Scenario(duration=0.2)\n"
        "run_episodes(p, s, design_policy(p, 0.01, s.noise), seed=0, episodes=[0])\n"
        "from pendulum_lqg.record import telling_episodes\n"
        "telling_episodes([{'episode': 0, 'success': True, 'cost': 1.0}])\n"
        "print('rerun' in sys.modules)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         cwd=Path(__file__).resolve().parents[2])
    assert out.stdout.strip() == "False"


# ---- telling episodes -------------------------------------------------------------------------
def _rows(spec):
    return [{"episode": e, "success": ok, "cost": c} for e, ok, c in spec]


def test_telling_episodes_picks_best_median_worst_and_first_failure():
    rows = _rows([(0, True, 5.0), (1, False, 0.1), (2, True, 1.0), (3, True, 9.0),
                  (4, False, 50.0), (5, True, 3.0), (6, True, 7.0)])
    assert telling_episodes(rows) == {"best": 2, "median": 0, "worst": 3, "first_failure": 1}


def test_telling_episodes_ignores_failures_for_cost_and_handles_edge_cases():
    # an even count takes the lower median; a failure's tiny cost never makes it "best"
    rows = _rows([(7, True, 4.0), (3, False, 0.0), (9, True, 2.0), (8, True, 3.0), (1, True, 1.0)])
    assert telling_episodes(rows) == {"best": 1, "median": 9, "worst": 7, "first_failure": 3}
    assert telling_episodes(_rows([(4, False, 1.0), (2, False, 2.0)])) == {"first_failure": 2}
    assert telling_episodes(_rows([(0, True, 1.0)])) == {"best": 0, "median": 0, "worst": 0}
    assert telling_episodes([]) == {}
    with pytest.raises(ConfigError, match="'cost'"):
        telling_episodes([{"episode": 0, "success": True}])
