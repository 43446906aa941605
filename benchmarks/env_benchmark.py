"""Physics steps per second of ``env.step``: pendulum_lqg/CartPoleLQG-v0 vs InvertedPendulum-v5.

Both envs are made with ``gymnasium.make`` (so both carry the same wrappers: TimeLimit,
OrderEnforcing, PassiveEnvChecker) and run the same number of physics steps per env step: ours
has h = 1 ms and T = 10 ms (k = 10); InvertedPendulum-v5 gets ``frame_skip=k``. Only the
``env.step`` calls are timed (action selection and resets are outside the clock). In each round
the two envs take turns block by block (``--blocks`` blocks of ``steps / blocks`` env steps each),
so a slow spell of the machine hits both alike; figures are medians over the rounds and the ratio
is the median of the per-round ratios. Our env is driven by the LQG agent (it balances, the common
case); InvertedPendulum-v5 by zero force. Two more lines time the bare physics of our env step —
one ``mujoco.rollout`` call of one row, and one ``mujoco.batch`` ``Batch.step`` of one simulation
(what the simulation core steps), no Python around them — the share of ``env.step`` no
bookkeeping can remove. A third env, ``CartPoleLQG-v0 via step()``, is ours with its one-row
period taken through the batch entry ``Simulator.step`` (which builds a ``StepResult``) instead of
``Simulator.step_one``: the paired ratio says what the single env's lean entry is worth. A fourth,
``CartPoleLQG-v0 via public rollout``, is ours with its physics calling the public
``Batch.rollout`` for every period instead of the batch's C++ core
(:data:`pendulum_lqg.core.physics.mujoco_batch.DIRECT_CALL`): the paired ratio says what the
package's one private API is worth (it is kept only while it is worth ≥ 1.03×).

Usage::

    uv run python benchmarks/env_benchmark.py [--steps 10000] [--blocks 20] [--repeats 7]
"""

from __future__ import annotations

import time

import gymnasium as gym
import numpy as np

import pendulum_lqg
from pendulum_lqg.bench.perf import raw_batch_rate, raw_rollout_rate
from pendulum_lqg.envs.agent import LQGAgent
from pendulum_lqg.util.scripts import ScriptParser, int_in, requires, run_script

#: Ceilings of the options (env steps per env and round; rounds).
MAX_STEPS, MAX_REPEATS = 10**7, 100


class Runner:
    """Steps one env with its policy, across calls (an episode continues where it stopped)."""

    def __init__(self, env: gym.Env, policy: object | None) -> None:
        self.env, self.policy = env, policy
        self.zero = np.zeros(env.action_space.shape, dtype=env.action_space.dtype)

    def reset(self, seed: int) -> None:
        self.obs, _ = self.env.reset(seed=seed)
        if self.policy is not None:
            self.policy.reset()

    def time_steps(self, steps: int) -> float:
        """Seconds spent inside ``env.step`` over ``steps`` steps (resets are not timed)."""
        env, policy, zero = self.env, self.policy, self.zero
        clock = time.perf_counter
        spent = 0.0
        obs = self.obs
        for _ in range(steps):
            action = policy.act(obs) if policy is not None else zero
            t0 = clock()
            obs, _, terminated, truncated, _ = env.step(action)
            spent += clock() - t0
            if terminated or truncated:
                obs, _ = env.reset()
                if policy is not None:
                    policy.reset()
        self.obs = obs
        return spent


def through_batch_step(env: gym.Env) -> gym.Env:
    """``env`` with its simulator's ``step_one`` answered by ``step`` on the one row (the same
    numbers, which the tests check: ``tests/core/test_loop.py``)."""
    sim = env.unwrapped._sim

    def step_one(u: float) -> tuple[float, int, float]:
        res = sim.step(np.array([u]))
        return float(res.cost[0]), int(res.reason[0]), float(res.requested[0])

    sim.step_one = step_one
    return env


def through_public_rollout(env: gym.Env) -> gym.Env:
    """``env`` with its physics taking the public ``Batch.rollout`` for every period (the same
    numbers: ``tests/core/physics/test_mujoco_batch.py`` checks the two calls)."""
    env.reset(seed=0)                                   # makes the simulator's physics
    env.unwrapped._sim._physics.direct_call = False
    return env


