"""Physics steps per second of ``env.step``: pendulum_lqg/CartPoleLQG-v0 vs InvertedPendulum-v5.

Both envs are made with ``gymnasium.make`` (so both carry the same wrappers: TimeLimit,
OrderEnforcing, PassiveEnvChecker) and run the same number of physics steps per env step: ours
has h = 1 ms and T = 10 ms (k = 10); InvertedPendulum-v5 gets ``frame_skip=k``. Only the
``env.step`` calls are timed (action selection and resets are outside the clock). The two envs
take turns, one timed run each per round, so a change in machine load hits both alike; figures are
medians over the rounds and the ratio is the median of the per-round ratios. Our env is driven by
the LQG agent (it balances, the common case); InvertedPendulum-v5 by zero force. A third line times
the bare physics of our env step (one ``mujoco.rollout`` call of one row, no Python around it), the
share of ``env.step`` no bookkeeping can remove.

Usage::

    uv run python experiments/env_benchmark.py [--steps 10000] [--repeats 7]
"""

from __future__ import annotations

import argparse
import time

import gymnasium as gym
import numpy as np

import pendulum_lqg
from pendulum_lqg.agent import LQGAgent
from pendulum_lqg.perf import raw_rollout_rate


def time_steps(env: gym.Env, steps: int, policy: object | None, seed: int) -> float:
    """Seconds spent inside ``env.step`` over ``steps`` steps (resets are not timed)."""
    obs, _ = env.reset(seed=seed)
    if policy is not None:
        policy.reset()
    zero = np.zeros(env.action_space.shape, dtype=env.action_space.dtype)
    clock = time.perf_counter
    spent = 0.0
    for _ in range(steps):
        action = policy.act(obs) if policy is not None else zero
        t0 = clock()
        obs, _, terminated, truncated, _ = env.step(action)
        spent += clock() - t0
        if terminated or truncated:
            obs, _ = env.reset()
            if policy is not None:
                policy.reset()
    return spent


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=10000, help="env steps per timed run")
    ap.add_argument("--repeats", type=int, default=7, help="rounds (one timed run per env each)")
    args = ap.parse_args()

    ours = gym.make(pendulum_lqg.ENV_ID)
    k = ours.unwrapped.frame_skip
    agent = LQGAgent(ours)
    theirs = gym.make("InvertedPendulum-v5", frame_skip=k)
    assert theirs.unwrapped.frame_skip == k
    contenders = (("CartPoleLQG-v0", ours, agent), ("InvertedPendulum-v5", theirs, None))
    for _, env, policy in contenders:
        time_steps(env, 500, policy, seed=1)     # warm-up
    print(f"{args.steps} env.step calls per run, {args.repeats} rounds, seeds 0..{args.repeats - 1}, "
          f"{k} physics steps per env step")
    runs: dict[str, list[float]] = {name: [] for name, _, _ in contenders}
    for r in range(args.repeats):
        for name, env, policy in contenders:
            runs[name].append(args.steps * k / time_steps(env, args.steps, policy, seed=r))
        runs.setdefault("physics only", []).append(
            raw_rollout_rate(ours.unwrapped.plant, 1, k, 0, calls=args.steps, outputs=False))
        print(f"round {r + 1}/{args.repeats}: " + ", ".join(
            f"{name} {v[-1]:,.0f}" for name, v in runs.items()) + " physics steps/s")
    for name, rates in runs.items():
        med = float(np.median(rates))
        what = "bare mujoco.rollout of 1 row" if name == "physics only" else "env.step"
        print(f"{name:>20}: {med:12,.0f} physics steps/s ({k / med * 1e6:6.1f} µs per {what}, "
              f"{k} physics steps each; runs {min(rates):,.0f}–{max(rates):,.0f})")
    rounds = [a / b for a, b in zip(runs["CartPoleLQG-v0"], runs["InvertedPendulum-v5"], strict=True)]
    print(f"{'ratio':>20}: {float(np.median(rounds)):.2f}× (CartPoleLQG-v0 / InvertedPendulum-v5, "
          f"median of the {args.repeats} rounds' ratios, {min(rounds):.2f}–{max(rounds):.2f}; "
          f"target ≥ 2.5×)")

if __name__ == "__main__":
    main()
