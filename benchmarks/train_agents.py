"""Train one RL baseline run — a method and a training seed — with stable-baselines3.

Needs the ``rl`` extra (stable-baselines3, sb3-contrib and torch; a CPU-only torch: install its
wheel first, ``pip install torch --index-url https://download.pytorch.org/whl/cpu``)::

    python benchmarks/train_agents.py ppo-history --seed 3                    # one run
    python benchmarks/train_agents.py ppo-history --seed 3 --steps 4000 --eval-every 2000   # a smoke run
    python benchmarks/train_agents.py ppo-history --seed 3 --noise-scale 0.25 # the noise ladder
    python benchmarks/train_agents.py --list                                  # the methods

One run writes, in ``--out`` (default ``experiments/agents/models``):

* ``METHOD-seedS.zip`` — the model (``METHOD-noiseX-seedS.zip`` with ``--noise-scale X``: the
  method's suite with its env's ``noise_scale`` set to ``X``, the noise ladder; its record's
  ``method`` is ``METHOD-noiseX``, so ``board`` never pools it with the method's own runs);
* ``METHOD-seedS.json`` — its training record (the schema:
  :func:`pendulum_lqg.boundary.schemas.training_record`): ``method``, ``seed``, the algorithm, the
  observation design (``frame_stack``, ``past_actions``, the frozen ``obs_norm``), the env, the
  budget and the library versions, which ``pendulum-lqg score --agent sb3:METHOD-seedS.zip``
  reads to rebuild the very observation the model was trained on
  (:mod:`pendulum_lqg.scoreboard.obs_design`) and copies into the score file (``board`` then
  aggregates the runs of one method);
* ``METHOD-seedS-curve.csv`` — the learning curve: every ``--eval-every`` env steps (default
  50 000) and at the end, the success rate and the failure-aware score
  (:mod:`pendulum_lqg.scoreboard.stats`) of the deterministic policy on 20 fixed episodes whose
  seeds derive from :data:`EVAL_SEED`, never a suite's seed, against the suite's reference on the
  same episodes.

Every method trains on the native vector env through the SB3 adapter
(:func:`pendulum_lqg.scoreboard.sb3_vec.native_vec_env`: one batched simulator, SB3's
same-step autoreset), the suite's ``[env]`` keywords, actions normalised to ``[−1, 1]``, seen
through the design's wrapper then ``VecNormalize`` (statistics frozen into the record). Sub-env
``i`` of run seed ``S`` is seeded ``TRAIN_SEED_BASE + 1000·S + i``: the suites' episodes are never
trained on.
"""

from __future__ import annotations

import argparse
import csv
import json
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

#: Root seed of the learning curve's 20 evaluation episodes (not a suite's seed).
EVAL_SEED, EVAL_EPISODES = 90_001, 20
#: Training env seeds: run seed S seeds sub-env i with TRAIN_SEED_BASE + 1000·S + i.
TRAIN_SEED_BASE = 500_000


@dataclass(frozen=True)
class Method:
    """One trainable method: algorithm, suite, observation design, budget and keywords."""

    algo: str
    suite: str
    frame_stack: int
    past_actions: bool
    steps: int
    envs: int
    kwargs: dict[str, Any] = field(default_factory=dict)
    what: str = ""
    #: show the reference Kalman filter's x̂ instead of y (:mod:`pendulum_lqg.scoreboard.obs_design`)
    estimator: str | None = None

    def design(self) -> Any:
        from pendulum_lqg.scoreboard.obs_design import ObservationDesign

        return ObservationDesign(self.frame_stack, self.past_actions, self.estimator)


# K = 32, log_std_init = −1 and γ = 0.998: the pilot's choice (benchmarks/pilot_agents.py)
_PPO = {"n_steps": 256, "batch_size": 1024, "gamma": 0.998,
        "policy_kwargs": {"log_std_init": -1.0, "net_arch": [64, 64]}}
METHODS: dict[str, Method] = {
    "ppo-history": Method("PPO", "lecture", 32, True, 1_000_000, 16, _PPO,
                          "PPO-MLP over the last 32 (y, previous action) pairs"),
    "recurrentppo-actions": Method(
        "RecurrentPPO", "lecture", 1, True, 1_000_000, 16,
        {"n_steps": 256, "batch_size": 1024, "n_epochs": 5, "gamma": 0.998,
         "policy_kwargs": {"lstm_hidden_size": 64, "net_arch": [64], "log_std_init": -1.0}},
        "RecurrentPPO (LSTM 64) over (y, previous action)"),
    # 16 envs, 2 gradient steps per vector step: one update per 8 env steps (37 500 updates in
    # 300 000 steps), what the CPU budget of five seeds allows
    "sac-history": Method("SAC", "lecture", 32, True, 300_000, 16,
                          {"learning_starts": 5_000, "train_freq": 1, "gradient_steps": 2,
                           "gamma": 0.995, "policy_kwargs": {"net_arch": [64, 64]}},
                          "SAC over the last 32 (y, previous action) pairs"),
    "ppo-kalman": Method("PPO", "lecture", 1, False, 1_000_000, 16, _PPO,
                         "PPO-MLP on the reference Kalman filter's x̂ (estimation given, control "
                         "learnt)", estimator="kalman"),
    "ppo-full-state": Method("PPO", "full-state", 1, False, 400_000, 16, _PPO,
                             "PPO-MLP on the true state x (the control-only row)"),
    "ppo-lecture": Method("PPO", "lecture", 8, False, 400_000, 8,
                          {"n_steps": 256, "batch_size": 256},
                          "the first board's PPO: the last 8 y, no past actions"),
}


