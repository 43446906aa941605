"""Throughput of the native vector env vs Gymnasium's SyncVectorEnv at 64 envs.

Both come from ``gymnasium.make_vec("pendulum_lqg/CartPoleLQG-v0", num_envs=N)``: the registered
vector entry point (one batched ``mujoco.batch`` call per step, the simulation core) and
``vectorization_mode="sync"`` (N single envs in a Python loop). Both run the same episodes (same
seeds, NEXT_STEP autoreset) driven by the batched LQG agent; only ``step`` calls are timed.

The physics alone bounds what any vector env can reach. Two more contenders time bare physics of
the same batch, one call per env step (N simulations × k physics steps, the native env's threads,
no outputs requested, no Python around them — a vector env must return to Python once per control
period): ``mujoco.rollout`` calls (with the chunking a rollout-based env would use) and
``mujoco.batch`` ``Batch.step`` calls with the force written before each. The faster of the two
(the higher median; its runs are then used round by round, :func:`pendulum_lqg.bench.perf.faster_series`)
is the ceiling: ``native / bare physics`` is the share of it the native env reaches;
``bare batch, … µs gaps`` makes the same ``Batch.step`` calls with ``--gap`` µs of Python spun
before each (not timed): no vector env can avoid running Python between steps, and MuJoCo's
threads, idle that long, go to sleep and wake late (a diagnostic, not the ceiling);
``per vector step`` gives the time beyond bare physics that the native env spends in a step
(its own Python, and the physics slowed by it) and what the target, 0.90× bare physics, allows;
``physics / sync`` is the ceiling of the native/sync ratio on this machine (with ``c`` cores it
grows about like ``c``: the sync env uses one). In each round the contenders take turns block by
block (``--blocks`` blocks of ``steps / blocks`` steps), so a slow spell of the machine hits all of
them alike; figures are medians over the rounds, ratios medians of the per-round ratios.

Usage::

    uv run python benchmarks/vector_benchmark.py [--num-envs 64] [--steps 600] [--blocks 20]
        [--repeats 5] [--gap 100]
"""

from __future__ import annotations

import time

import gymnasium as gym
import numpy as np

import pendulum_lqg
from pendulum_lqg.bench.perf import faster_series, raw_batch_rate, raw_rollout_rate, rollout_chunk
from pendulum_lqg.envs.agent import LQGAgent
from pendulum_lqg.util.limits import MAX_NUM_ENVS
from pendulum_lqg.util.scripts import ScriptParser, int_in, number, run_script

#: Ceilings of the options (vector steps per contender and round; rounds; µs of a gap).
MAX_STEPS, MAX_REPEATS, MAX_GAP_US = 10**7, 100, 10**6


class Runner:
    """Steps one vector env with the agent, across calls (episodes continue where they stopped)."""

    def __init__(self, envs: gym.vector.VectorEnv, agent: LQGAgent) -> None:
        self.envs, self.agent = envs, agent

    def reset(self, seed: int) -> None:
        self.obs, _ = self.envs.reset(seed=seed)
        self.agent.reset()

    def time_steps(self, steps: int) -> float:
        """Seconds spent inside ``envs.step`` over ``steps`` steps of the whole batch."""
        envs, agent, obs = self.envs, self.agent, self.obs
        clock = time.perf_counter
        spent = 0.0
        for _ in range(steps):
            action = agent.act(obs)
            t0 = clock()
            obs, _, terminated, truncated, _ = envs.step(action)
            spent += clock() - t0
            agent.reset(np.nonzero(terminated | truncated)[0])
        self.obs = obs
        return spent


