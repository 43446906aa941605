"""Where the closed loop's time goes, on one thread: CPU seconds of three runs side by side.

* **bare physics**: one ``mujoco.batch`` ``Batch.step`` call over the whole horizon (no outputs);
* **per-period physics**: the same steps as the core asks for them — one ``Batch.rollout`` call
  per control period, recording ``[time, qpos, qvel]`` after every physics step, and nothing else;
* **closed loop**: :func:`pendulum_lqg.core.runner.run_episodes` with DLQR + Kalman under the lecture noise
  (``nthread=1``: one shard, so nothing overlaps).

The three alternate ``--rounds`` times; CPU time (``time.process_time``) is used because on a
shared VM it is less disturbed by other tenants than wall time. ``per-period / bare`` is what
returning to Python once per period costs the physics; ``closed / per-period`` is the share of the
loop's own numpy (noise, policy, failure rule, cost, metrics) on top of it.

Usage::

    uv run python benchmarks/loop_profile.py [--episodes 512] [--duration 2] [--rounds 5]
"""

from __future__ import annotations

import statistics
import time

import mujoco
import numpy as np
from mujoco.batch import Batch

from pendulum_lqg.core.runner import run_episodes
from pendulum_lqg.core.scenario import Scenario
from pendulum_lqg.model.interface import steps_per_period
from pendulum_lqg.model.plant import load_plant
from pendulum_lqg.policies.lqg import DesignSpec, design_policy
from pendulum_lqg.util.limits import MAX_BATCH_EPISODES
from pendulum_lqg.util.scripts import ScriptParser, int_in, number, run_script

#: Ceiling of the alternating rounds.
MAX_ROUNDS = 100


def main(argv: list[str] | None = None) -> None:
    ap = ScriptParser(description=__doc__.splitlines()[0])
    ap.add_argument("--episodes", type=int_in(1, MAX_BATCH_EPISODES), default=512)
    ap.add_argument("--duration", type=number(positive=True), default=2.0,
                    help="seconds per episode (the scenario's ceilings apply)")
    ap.add_argument("--rounds", type=int_in(1, MAX_ROUNDS), default=5)
    args = ap.parse_args(argv)
    plant = load_plant()
    m, n = plant.model, args.episodes
    sc = Scenario(duration=args.duration)
    k = steps_per_period(plant, sc.control_period)
    periods = sc.n_periods
    policy = design_policy(plant, sc.control_period, sc.noise, DesignSpec("dlqr", "kalman"))
    st = mujoco.mjtState
    spec = int(st.mjSTATE_TIME | st.mjSTATE_QPOS | st.mjSTATE_QVEL)

    def bare() -> None:
        batch = Batch(m, n, nthread=1)
        batch.qpos[:, 1] = 0.1
        batch.step(nstep=periods * k)

    def per_period() -> None:
        batch = Batch(m, n, nthread=1)
        batch.qpos[:, 1] = 0.1
        out = {spec: np.empty((n, k, 5))}
        for _ in range(periods):
            batch.rollout(k, None, record=(spec,), out=out)

    def closed() -> None:
        run_episodes(plant, sc, policy, seed=0, episodes=range(n), nthread=1)

    runs = {"bare physics": bare, "per-period physics": per_period, "closed loop": closed}
    closed()                                                  # warm-up
    cpu: dict[str, list[float]] = {name: [] for name in runs}
    for r in range(args.rounds):
        for name, run in runs.items():
            t = time.process_time()
            run()
            cpu[name].append(time.process_time() - t)
        print(f"round {r + 1}/{args.rounds}: " + ", ".join(
            f"{name} {v[-1]:.3f} s" for name, v in cpu.items()))
    print(f"{n} episodes × {args.duration:g} s, {k} physics steps per period, 1 thread, "
          f"{args.rounds} alternating rounds (CPU seconds, medians)")
    for name, v in cpu.items():
        print(f"{name:>20}: {statistics.median(v):7.3f} s  ({n * periods * k / statistics.median(v):,.0f} "
              "physics steps per CPU second)")
    for a, b in (("per-period physics", "bare physics"), ("closed loop", "per-period physics"),
                 ("closed loop", "bare physics")):
        ratios = [x / y for x, y in zip(cpu[a], cpu[b], strict=True)]
        print(f"{a + ' / ' + b:>40}: {statistics.median(ratios):.3f}  "
              f"(rounds {min(ratios):.3f}–{max(ratios):.3f})")


if __name__ == "__main__":
    run_script(main)