def run_name(method: str, seed: int) -> str:
    return f"{method}-seed{seed}"


def method_name(method: str, noise_scale: float | None) -> str:
    """The run's method: ``METHOD``, or ``METHOD-noiseX`` on the noise ladder."""
    return method if noise_scale is None else f"{method}-noise{noise_scale:g}"


def training_suite(m: Method, noise_scale: float | None = None) -> Any:
    """The suite ``m`` trains on, its env's ``noise_scale`` set to ``noise_scale`` if given."""
    from pendulum_lqg.scoreboard.suites import load_suite

    return load_suite(m.suite).with_noise_scale(noise_scale)


def make_training_env(m: Method, seed: int, noise_scale: float | None = None,
                      ) -> tuple[Any, Any]:
    """``VecNormalize(design(native vector env))`` of method ``m``, and the suite (seeded by
    :func:`build`)."""
    from stable_baselines3.common.vec_env import VecNormalize

    from pendulum_lqg.scoreboard.obs_design import ObservationDesign, history_vec_env
    from pendulum_lqg.scoreboard.sb3_vec import native_vec_env

    suite = training_suite(m, noise_scale)
    venv = native_vec_env(m.envs, nthread=1, normalize_action=True, **suite.env)
    design = m.design()
    if design != ObservationDesign():
        venv = history_vec_env(venv, design, normalize_action=True)
    return VecNormalize(venv, norm_obs=True, norm_reward=True, clip_obs=10.0), suite


def obs_norm_of(norm: Any) -> dict[str, Any]:
    return {"mean": norm.obs_rms.mean.tolist(), "var": norm.obs_rms.var.tolist(),
            "clip": float(norm.clip_obs), "epsilon": float(norm.epsilon)}


def evaluate(model: Any, m: Method, norm: Any, suite: Any, reference: list[dict[str, Any]],
             ) -> dict[str, float | None]:
    """Success and failure-aware score of the deterministic policy on the curve's episodes."""
    from types import SimpleNamespace

    from pendulum_lqg.scoreboard.sb3_batch import batched_rows
    from pendulum_lqg.scoreboard.score import success_figures
    from pendulum_lqg.scoreboard.stats import failure_aware_figures

    # the scorer's batched path, with the statistics VecNormalize holds now (the record's later)
    run = SimpleNamespace(path_text=f"(training {m.algo})", model=model, normalize_action=True,
                          env=suite.env, meta={**m.design().record(),
                                               "obs_norm": obs_norm_of(norm)})
    rows = batched_rows(eval_suite(suite), run)
    fig = failure_aware_figures(rows, reference)
    lo, hi = fig["score_ci"]
    return {"success_rate": success_figures(rows)["success_rate"],
            "score_mean": fig["score_mean"], "score_ci_lo": lo, "score_ci_hi": hi}


def eval_suite(suite: Any) -> Any:
    return replace(suite, seed=EVAL_SEED, episodes=EVAL_EPISODES)


def train(method: str, out: Path, *, seed: int, steps: int | None = None,
          eval_every: int = 50_000, m: Method | None = None,
          noise_scale: float | None = None) -> Path:
    """Train run ``seed`` of ``method`` (or of ``m``, a variant of it that the pilot tries, under
    the name ``method``), on its suite's noise or at ``noise_scale``; write its model, record and
    learning curve to ``out``."""
    import torch

    from pendulum_lqg.scoreboard import episodes as ep

    m = m or METHODS[method]
    steps = steps or m.steps
    method = method_name(method, noise_scale)
    torch.set_num_threads(1)
    model, venv, suite = build(m, seed, noise_scale)
    reference = ep.policy_rows(eval_suite(suite), suite.reference, nthread=1)
    out.mkdir(parents=True, exist_ok=True)
    path = out / f"{run_name(method, seed)}.zip"
    curve, t0, done = [], time.perf_counter(), 0
    while done < steps:
        chunk = min(eval_every, steps - done)
        model.learn(total_timesteps=chunk, reset_num_timesteps=False)
        done = int(model.num_timesteps)
        curve.append({"env_steps": done, "wall_seconds": round(time.perf_counter() - t0, 1),
                      **evaluate(model, m, venv, suite, reference)})
        print(f"{run_name(method, seed)}: {done:,} steps, success {curve[-1]['success_rate']:.2f},"
              f" score {curve[-1]['score_mean']}", flush=True)
    model.save(str(path))
    _write_curve(path.with_name(f"{run_name(method, seed)}-curve.csv"), curve)
    record = _record(method, m, seed, steps, venv, suite, curve)
    record["budget"]["steps"] = done        # PPO rolls out whole n_steps × envs: may exceed
    path.with_suffix(".json").write_text(json.dumps(record, indent=1) + "\n", encoding="utf-8")
    return path


