"""Throughput of the closed loop against bare MuJoCo physics, measured in one run.

* **bare physics** (the baseline): the faster of two open-loop calls over the whole horizon
  (zero force, θ₀ = 0.1), same model, batch size and thread count, **no trajectory outputs
  requested** — one ``mujoco.rollout`` ``Rollout.rollout`` call, and one ``mujoco.batch``
  ``Batch.step`` call (MuJoCo 4's batch, which the simulation core steps) — the ceiling for any
  closed loop on this model. "The faster" is the call with the higher median over the repeats
  (:func:`faster_series`), and each pair's ratio uses that call's run of the pair: the larger
  of the two runs within each pair would bias the baseline upwards by the machine's noise, the
  two calls being about equally fast;
* **with outputs** (for reference): the rollout call also writing the full physics state and
  sensor data of every step;
* **closed loop**: :func:`~pendulum_lqg.core.runner.run_episodes` with DLQR + steady-state Kalman under the
  lecture noise (policy, noise, saturation, failure detection and metrics included);
* **shard idle**: the closed loop runs as fixed shards of episodes, one per thread
  (:func:`~pendulum_lqg.core.runner.shard_count`); the share of their thread time spent waiting for the
  last one to end (:func:`shard_idle`) is lost to the ratio — where ``Batch.step`` and the rollout
  hand out simulations to whichever thread is free;
* **single-episode path**: the plain ``mj_step`` backend, one episode at a time;
* **memory** (optional): peak traced allocations of 1000-episode runs of 2 s and 10 s — streamed
  metrics mean the peak must not grow with the episode length.

Bare physics and the closed loop alternate ``repeats`` times; the ratio is the median of the
per-pair ratios, so a slow spell of the machine affects both sides of a pair. Each timed call
starts after a full garbage collection (``gc.collect()``), as ``timeit`` disables collection: a
collection of the whole heap, which the objects of earlier calls would otherwise trigger inside
whichever call came next, would be charged to that call (docs/performance.md, "Settings that rest
on a measurement"); each call still pays for the collections its own allocations cause.
"""

from __future__ import annotations

import gc
import statistics
import time
import tracemalloc
from collections.abc import Callable
from typing import Any

import mujoco
import numpy as np
from mujoco import rollout as mj_rollout

from pendulum_lqg.core.physics import thread_count
from pendulum_lqg.core.runner import run_episodes, shard_count
from pendulum_lqg.core.scenario import Scenario
from pendulum_lqg.model.interface import steps_per_period
from pendulum_lqg.model.plant import load_plant
from pendulum_lqg.policies.lqg import DesignSpec, design_policy

#: Fewest physics steps a rollout chunk (one thread-pool task) should hold: each chunk costs a
#: hand-off to a thread, and below this the hand-offs cost more than the load balance of more
#: chunks wins (docs/performance.md, "Settings that rest on a measurement").
MIN_CHUNK_STEPS = 300


