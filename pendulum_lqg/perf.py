"""Throughput of the closed loop against raw ``mujoco.rollout``, measured in one run.

* **raw**: one open-loop ``Rollout.rollout`` call over the whole horizon (zero force, θ₀ = 0.1),
  same model, same batch size and thread count — the ceiling for any closed loop on this model;
* **closed loop**: :func:`~pendulum_lqg.sim.run_episodes` with DLQR + steady-state Kalman under the
  lecture noise (policy, noise, saturation, failure detection and metrics included);
* **single-episode path**: the plain ``mj_step`` backend, one episode at a time;
* **memory** (optional): peak traced allocations of 1000-episode runs of 2 s and 10 s — streamed
  metrics mean the peak must not grow with the episode length.

Raw and closed-loop runs alternate ``repeats`` times and the medians are compared, so a slow spell of
the machine affects both sides.
"""

from __future__ import annotations

import statistics
import time
import tracemalloc
from collections.abc import Callable

import mujoco
import numpy as np
from mujoco import rollout as mj_rollout

from pendulum_lqg.plant import load_plant
from pendulum_lqg.policy import DesignSpec, design_policy
from pendulum_lqg.sim import Scenario, _cpu_count, run_episodes


def raw_rollout_rate(plant: object, episodes: int, nstep: int, nthread: int, *,
                     calls: int = 1, chunk_size: int | None = None) -> float:
    """Physics steps per second of ``calls`` open-loop rollouts of ``episodes × nstep`` steps."""
    m = plant.model  # type: ignore[attr-defined]
    nstate = mujoco.mj_stateSize(m, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    init = np.zeros((episodes, nstate))
    init[:, plant.state_columns()[1]] = 0.1  # type: ignore[attr-defined]
    ctrl = np.zeros((episodes, nstep, m.nu))
    datas = [mujoco.MjData(m) for _ in range(max(1, nthread))]
    state = np.empty((episodes, nstep, nstate))
    sens = np.empty((episodes, nstep, m.nsensordata))
    models = [m] * episodes
    with mj_rollout.Rollout(nthread=nthread if nthread > 1 else 0) as r:
        t = time.perf_counter()
        for _ in range(calls):
            r.rollout(models, datas, init, ctrl, skip_checks=True, nstep=nstep, state=state,
                      sensordata=sens, chunk_size=chunk_size)
        return calls * episodes * nstep / (time.perf_counter() - t)


def run_perf(*, episodes: int = 1024, duration: float = 2.0, nthread: int | None = None,
             repeats: int = 5, memory: bool = False,
             log: Callable[[str], None] = lambda s: None) -> dict[str, object]:
    plant = load_plant()
    nthread = nthread if nthread is not None else min(8, _cpu_count())
    scenario = Scenario(duration=duration)
    policy = design_policy(plant, scenario.control_period, scenario.noise,
                           DesignSpec(controller="dlqr", observer="kalman"))
    k = round(scenario.control_period / plant.timestep)
    nstep = scenario.n_periods * k
    raw, closed = [], []
    run_episodes(plant, scenario.replace(duration=scenario.control_period * 5), policy,
                 seed=0, episodes=range(8), nthread=nthread)   # warm-up (imports, pools)
    for i in range(repeats):
        raw.append(raw_rollout_rate(plant, episodes, nstep, nthread))
        t = time.perf_counter()
        res = run_episodes(plant, scenario, policy, seed=i, episodes=range(episodes),
                           nthread=nthread)
        elapsed = time.perf_counter() - t
        steps = sum(round(float(r["duration"]) / plant.timestep) for r in res.rows)
        closed.append(steps / elapsed)
        log(f"repeat {i + 1}/{repeats}: raw {raw[-1]:,.0f} steps/s, closed loop "
            f"{closed[-1]:,.0f} steps/s")
    single_eps = 4
    t = time.perf_counter()
    res = run_episodes(plant, scenario, policy, seed=0, episodes=range(single_eps), backend="step")
    single = sum(round(float(r["duration"]) / plant.timestep) for r in res.rows) / (
        time.perf_counter() - t)
    raw_med, closed_med = statistics.median(raw), statistics.median(closed)
    pair_ratios = [c / r for c, r in zip(closed, raw, strict=True)]
    out: dict[str, object] = {
        "episodes": episodes, "duration_s": duration, "nthread": nthread, "repeats": repeats,
        "physics_step_s": plant.timestep, "steps_per_period": k,
        "raw_rollout_steps_per_s": raw, "closed_loop_steps_per_s": closed,
        "raw_median": raw_med, "closed_loop_median": closed_med,
        "ratio": closed_med / raw_med, "pair_ratios": pair_ratios,
        "single_episode_steps_per_s": single,
    }
    report = [
        f"pendulum-lqg perf — {episodes} episodes × {duration:g} s, h = {plant.timestep:g} s, "
        f"{k} steps per control period, {nthread} rollout threads, median of {repeats}",
        f"raw mujoco.rollout (open loop):       {raw_med:>12,.0f} physics steps/s",
        f"closed loop (DLQR + Kalman, noisy):   {closed_med:>12,.0f} physics steps/s",
        f"ratio closed / raw:                   {closed_med / raw_med:>12.3f}   (target ≥ 0.80; "
        f"pairs {min(pair_ratios):.2f}–{max(pair_ratios):.2f})",
        f"single-episode path (mj_step loop):   {single:>12,.0f} physics steps/s",
    ]
    if memory:
        peaks = {}
        for dur in (2.0, 10.0):
            tracemalloc.start()
            run_episodes(plant, scenario.replace(duration=dur), policy, seed=0,
                         episodes=range(1000), nthread=nthread)
            peaks[dur] = tracemalloc.get_traced_memory()[1] / 2**20
            tracemalloc.stop()
            log(f"memory: 1000 episodes × {dur:g} s peak {peaks[dur]:.1f} MiB")
        out["peak_mib_2s"], out["peak_mib_10s"] = peaks[2.0], peaks[10.0]
        report.append(f"peak traced memory, 1000 episodes:   {peaks[2.0]:.1f} MiB at 2 s, "
                      f"{peaks[10.0]:.1f} MiB at 10 s")
    out["report"] = report
    return out
