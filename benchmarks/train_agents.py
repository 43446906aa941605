"""Train the RL baselines of the leaderboard with stable-baselines3 and score them on the suites.

Needs the ``rl`` extra (stable-baselines3, sb3-contrib and torch)::

    pip install torch==2.13.0   # a CPU build; or let pip pick one
    pip install 'dist/pendulum_lqg-0.5.0-py3-none-any.whl[rl]'
    python benchmarks/train_agents.py --out experiments/agents/models      # all four baselines
    python benchmarks/train_agents.py --only ppo-lecture --steps 20000    # one, a shorter budget

Each baseline trains on a suite's Gymnasium env (the suite's ``[env]`` keywords, its reward
version ``pendulum_lqg/CartPoleLQG-v0``), with actions normalised to ``[−1, 1]``, observations
stacked, where named, over the last observations (``VecFrameStack``, newest last), then
normalised by ``VecNormalize`` (its statistics frozen and saved with the model). Training seeds are not the
suite's: the suites' episodes are never trained on. Each model is saved as ``NAME.zip`` with its
training record ``NAME.json`` (algorithm, wrappers, budget: steps, seed, envs, wall time), which
``pendulum-lqg score --agent sb3:NAME.zip`` reads to replay the same wrappers.

================  =========================  ============  ===================================
baseline          algorithm                  suite         observation
================  =========================  ============  ===================================
ppo-lecture       PPO (MLP 64×64)            lecture       the last 8 noisy y = [p, θ]
recurrentppo-     RecurrentPPO (LSTM 64)     lecture       the noisy y = [p, θ]
lecture
sac-lecture       SAC (MLP 64×64)            lecture       the last 8 noisy y = [p, θ]
ppo-full-state    PPO (MLP 64×64)            full-state    the true state x
================  =========================  ============  ===================================
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

#: name → (algorithm, suite, frame stack, default training steps, envs, algorithm keywords)
BASELINES: dict[str, tuple[str, str, int, int, int, dict[str, Any]]] = {
    "ppo-lecture": ("PPO", "lecture", 8, 400_000, 8, {"n_steps": 256, "batch_size": 256}),
    "recurrentppo-lecture": ("RecurrentPPO", "lecture", 1, 150_000, 8,
                             {"n_steps": 512, "batch_size": 1024, "n_epochs": 5,
                              "policy_kwargs": {"lstm_hidden_size": 64, "net_arch": [64]}}),
    "sac-lecture": ("SAC", "lecture", 8, 60_000, 1, {"learning_starts": 2_000,
                                                      "train_freq": 4, "gradient_steps": 1,
                                                      "policy_kwargs": {"net_arch": [64, 64]}}),
    "ppo-full-state": ("PPO", "full-state", 1, 200_000, 8, {"n_steps": 256, "batch_size": 256}),
}
#: Training seed (the suites' episodes use their own seeds: never trained on).
TRAIN_SEED = 7


def train(name: str, out: Path, *, steps: int | None = None, seed: int = TRAIN_SEED) -> Path:
    """Train baseline ``name`` and save ``out/NAME.zip`` and ``out/NAME.json``."""
    import gymnasium as gym
    import torch
    from stable_baselines3 import PPO, SAC
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import VecFrameStack, VecNormalize

    import pendulum_lqg
    from pendulum_lqg.scoreboard.suites import load_suite

    algo, suite_name, stack, default_steps, n_envs, kwargs = BASELINES[name]
    steps = steps or default_steps
    torch.set_num_threads(1)
    suite = load_suite(suite_name)
    env_kwargs = {**suite.env, "normalize_action": True}
    venv = make_vec_env(lambda: gym.make(pendulum_lqg.ENV_ID, **env_kwargs), n_envs=n_envs,
                        seed=seed)
    if stack > 1:                           # stack, then normalise the stacked observation (the
        venv = VecFrameStack(venv, n_stack=stack)   # off-policy replay buffer needs this order)
    venv = VecNormalize(venv, norm_obs=True, norm_reward=True, clip_obs=10.0)
    if algo == "RecurrentPPO":
        from sb3_contrib import RecurrentPPO

        model: Any = RecurrentPPO("MlpLstmPolicy", venv, seed=seed, verbose=0, device="cpu",
                                  **kwargs)
    elif algo == "SAC":
        model = SAC("MlpPolicy", venv, seed=seed, verbose=0, device="cpu", **kwargs)
    else:
        model = PPO("MlpPolicy", venv, seed=seed, verbose=0, device="cpu", **kwargs)
    t0 = time.perf_counter()
    model.learn(total_timesteps=steps)
    wall = time.perf_counter() - t0
    out.mkdir(parents=True, exist_ok=True)
    path = out / f"{name}.zip"
    model.save(str(path))
    norm = venv
    record = {"algo": algo, "suite": suite_name, "frame_stack": stack, "normalize_action": True,
              "wrappers": "VecNormalize(VecFrameStack(env))",
              "obs_norm": {"mean": norm.obs_rms.mean.tolist(), "var": norm.obs_rms.var.tolist(),
                           "clip": float(norm.clip_obs), "epsilon": float(norm.epsilon)},
              "env_id": pendulum_lqg.ENV_ID, "env": suite.env, "reward": "v0 (exp(-c / (s·T)))",
              "budget": {"steps": steps, "seed": seed, "envs": n_envs,
                         "wall_seconds": round(wall, 1), "threads": 1, "kwargs": kwargs},
              "versions": _versions()}
    path.with_suffix(".json").write_text(json.dumps(record, indent=1) + "\n", encoding="utf-8")
    print(f"{name}: {algo} on {suite_name}, {steps:,} steps in {wall:.0f} s → {path}", flush=True)
    return path


def _versions() -> dict[str, str]:
    from importlib import metadata

    return {lib: metadata.version(lib) for lib in
            ("pendulum-lqg", "stable-baselines3", "sb3-contrib", "torch", "gymnasium", "mujoco")}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("experiments/agents/models"))
    ap.add_argument("--only", action="append", choices=sorted(BASELINES), default=None)
    ap.add_argument("--steps", type=int, default=None, help="training steps (default: each one's)")
    ap.add_argument("--seed", type=int, default=TRAIN_SEED)
    args = ap.parse_args()
    for name in args.only or list(BASELINES):
        train(name, args.out, steps=args.steps, seed=args.seed)


if __name__ == "__main__":
    main()