def rollout_chunk(n: int, nthread: int, nstep: int) -> int | None:
    """``chunk_size`` for the ``mujoco.rollout`` baselines (the core steps ``mujoco.batch``,
    which schedules its own threads): a ``Rollout`` of ``n`` rows of ``nstep`` physics steps on
    ``nthread`` threads: about ten chunks per thread (``mujoco.rollout``'s default, for load balance), but no
    chunk under :data:`MIN_CHUNK_STEPS` steps, and a whole multiple of the thread count so no
    thread is left with an extra chunk while the others wait (64 rows on 2 threads: 2 × 32, not
    30 + 30 + 4). A batch too small to split runs as one chunk."""
    if nthread <= 1:
        return None
    most = (n * nstep) // MIN_CHUNK_STEPS
    if most < nthread:
        return max(n, 1)
    chunks = min(10 * nthread, most)
    chunks -= chunks % nthread
    return -(-n // chunks)


def raw_rollout_rate(plant: object, episodes: int, nstep: int, nthread: int, *,
                     calls: int = 1, chunk_size: int | None = None, outputs: bool = False,
                     ) -> float:
    """Physics steps per second of ``calls`` open-loop rollouts of ``episodes × nstep`` steps.

    ``outputs=False`` is bare physics (no state or sensor trajectories requested); ``True`` also
    writes the full physics state and the sensor data of every step.
    """
    m = plant.model  # type: ignore[attr-defined]
    nstate = mujoco.mj_stateSize(m, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    init = np.zeros((episodes, nstate))
    init[:, plant.state_columns()[1]] = 0.1  # type: ignore[attr-defined]
    ctrl = np.zeros((episodes, nstep, m.nu))
    datas = [mujoco.MjData(m) for _ in range(max(1, nthread))]
    state = np.empty((episodes, nstep, nstate)) if outputs else None
    sens = np.empty((episodes, nstep, m.nsensordata)) if outputs else None
    models = [m] * episodes
    with mj_rollout.Rollout(nthread=nthread if nthread > 1 else 0) as r:
        t = time.perf_counter()
        for _ in range(calls):
            r.rollout(models, datas, init, ctrl, skip_checks=True, nstep=nstep, state=state,
                      sensordata=sens, chunk_size=chunk_size)
        return calls * episodes * nstep / (time.perf_counter() - t)


def raw_batch_rate(plant: object, episodes: int, nstep: int, nthread: int, *,
                   calls: int = 1, gap: float = 0.0) -> float:
    """Physics steps per second of ``calls`` calls of ``mujoco.batch.Batch.step(nstep)`` on
    ``episodes`` simulations (θ₀ = 0.1, the force written before each call, nothing recorded):
    bare physics that returns to Python every ``nstep`` steps, as a vector env must once per
    control period (the same MuJoCo batch the simulation core steps).

    ``gap`` > 0: the calling thread spins that many seconds of Python before each call (not
    timed), as an env and its agent run Python between steps. The batch's other threads wait
    for the next call spinning only briefly, then sleep, and a sleeping thread wakes late: the
    physics of a step then takes longer than back to back, with no other work in the way."""
    from mujoco.batch import Batch

    m = plant.model  # type: ignore[attr-defined]
    batch = Batch(m, episodes, nthread=max(1, nthread))
    batch.qpos[:, plant.qpos_index[1]] = 0.1  # type: ignore[attr-defined]
    ctrl = batch.ctrl
    clock = time.perf_counter
    if gap <= 0.0:
        t = clock()
        for _ in range(calls):
            ctrl[:] = 0.0
            batch.step(nstep=nstep)
        return calls * episodes * nstep / (clock() - t)
    spent = 0.0
    for _ in range(calls):
        until = clock() + gap
        while clock() < until:
            pass
        t = clock()
        ctrl[:] = 0.0
        batch.step(nstep=nstep)
        spent += clock() - t
    return calls * episodes * nstep / spent


def shard_idle(shard_seconds: list[tuple[float, float]]) -> float:
    """The share of the shards' thread time spent idle, waiting for the last shard to end:
    ``Σ (end_last − end_i) / (shards · end_last)`` over ``(start, end)`` times since the run
    started (0 for one shard). Shards are fixed sets of episodes, so a thread that finishes its
    shard first (a faster core, a shard started earlier) has nothing left to run."""
    if len(shard_seconds) < 2:
        return 0.0
    last = max(end for _, end in shard_seconds)
    return sum(last - end for _, end in shard_seconds) / (len(shard_seconds) * last)


def faster_series(series: dict[str, list[float]]) -> str:
    """The name of the series (rates, higher is faster) with the highest median: the baseline
    whose runs, pair by pair, the contender is compared with."""
    return max(series, key=lambda name: statistics.median(series[name]))


def _count(name: str, value: object) -> int:
    """``value`` as a positive integer; else a one-line error naming ``name``."""
    from pendulum_lqg.errors import ConfigError

    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
        raise ConfigError(f"{name}: expected a positive integer, got {value!r}")
    return int(value)


def run_perf(*, episodes: int = 1024, duration: float = 2.0, nthread: int | None = None,
             repeats: int = 5, memory: bool = False,
             log: Callable[[str], None] = lambda s: None) -> dict[str, Any]:
    """``pendulum-lqg perf``: the measurements of the module docstring, as a dict of the series
    and their medians and ratios, with ``"report"`` the lines the command prints. ``log`` gets a
    line per repeat."""
    scenario, plant, nstep = _checked_batch(episodes, duration, repeats)
    k = steps_per_period(plant, scenario.control_period)
    nthread = thread_count(nthread)
    policy = design_policy(plant, scenario.control_period, scenario.noise,
                           DesignSpec(controller="dlqr", observer="kalman"))
    series = _alternate(plant, scenario, policy, episodes=episodes, nstep=nstep, nthread=nthread,
                        repeats=repeats, log=log)
    bare = {"rollout": series["rollout"], "batch": series["batch"]}
    baseline = faster_series(bare)
    raw, closed, with_outputs = bare[baseline], series["closed"], series["with_outputs"]
    pair_ratios = [c / r for c, r in zip(closed, raw, strict=True)]
    out: dict[str, Any] = {
        "episodes": episodes, "duration_s": duration, "nthread": nthread, "repeats": repeats,
        "physics_step_s": plant.timestep, "steps_per_period": k,
        "shards": shard_count(episodes, nthread, "rollout", policy),
        "raw_steps_per_s": raw, "bare_baseline": baseline,
        "bare_rollout_steps_per_s": series["rollout"], "bare_batch_steps_per_s": series["batch"],
        "closed_loop_steps_per_s": closed, "pair_ratios": pair_ratios,
        "ratio": statistics.median(pair_ratios), "shard_idle_fraction": series["idle"],
        "raw_with_outputs_steps_per_s": with_outputs,
        "ratio_vs_outputs": statistics.median(c / r for c, r in
                                              zip(closed, with_outputs, strict=True)),
        "single_episode_steps_per_s": _single_episode_rate(plant, scenario, policy),
    }
    report = _report_lines(out)
    if memory:
        out["peak_mib_2s"], out["peak_mib_10s"] = _peak_memory(plant, scenario, policy, nthread,
                                                               log)
        report.append(f"peak traced memory, 1000 episodes:     {out['peak_mib_2s']:.1f} MiB at "
                      f"2 s, {out['peak_mib_10s']:.1f} MiB at 10 s")
    out["report"] = report
    return out


def _checked_batch(episodes: int, duration: float, repeats: int) -> tuple[Scenario, Any, int]:
    """The scenario, the plant and the physics steps per episode of the timed batch, its sizes
    checked first: nothing is allocated or timed before they are known to fit."""
    from pendulum_lqg.util.limits import (
        MAX_PERF_REPEATS,
        MAX_PERF_STEPS,
        MAX_RUN_EPISODES,
        check_at_most,
    )

    check_at_most("repeats", _count("repeats", repeats), MAX_PERF_REPEATS,
                  "alternating pairs, each running the whole batch three times")
    check_at_most("episodes", _count("episodes", episodes), MAX_RUN_EPISODES,
                  "episodes of the one batch timed")
    scenario = Scenario(duration=duration)
    plant = load_plant()
    nstep = scenario.n_periods * steps_per_period(plant, scenario.control_period)
    check_at_most("episodes × duration", episodes * nstep, MAX_PERF_STEPS,
                  f"physics steps of the batch, {episodes:,} episodes × {nstep:,} steps of "
                  f"{plant.timestep:g} s: the bare-physics baselines hold a force for each")
    return scenario, plant, nstep


def _alternate(plant: Any, scenario: Scenario, policy: Any, *, episodes: int, nstep: int,
               nthread: int, repeats: int, log: Callable[[str], None]) -> dict[str, list[float]]:
    """``repeats`` rounds of bare physics (rollout and batch), the closed loop and physics with
    outputs, each call after a full collection: the series of rates (physics steps/s) and the
    closed loop's shard idle fractions."""
    series: dict[str, list[float]] = {"rollout": [], "batch": [], "closed": [], "idle": [],
                                      "with_outputs": []}
    run_episodes(plant, scenario.replace(duration=scenario.control_period * 5), policy,
                 seed=0, episodes=range(8), nthread=nthread)   # warm-up (imports, pools)
    for i in range(repeats):
        gc.collect()
        series["rollout"].append(raw_rollout_rate(plant, episodes, nstep, nthread))
        gc.collect()
        series["batch"].append(raw_batch_rate(plant, episodes, nstep, nthread))
        gc.collect()
        t = time.perf_counter()
        res = run_episodes(plant, scenario, policy, seed=i, episodes=range(episodes),
                           nthread=nthread)
        elapsed = time.perf_counter() - t
        series["closed"].append(_physics_steps(plant, res.rows) / elapsed)
        series["idle"].append(shard_idle(res.shard_seconds))
        del res
        gc.collect()
        series["with_outputs"].append(raw_rollout_rate(plant, episodes, nstep, nthread,
                                                       outputs=True))
        log(f"repeat {i + 1}/{repeats}: bare physics: rollout {series['rollout'][-1]:,.0f}, batch "
            f"{series['batch'][-1]:,.0f} steps/s; closed loop {series['closed'][-1]:,.0f} "
            f"steps/s; physics with outputs {series['with_outputs'][-1]:,.0f} steps/s")
    return series


def _physics_steps(plant: Any, rows: list[dict[str, Any]]) -> int:
    """Physics steps the episodes of ``rows`` ran (a failed episode stops early)."""
    return sum(round(float(r["duration"]) / plant.timestep) for r in rows)


def _single_episode_rate(plant: Any, scenario: Scenario, policy: Any, episodes: int = 4) -> float:
    """Physics steps/s of the plain ``mj_step`` backend, one episode at a time."""
    t = time.perf_counter()
    res = run_episodes(plant, scenario, policy, seed=0, episodes=range(episodes), backend="step")
    return _physics_steps(plant, res.rows) / (time.perf_counter() - t)


def _peak_memory(plant: Any, scenario: Scenario, policy: Any, nthread: int,
                 log: Callable[[str], None]) -> tuple[float, float]:
    """Peak traced allocations (MiB) of 1000-episode runs of 2 s and of 10 s."""
    peaks = []
    for dur in (2.0, 10.0):
        tracemalloc.start()
        run_episodes(plant, scenario.replace(duration=dur), policy, seed=0,
                     episodes=range(1000), nthread=nthread)
        peaks.append(tracemalloc.get_traced_memory()[1] / 2**20)
        tracemalloc.stop()
        log(f"memory: 1000 episodes × {dur:g} s peak {peaks[-1]:.1f} MiB")
    return peaks[0], peaks[1]


def _report_lines(out: dict[str, Any]) -> list[str]:
    """The lines ``pendulum-lqg perf`` prints for the measurements ``out``."""
    median = statistics.median
    baseline, idle, pairs = out["bare_baseline"], out["shard_idle_fraction"], out["pair_ratios"]
    return [
        f"pendulum-lqg perf — {out['episodes']} episodes × {out['duration_s']:g} s, "
        f"h = {out['physics_step_s']:g} s, {out['steps_per_period']} steps per control period, "
        f"{out['nthread']} threads, {out['repeats']} alternating pairs",
        f"bare physics ({baseline}, the faster):{' ' * (12 - len(baseline))}"
        f"{median(out['raw_steps_per_s']):>12,.0f} physics steps/s (median)",
        f"  one mujoco.rollout call, no outputs:  {median(out['bare_rollout_steps_per_s']):>12,.0f}",
        f"  one mujoco.batch Batch.step call:     {median(out['bare_batch_steps_per_s']):>12,.0f}",
        f"closed loop (DLQR + Kalman, noisy):     {median(out['closed_loop_steps_per_s']):>12,.0f} "
        "physics steps/s (median)",
        f"ratio closed / bare physics:            {out['ratio']:>12.3f}   (median of the pair "
        f"ratios, pairs {min(pairs):.3f}–{max(pairs):.3f}; target ≥ 0.90)",
        f"  vs physics writing state + sensors:   {out['ratio_vs_outputs']:>12.3f}   "
        f"({median(out['raw_with_outputs_steps_per_s']):,.0f} steps/s)",
        f"shards idle while the last one runs:    {100 * median(idle):>11.1f} %   "
        f"(median; {100 * min(idle):.1f}–{100 * max(idle):.1f} %; "
        f"{out['shards']} shards, fixed at the start)",
        f"single-episode path (mj_step loop):     {out['single_episode_steps_per_s']:>12,.0f} "
        "physics steps/s",
    ]