def main(argv: list[str] | None = None) -> None:
    ap = ScriptParser(description=__doc__.splitlines()[0])
    ap.add_argument("--num-envs", type=int_in(1, MAX_NUM_ENVS), default=64)
    ap.add_argument("--steps", type=int_in(1, MAX_STEPS), default=600,
                    help="vector steps per contender and round")
    ap.add_argument("--blocks", type=int_in(1, MAX_STEPS), default=20,
                    help="blocks per round, the contenders taking turns block by block")
    ap.add_argument("--repeats", type=int_in(1, MAX_REPEATS), default=5, help="rounds")
    ap.add_argument("--gap", type=number(minimum=0, maximum=MAX_GAP_US), default=100.0,
                    help="µs of Python before each call of the 'gaps' contender (default 100)")
    args = ap.parse_args(argv)
    n = args.num_envs
    native = gym.make_vec(pendulum_lqg.ENV_ID, num_envs=n)
    sync = gym.make_vec(pendulum_lqg.ENV_ID, num_envs=n, vectorization_mode="sync")
    k, nthread = native.unwrapped.frame_skip, native.unwrapped.nthread
    plant = native.unwrapped.plant
    # each env has its own agent (the agent keeps per-sub-env estimator state)
    runners = {"native": Runner(native, LQGAgent(native)), "sync": Runner(sync, LQGAgent(native))}
    block = max(1, args.steps // args.blocks)
    chunk = rollout_chunk(n, nthread, k)
    bare = {"rollout": lambda: raw_rollout_rate(plant, n, k, nthread, calls=block, outputs=False,
                                                chunk_size=chunk),
            "batch": lambda: raw_batch_rate(plant, n, k, nthread, calls=block)}
    gapped = {"gaps": lambda: raw_batch_rate(plant, n, k, nthread, calls=block,
                                             gap=args.gap * 1e-6)}
    for runner in runners.values():
        runner.reset(seed=0)
        runner.time_steps(20)                                  # warm-up
    print(f"{n} envs, {block * args.blocks} vector steps per contender and round in {args.blocks} "
          f"alternating blocks of {block}, {args.repeats} rounds, seeds 0..{args.repeats - 1}, "
          f"{k} physics steps per env step, {nthread} physics threads")
    rates: dict[str, list[float]] = {name: [] for name in (*runners, *bare, *gapped, "physics")}
    for r in range(args.repeats):
        spent = dict.fromkeys((*runners, *bare, *gapped), 0.0)
        for runner in runners.values():
            runner.reset(seed=r)
        for _ in range(args.blocks):
            for name, runner in runners.items():
                spent[name] += runner.time_steps(block)
            for name, rate in {**bare, **gapped}.items():    # physics steps/s → seconds
                spent[name] += block * n * k / rate()
        for name, secs in spent.items():
            rates[name].append(n * block * args.blocks / secs)
        log = {name: f"{v[-1]:,.0f}" for name, v in rates.items() if v}
        print(f"round {r + 1}/{args.repeats}: env steps/s {log}")
    faster = faster_series({name: rates[name] for name in bare})
    rates["physics"] = rates[faster]
    med = {name: float(np.median(v)) for name, v in rates.items()}
    for name, label in (("native", "native vector env"), ("sync", "SyncVectorEnv"),
                        ("rollout", "bare mujoco.rollout"), ("batch", "bare mujoco.batch"),
                        ("gaps", f"bare batch, {args.gap:g} µs gaps"),
                        ("physics", f"bare physics ({faster})")):
        print(f"{label:>28}: {med[name]:12,.0f} env steps/s ({med[name] * k:14,.0f} physics "
              f"steps/s; runs {min(rates[name]):,.0f}–{max(rates[name]):,.0f})")
    to_physics = [a / b for a, b in zip(rates["native"], rates["physics"], strict=True)]
    to_gaps = [a / b for a, b in zip(rates["native"], rates["gaps"], strict=True)]
    gap_cost = [b / g for b, g in zip(rates["physics"], rates["gaps"], strict=True)]
    to_sync = [a / b for a, b in zip(rates["native"], rates["sync"], strict=True)]
    ceiling = [a / b for a, b in zip(rates["physics"], rates["sync"], strict=True)]
    print(f"{'native / bare physics':>28}: {np.median(to_physics):.3f}   (median of the "
          f"{args.repeats} rounds, {min(to_physics):.3f}–{max(to_physics):.3f}; target ≥ 0.90)")
    print(f"{'native / physics with gaps':>28}: {np.median(to_gaps):.3f}   (rounds "
          f"{min(to_gaps):.3f}–{max(to_gaps):.3f}; with the gaps bare physics takes "
          f"{np.median(gap_cost):.3f}× as long)")
    # the budget: per vector step, the time beyond bare physics that the target allows, and what
    # the native env spends (per round, then medians)
    bare_us = [n / r * 1e6 for r in rates["physics"]]
    spent = [n / a * 1e6 - b for a, b in zip(rates["native"], bare_us, strict=True)]
    print(f"{'per vector step':>28}: bare physics {np.median(bare_us):.0f} µs; the native env "
          f"spends {np.median(spent):.0f} µs beyond it (rounds {min(spent):.0f}–{max(spent):.0f}), "
          f"0.90 allows {np.median(bare_us) * (1 / 0.9 - 1):.0f} µs")
    print(f"{'native / sync':>28}: {np.median(to_sync):.1f}×   (ceiling bare physics / sync "
          f"{np.median(ceiling):.1f}×: no vector env can exceed it here)")
    native.close()
    sync.close()


if __name__ == "__main__":
    run_script(main)