def main(argv: list[str] | None = None) -> None:
    ap = ScriptParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int_in(1, MAX_STEPS), default=10000,
                    help="env steps per env and round")
    ap.add_argument("--blocks", type=int_in(1, MAX_STEPS), default=20,
                    help="blocks per round, the envs alternating block by block")
    ap.add_argument("--repeats", type=int_in(1, MAX_REPEATS), default=7, help="rounds")
    args = ap.parse_args(argv)
    requires("imageio", needed_for="gymnasium's InvertedPendulum-v5 (the env compared with)",
             install="imageio (in the dev group: uv sync; or pip install imageio)")

    ours = gym.make(pendulum_lqg.ENV_ID)
    k = ours.unwrapped.frame_skip
    agent = LQGAgent(ours)
    theirs = gym.make("InvertedPendulum-v5", frame_skip=k)
    assert theirs.unwrapped.frame_skip == k
    generic = through_batch_step(gym.make(pendulum_lqg.ENV_ID))
    public = through_public_rollout(gym.make(pendulum_lqg.ENV_ID))
    runners = {"CartPoleLQG-v0": Runner(ours, agent), "InvertedPendulum-v5": Runner(theirs, None),
               "CartPoleLQG-v0 via step()": Runner(generic, LQGAgent(generic)),
               "CartPoleLQG-v0 via public rollout": Runner(public, LQGAgent(public))}
    block = max(1, args.steps // args.blocks)
    for runner in runners.values():                  # warm-up
        runner.reset(seed=1)
        runner.time_steps(500)
    print(f"{block * args.blocks} env.step calls per env and round, in {args.blocks} alternating "
          f"blocks of {block}; {args.repeats} rounds, seeds 0..{args.repeats - 1}, {k} physics "
          "steps per env step")
    runs: dict[str, list[float]] = {name: [] for name in runners}
    runs["physics: rollout"], runs["physics: batch"] = [], []
    for r in range(args.repeats):
        spent = dict.fromkeys(runners, 0.0)
        for runner in runners.values():
            runner.reset(seed=r)
        for _ in range(args.blocks):             # the two envs take turns block by block, so a
            for name, runner in runners.items():  # slow spell of the machine hits both alike
                spent[name] += runner.time_steps(block)
        for name in runners:
            runs[name].append(block * args.blocks * k / spent[name])
        plant = ours.unwrapped.plant
        runs["physics: rollout"].append(
            raw_rollout_rate(plant, 1, k, 0, calls=args.steps, outputs=False))
        runs["physics: batch"].append(raw_batch_rate(plant, 1, k, 1, calls=args.steps))
        print(f"round {r + 1}/{args.repeats}: " + ", ".join(
            f"{name} {v[-1]:,.0f}" for name, v in runs.items()) + " physics steps/s")
    for name, rates in runs.items():
        med = float(np.median(rates))
        what = {"physics: rollout": "bare mujoco.rollout of 1 row",
                "physics: batch": "bare Batch.step of 1 simulation"}.get(name, "env.step")
        print(f"{name:>20}: {med:12,.0f} physics steps/s ({k / med * 1e6:6.1f} µs per {what}, "
              f"{k} physics steps each; runs {min(rates):,.0f}–{max(rates):,.0f})")
    rounds = [a / b for a, b in zip(runs["CartPoleLQG-v0"], runs["InvertedPendulum-v5"], strict=True)]
    print(f"{'ratio':>20}: {float(np.median(rounds)):.2f}× (CartPoleLQG-v0 / InvertedPendulum-v5, "
          f"median of the {args.repeats} rounds' ratios, {min(rounds):.2f}–{max(rounds):.2f}; "
          f"target ≥ 2.5×)")
    lean = [a / b for a, b in zip(runs["CartPoleLQG-v0"], runs["CartPoleLQG-v0 via step()"],
                                  strict=True)]
    print(f"{'step_one / step()':>20}: {float(np.median(lean)):.3f}× (env.step through the one-row "
          f"entry vs through Simulator.step, median of the rounds' ratios, "
          f"{min(lean):.3f}–{max(lean):.3f}; the entry is kept only if ≥ 1.03×)")
    direct = [a / b for a, b in zip(runs["CartPoleLQG-v0"],
                                    runs["CartPoleLQG-v0 via public rollout"], strict=True)]
    print(f"{'direct / public':>20}: {float(np.median(direct)):.3f}× (env.step with the batch's "
          f"C++ core called directly vs through the public Batch.rollout, median of the rounds' "
          f"ratios, {min(direct):.3f}–{max(direct):.3f}; the direct call is kept only if ≥ 1.03×)")

if __name__ == "__main__":
    run_script(main)