def build(m: Method, seed: int, noise_scale: float | None = None) -> tuple[Any, Any, Any]:
    """The model, its training env and the suite of run ``seed`` of ``m``, the env seeded for
    its first reset (SB3 seeds the env with the model's seed when it builds the model: seeded
    again after that, sub-env i starts from TRAIN_SEED_BASE + 1000·seed + i)."""
    venv, suite = make_training_env(m, seed, noise_scale)
    model = _model(m, venv, seed)
    venv.seed(TRAIN_SEED_BASE + 1000 * seed)
    return model, venv, suite


def _model(m: Method, venv: Any, seed: int) -> Any:
    import importlib

    from pendulum_lqg.boundary.schemas import ALGORITHMS

    cls = getattr(importlib.import_module(ALGORITHMS[m.algo]), m.algo)
    policy = "MlpLstmPolicy" if m.algo == "RecurrentPPO" else "MlpPolicy"
    return cls(policy, venv, seed=seed, verbose=0, device="cpu", **m.kwargs)


def _write_curve(path: Path, curve: list[dict[str, Any]]) -> None:
    with path.open("w", newline="", encoding="utf-8") as f:
        writer = csv.DictWriter(f, fieldnames=list(curve[0]))
        writer.writeheader()
        writer.writerows(curve)


def _record(method: str, m: Method, seed: int, steps: int, venv: Any, suite: Any,
            curve: list[dict[str, Any]]) -> dict[str, Any]:
    import pendulum_lqg
    from pendulum_lqg.scoreboard.sb3 import rl_versions

    return {"method": method, "seed": seed, "algo": m.algo, "suite": suite.name,
            **m.design().record(),
            "normalize_action": True, "obs_norm": obs_norm_of(venv),
            "wrappers": "VecNormalize(history(native_vec_env))", "env_id": pendulum_lqg.ENV_ID,
            "env": suite.env, "reward": "v0 (exp(-c / (s·T)))",
            "budget": {"steps": steps, "steps_requested": steps, "seed": seed, "envs": m.envs,
                       "env_seeds": f"{TRAIN_SEED_BASE + 1000 * seed} + i",
                       "wall_seconds": curve[-1]["wall_seconds"], "threads": 1,
                       "kwargs": m.kwargs},
            "curve": {"eval_seed": EVAL_SEED, "episodes": EVAL_EPISODES},
            "versions": {**rl_versions(), **_versions()}}


def _versions() -> dict[str, str]:
    from importlib import metadata

    return {lib: metadata.version(lib) for lib in ("pendulum-lqg", "gymnasium", "mujoco")}


def main(argv: list[str] | None = None) -> int:
    import sys

    args_in = sys.argv[1:] if argv is None else argv
    if args_in and args_in[0] in ("ars-history", "sysid-lqg"):  # torch-free: train_linear.py
        from train_linear import main as linear_main

        return linear_main(args_in)
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("method", nargs="?", choices=sorted(METHODS))
    ap.add_argument("--seed", type=int, default=0, help="the run's training seed (default 0)")
    ap.add_argument("--steps", type=int, default=None, help="env steps (default: the method's)")
    ap.add_argument("--eval-every", type=int, default=50_000, help="env steps between curve points")
    ap.add_argument("--noise-scale", type=float, default=None, metavar="X",
                    help="train at the suite's env with noise_scale X (the noise ladder: 0, 0.25, "
                         "0.5, 1); writes METHOD-noiseX-seedS (default: the suite's own noise)")
    ap.add_argument("--out", type=Path, default=Path("experiments/agents/models"))
    ap.add_argument("--list", action="store_true", help="list the methods and exit")
    args = ap.parse_args(argv)
    if args.list or args.method is None:
        for name, m in METHODS.items():
            print(f"{name:22s} {m.algo:13s} {m.suite:11s} {m.steps:>9,} steps  {m.what}")
        return 0
    for name in ("seed", "steps", "eval_every"):
        value = getattr(args, name)
        if value is not None and value < (0 if name == "seed" else 1):
            ap.error(f"--{name.replace('_', '-')}: expected a "
                     f"{'non-negative' if name == 'seed' else 'positive'} integer, got {value}")
    if args.noise_scale is not None and not 0 <= args.noise_scale < float("inf"):
        ap.error(f"--noise-scale: expected a finite number ≥ 0, got {args.noise_scale}")
    path = train(args.method, args.out, seed=args.seed, steps=args.steps,
                 eval_every=args.eval_every, noise_scale=args.noise_scale)
    print(f"wrote {path}, {path.with_suffix('.json').name} and "
          f"{path.stem}-curve.csv", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
