"""Throughput of the native vector env vs Gymnasium's SyncVectorEnv at 64 envs.

Both come from ``gymnasium.make_vec("pendulum_lqg/CartPoleLQG-v0", num_envs=N)``: the registered
vector entry point (one batched ``mujoco.rollout`` per step) and ``vectorization_mode="sync"``
(N single envs in a Python loop). Both run the same episodes (same seeds, NEXT_STEP autoreset)
driven by the batched LQG agent; only ``step`` calls are timed.

The physics alone bounds what any vector env can reach: the third line times bare
``mujoco.rollout`` calls of the same batch, one per env step (N rows × k physics steps, the native
env's threads and chunking, no state or sensor outputs requested, no Python around them) — a vector
env must return to Python once per control period. ``native / bare physics`` is the share of that
ceiling the native env reaches; ``physics / sync`` is the ceiling of the native/sync ratio on this
machine (with ``c`` cores it grows about like ``c``: the sync env uses one). The three take turns,
one timed run each per round; figures are medians over the rounds, ratios medians of the per-round
ratios.

Usage::

    uv run python experiments/vector_benchmark.py [--num-envs 64] [--steps 300] [--repeats 5]
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import pendulum_lqg
from pendulum_lqg.agent import LQGAgent
from pendulum_lqg.perf import raw_batch_rate, raw_rollout_rate
from pendulum_lqg.sim import rollout_chunk


def time_steps(envs: gym.vector.VectorEnv, agent: LQGAgent, steps: int, seed: int) -> float:
    """Seconds spent inside ``envs.step`` over ``steps`` steps of the whole batch."""
    obs, _ = envs.reset(seed=seed)
    agent.reset()
    clock = time.perf_counter
    spent = 0.0
    for _ in range(steps):
        action = agent.act(obs)
        t0 = clock()
        obs, _, terminated, truncated, _ = envs.step(action)
        spent += clock() - t0
        agent.reset(np.nonzero(terminated | truncated)[0])
    return spent


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--num-envs", type=int, default=64)
    ap.add_argument("--steps", type=int, default=300, help="vector steps per timed run")
    ap.add_argument("--repeats", type=int, default=5, help="rounds (one timed run each)")
    args = ap.parse_args()
    n = args.num_envs
    native = gym.make_vec(pendulum_lqg.ENV_ID, num_envs=n)
    sync = gym.make_vec(pendulum_lqg.ENV_ID, num_envs=n, vectorization_mode="sync")
    k, nthread = native.unwrapped.frame_skip, native.unwrapped.nthread
    # the sync env's sub-envs are plain single envs: the agent acts on the stacked batch
    agent = LQGAgent(native)
    contenders = {"native": native, "sync": sync}
    for envs in contenders.values():
        time_steps(envs, agent, 20, seed=0)                     # warm-up
    print(f"{n} envs, {args.steps} vector steps per run, {args.repeats} rounds, seeds "
          f"0..{args.repeats - 1}, {k} physics steps per env step, {nthread} rollout threads")
    rates: dict[str, list[float]] = {"native": [], "sync": [], "rollout": [], "batch": [],
                                     "physics": []}
    for r in range(args.repeats):
        for name, envs in contenders.items():
            rates[name].append(n * args.steps / time_steps(envs, agent, args.steps, seed=r))
        plant = native.unwrapped.plant
        rates["rollout"].append(raw_rollout_rate(plant, n, k, nthread, calls=args.steps,
                                                 outputs=False,
                                                 chunk_size=rollout_chunk(n, nthread, k)) / k)
        rates["batch"].append(raw_batch_rate(plant, n, k, nthread, calls=args.steps) / k)
        rates["physics"].append(max(rates["rollout"][-1], rates["batch"][-1]))
        log = {name: f"{v[-1]:,.0f}" for name, v in rates.items()}
        print(f"round {r + 1}/{args.repeats}: env steps/s {log}")
    med = {name: float(np.median(v)) for name, v in rates.items()}
    for name, label in (("native", "native vector env"), ("sync", "SyncVectorEnv"),
                        ("rollout", "bare mujoco.rollout"), ("batch", "bare mujoco.batch"),
                        ("physics", "bare physics (faster)")):
        print(f"{label:>28}: {med[name]:12,.0f} env steps/s ({med[name] * k:14,.0f} physics "
              f"steps/s; runs {min(rates[name]):,.0f}–{max(rates[name]):,.0f})")
    to_physics = [a / b for a, b in zip(rates["native"], rates["physics"], strict=True)]
    to_sync = [a / b for a, b in zip(rates["native"], rates["sync"], strict=True)]
    ceiling = [a / b for a, b in zip(rates["physics"], rates["sync"], strict=True)]
    print(f"{'native / bare physics':>28}: {np.median(to_physics):.3f}   (median of the "
          f"{args.repeats} rounds, {min(to_physics):.3f}–{max(to_physics):.3f}; target ≥ 0.90)")
    print(f"{'native / sync':>28}: {np.median(to_sync):.1f}×   (ceiling bare physics / sync "
          f"{np.median(ceiling):.1f}×: no vector env can exceed it here)")
    native.close()
    sync.close()


if __name__ == "__main__":
    main()
