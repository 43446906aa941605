"""The LQG baseline agent in a plain Gymnasium loop, scored as ``pendulum-lqg bench`` scores policies.

Episode ``k`` of a run seeded ``--seed`` is ``env.reset(seed=episode_seed(seed, k))`` — the very
episode the benchmark runs — so the success rate and mean J printed here equal the benchmark's
for the same configuration (lecture scenario: T = 10 ms, 10 s, x₀ = [0, 0.1, 0, 0], lecture noise,
DLQR + steady-state Kalman filter). ``--check`` also runs the sim core directly
(:func:`~pendulum_lqg.core.runner.run_episodes`, what ``bench`` calls) and compares episode by episode.

Usage::

    uv run python experiments/gym_lqg_agent.py [--episodes 100] [--seed 0] [--observer kalman] [--check]
"""

from __future__ import annotations

import argparse

import gymnasium as gym
import numpy as np

import pendulum_lqg
from pendulum_lqg.core.metrics import mean_se, wilson_interval
from pendulum_lqg.core.seeding import episode_seed
from pendulum_lqg.envs.agent import LQGAgent
from pendulum_lqg.names import OBSERVERS


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--episodes", type=int, default=100)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--controller", default="dlqr", choices=("lqr", "dlqr"))
    ap.add_argument("--observer", default="kalman", choices=OBSERVERS)
    ap.add_argument("--check", action="store_true", help="compare with run_episodes (bench)")
    args = ap.parse_args()

    mode = "state" if args.observer == "none" else "measurement"
    env = gym.make(pendulum_lqg.ENV_ID, observation_mode=mode)
    agent = LQGAgent(env, controller=args.controller, observer=args.observer)

    success, cost = [], []
    for k in range(args.episodes):
        obs, info = env.reset(seed=episode_seed(args.seed, k))
        agent.reset()
        terminated = truncated = False
        while not (terminated or truncated):
            obs, _, terminated, truncated, info = env.step(agent.act(obs))
        success.append(not terminated)
        cost.append(info["running_cost"])
    env.close()

    ok = np.array(success)
    lo, hi = wilson_interval(int(ok.sum()), ok.size)
    mean, se = mean_se(np.array(cost)[ok])          # as bench: J over the successful episodes
    j = f"{mean:.6g} ± {se:.2g}" if ok.any() else "– (no successful episode)"
    print(f"{agent.name}, {args.episodes} episodes, seed {args.seed}: success "
          f"{ok.mean():.1%} (95% CI {lo:.1%}–{hi:.1%}), mean J {j}")

    if args.check:
        from pendulum_lqg.core.metrics import summarize
        from pendulum_lqg.core.runner import run_episodes

        base = env.unwrapped
        res = run_episodes(base.plant, base.scenario, LQGAgent(env, agent.spec).policy,
                           seed=args.seed, episodes=range(args.episodes))
        same = all(r["success"] == s and r["cost"] == c
                   for r, s, c in zip(res.rows, success, cost, strict=True))
        summary = summarize(res.rows)
        bench_j = f"{summary['cost']['mean']:.6g}" if ok.any() else "–"
        print(f"run_episodes (bench): success {summary['success_rate']:.1%}, mean J "
              f"{bench_j}; identical episode by episode: {same}")


if __name__ == "__main__":
    main()
