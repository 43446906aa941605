"""Throughput of the native vector env vs Gymnasium's SyncVectorEnv at 64 envs.

Both come from ``gymnasium.make_vec("pendulum_lqg/CartPoleLQG-v0", num_envs=N)``: the registered
vector entry point (one batched ``mujoco.rollout`` per step) and ``vectorization_mode="sync"``
(N single envs in a Python loop). Both run the same episodes (same seeds, SAME_STEP autoreset)
driven by the batched LQG agent; only ``step`` calls are timed, the best of ``--repeats``.

Usage::

    uv run python experiments/vector_benchmark.py [--num-envs 64] [--steps 300] [--repeats 3]
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import pendulum_lqg
from pendulum_lqg.agent import LQGAgent


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
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    n = args.num_envs
    native = gym.make_vec(pendulum_lqg.ENV_ID, num_envs=n)
    sync = gym.make_vec(pendulum_lqg.ENV_ID, num_envs=n, vectorization_mode="sync",
                        vector_kwargs={"autoreset_mode": gym.vector.AutoresetMode.SAME_STEP})
    k = native.unwrapped.frame_skip
    rates = {}
    for name, envs in (("native", native), ("sync", sync)):
        # the sync env's sub-envs are plain single envs: the agent acts on the stacked batch
        agent = LQGAgent(native)
        time_steps(envs, agent, 20, seed=0)                     # warm-up
        best = min(time_steps(envs, agent, args.steps, seed=r) for r in range(args.repeats))
        rates[name] = n * args.steps / best
        print(f"{name:>7}: {rates[name]:12,.0f} env steps/s ({rates[name] * k:14,.0f} physics "
              f"steps/s) with {n} envs")
    print(f"  ratio: {rates['native'] / rates['sync']:.1f}× (native / sync)")
    native.close()
    sync.close()


if __name__ == "__main__":
    main()
