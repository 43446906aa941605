"""The deep-RL baselines: stable-baselines3 (PPO, SAC) and sb3-contrib (RecurrentPPO) runs of
``pendulum-lqg train``, the ``rl`` extra imported only inside the functions that train.

One run writes, in its folder:

* ``METHOD-seedS.zip`` — the model (``METHOD-noiseX-seedS.zip`` with ``--noise-scale X``: the
  method's suite with its env's ``noise_scale`` set to ``X``, the noise ladder; its record's
  ``method`` is ``METHOD-noiseX``, so ``board`` never pools it with the method's own runs);
* ``METHOD-seedS.json`` — its training record (the schema:
  :func:`pendulum_lqg.boundary.schemas.training_record`): ``method``, ``seed``, the algorithm, the
  observation design (``frame_stack``, ``past_actions``, the frozen ``obs_norm``), the env, the
  budget and the library versions, which ``pendulum-lqg score --agent sb3:METHOD-seedS.zip`` reads
  to rebuild the very observation the model was trained on;
* ``METHOD-seedS-curve.csv`` — the learning curve (:mod:`pendulum_lqg.learn.curve`), every
  ``--eval-every`` env steps and at the end, with the mean return (the env's reward, before
  ``VecNormalize``) and length of the training episodes.

Every method trains on the native vector env through the SB3 adapter
(:func:`pendulum_lqg.scoreboard.sb3_vec.native_vec_env`), the suite's ``[env]`` keywords, actions
normalised to ``[−1, 1]``, seen through the design's wrapper then ``VecNormalize`` (statistics
frozen into the record). Sub-env ``i`` of run seed ``S`` is seeded ``TRAIN_SEED_BASE + 1000·S +
i``. At every curve point the run writes a checkpoint (the model with its optimiser state,
``VecNormalize``'s statistics, SAC's replay buffer); ``--resume`` loads it and reseeds the envs
with ``root + N + i`` at step ``N`` (the episodes in progress at the stop are not continued: the
resumed run equals the uninterrupted one up to the checkpoint, not after it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from pendulum_lqg.learn.runs import (
    EVAL_EPISODES,
    EVAL_SEED,
    TRAIN_SEED_BASE,
    RunContext,
    Stopped,
    eval_suite,
    versions,
    write_json,
)

CHECKPOINT = "-checkpoint.json"


@dataclass(frozen=True)
class Method:
    """One trainable SB3 method: algorithm, suite, observation design, budget and keywords."""

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


# K = 32, log_std_init = −1 and γ = 0.998: the pilot's choice (pendulum_lqg.learn.pilot)
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


def method_name(method: str, noise_scale: float | None) -> str:
    """The run's method: ``METHOD``, or ``METHOD-noiseX`` on the noise ladder."""
    return method if noise_scale is None else f"{method}-noise{noise_scale:g}"


def training_suite(m: Method, noise_scale: float | None = None) -> Any:
    """The suite ``m`` trains on, its env's ``noise_scale`` set to ``noise_scale`` if given."""
    from pendulum_lqg.scoreboard.suites import load_suite

    return load_suite(m.suite).with_noise_scale(noise_scale)


def make_training_env(m: Method, suite: Any) -> Any:
    """``VecNormalize(design(native vector env))`` of method ``m`` on ``suite``'s env."""
    from stable_baselines3.common.vec_env import VecNormalize

    return VecNormalize(_design_env(m, suite), norm_obs=True, norm_reward=True, clip_obs=10.0)


def _design_env(m: Method, suite: Any) -> Any:
    from pendulum_lqg.scoreboard.obs_design import ObservationDesign, history_vec_env
    from pendulum_lqg.scoreboard.sb3_vec import native_vec_env

    venv = native_vec_env(m.envs, nthread=1, normalize_action=True, **suite.env)
    if m.design() != ObservationDesign():
        venv = history_vec_env(venv, m.design(), normalize_action=True)
    return venv


def build(m: Method, seed: int, suite: Any, *, tensorboard: Path | None = None,
          ) -> tuple[Any, Any]:
    """The model and its training env of run ``seed`` of ``m`` (SB3's TensorBoard logs in
    ``tensorboard`` where tensorboard is installed), the env seeded for its first reset (SB3 seeds
    the env with the model's seed when it builds the model: seeded again after that, sub-env i
    starts from TRAIN_SEED_BASE + 1000·seed + i)."""
    import importlib

    from pendulum_lqg.boundary.schemas import ALGORITHMS

    venv = make_training_env(m, suite)
    cls = getattr(importlib.import_module(ALGORITHMS[m.algo]), m.algo)
    policy = "MlpLstmPolicy" if m.algo == "RecurrentPPO" else "MlpPolicy"
    model = cls(policy, venv, seed=seed, verbose=0, device="cpu",
                tensorboard_log=_tensorboard_folder(tensorboard), **m.kwargs)
    venv.seed(TRAIN_SEED_BASE + 1000 * seed)
    return model, venv


def _tensorboard_folder(folder: Path | None) -> str | None:
    """TensorBoard logs (SB3's own) only where tensorboard is installed."""
    import importlib.util

    if folder is None or importlib.util.find_spec("tensorboard") is None:
        return None
    return str(folder)


def obs_norm_of(norm: Any) -> dict[str, Any]:
    return {"mean": norm.obs_rms.mean.tolist(), "var": norm.obs_rms.var.tolist(),
            "clip": float(norm.clip_obs), "epsilon": float(norm.epsilon)}


def curve_rows(model: Any, m: Method, norm: Any, suite: Any) -> list[dict[str, Any]]:
    """The deterministic policy's rows on the curve's episodes, through the scorer's batch path
    with the statistics ``VecNormalize`` holds now (the record's later)."""
    from types import SimpleNamespace

    from pendulum_lqg.scoreboard.sb3_batch import batched_rows

    run = SimpleNamespace(path_text=f"(training {m.algo})", model=model, normalize_action=True,
                          env=suite.env, meta={**m.design().record(),
                                               "obs_norm": obs_norm_of(norm)})
    return batched_rows(eval_suite(suite), run)


def _callback(ctx: RunContext, venv: Any) -> Any:
    """An SB3 callback that stops at a Ctrl-C (the run's stop flag) and logs the training
    episodes' return (the env's reward, before ``VecNormalize``) and length."""
    import numpy as np
    from stable_baselines3.common.callbacks import BaseCallback

    class Watch(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            self.returns: Any = None
            self.lengths: Any = None
            self.done_returns: list[float] = []
            self.done_lengths: list[int] = []

        def _on_step(self) -> bool:
            reward = venv.get_original_reward()
            if self.returns is None:
                self.returns, self.lengths = np.zeros(len(reward)), np.zeros(len(reward), int)
            self.returns += reward
            self.lengths += 1
            for i in np.flatnonzero(self.locals["dones"]):
                self.done_returns.append(float(self.returns[i]))
                self.done_lengths.append(int(self.lengths[i]))
                self.returns[i], self.lengths[i] = 0.0, 0
            return not ctx.stop.requested

        def take(self) -> dict[str, float]:
            out = {"train_return": float(np.mean(self.done_returns)) if self.done_returns
                   else math.nan,
                   "train_length": float(np.mean(self.done_lengths)) if self.done_lengths
                   else math.nan}
            self.done_returns, self.done_lengths = [], []
            return out

    return Watch()


def train_sb3(ctx: RunContext, m: Method) -> list[Path]:
    """Train run ``ctx.seed`` of ``m`` on ``ctx.suite``; write its model, record and curve."""
    import torch

    from pendulum_lqg.learn.curve import Curve

    steps = ctx.steps or m.steps
    torch.set_num_threads(1)
    model, venv, points = _start(ctx, m)
    curve = Curve(ctx.suite, ctx.path("-curve.csv"), name=ctx.name, log=ctx.log, points=points)
    watch = _callback(ctx, venv)
    done = int(model.num_timesteps)
    with ctx.stop.installed():
        while done < steps:
            chunk = min(ctx.eval_every - done % ctx.eval_every, steps - done)
            model.learn(total_timesteps=chunk, reset_num_timesteps=False, callback=watch,
                        tb_log_name=ctx.name)
            done = int(model.num_timesteps)
            if ctx.stop.requested:
                _checkpoint(ctx, model, venv, curve)
                raise Stopped(done, [ctx.path("-curve.csv"), ctx.path(CHECKPOINT)])
            curve.add(done, curve_rows(model, m, venv, ctx.suite), **watch.take())
            if done < steps:
                _checkpoint(ctx, model, venv, curve)
    _finish(ctx, m, model, venv, curve, steps)
    return [ctx.path(".zip"), ctx.path(".json"), ctx.path("-curve.csv")]


def _start(ctx: RunContext, m: Method) -> tuple[Any, Any, list[dict[str, Any]] | None]:
    """A new model, or the checkpoint's with its env reseeded at its step count (``--resume``)."""
    import importlib

    from stable_baselines3.common.vec_env import VecNormalize

    from pendulum_lqg.boundary.schemas import ALGORITHMS
    from pendulum_lqg.errors import ConfigError

    if not ctx.resume:
        model, venv = build(m, ctx.seed, ctx.suite, tensorboard=ctx.out / "tensorboard")
        _log_into(model, ctx.out)
        return model, venv, None
    saved = ctx.resumed()           # checked at the boundary before any work
    cls = getattr(importlib.import_module(ALGORITHMS[m.algo]), m.algo)
    path = ctx.path("-checkpoint-vecnormalize.pkl")
    try:
        venv = VecNormalize.load(str(path), _design_env(m, ctx.suite))
        path = ctx.path("-checkpoint.zip")
        model = cls.load(str(path), env=venv, device="cpu",
                         tensorboard_log=_tensorboard_folder(ctx.out / "tensorboard"))
        path = ctx.path("-checkpoint-replay.pkl")
        if path.is_file():
            model.load_replay_buffer(str(path))
    except Exception as exc:        # a damaged zip or pickle raises whatever its reader meets
        raise ConfigError(f"--resume: {path}: not a checkpoint of {m.algo} that stable-baselines3 "
                          f"can load ({type(exc).__name__}: {' '.join(str(exc).split())[:120]})"
                          ) from None
    if int(model.num_timesteps) != saved["steps"]:
        raise ConfigError(f"--resume: {ctx.path('-checkpoint.zip')}: holds a model of "
                          f"{int(model.num_timesteps):,} steps, {ctx.path(CHECKPOINT).name}: steps "
                          f"says {saved['steps']:,}; start the run again with --force")
    _log_into(model, ctx.out)
    # loaded with an env, the model resets it on its next learn(): these seeds
    venv.seed(TRAIN_SEED_BASE + 1000 * ctx.seed + int(model.num_timesteps))
    return model, venv, saved["curve"]


def _log_into(model: Any, folder: Path) -> None:
    """SB3's logger writes into the run folder (TensorBoard's files, where it is installed), never
    into an ``SB3-<time>`` folder of the system's temporary folder (SB3's default without one)."""
    if model.tensorboard_log is None:
        from stable_baselines3.common.logger import configure

        model.set_logger(configure(str(folder), []))


def _checkpoint(ctx: RunContext, model: Any, venv: Any, curve: Any) -> None:
    """Model (with its optimiser), ``VecNormalize``'s statistics, SAC's replay buffer, then the
    JSON that names them (written last: a checkpoint exists only once it is whole)."""
    from pendulum_lqg.util.files import replacing

    for suffix, save in ((".zip", model.save), ("-vecnormalize.pkl", venv.save)) + (
            (("-replay.pkl", model.save_replay_buffer),) if hasattr(model, "replay_buffer")
            else ()):
        # whole or not at all, and on any error (a full disk, a file-size limit) no temporary
        # file left behind
        with replacing(ctx.path(f"-checkpoint{suffix}"), where="--out", what="checkpoint") as tmp:
            save(str(tmp))
    write_json(ctx.path(CHECKPOINT), {"algo": type(model).__name__, "steps": int(model.num_timesteps),
                                      "points": len(curve.points), "suite": ctx.suite.fingerprint(),
                                      "wall_seconds": curve.wall_seconds()})


def _finish(ctx: RunContext, m: Method, model: Any, venv: Any, curve: Any, steps: int) -> None:
    """The model (temp + rename), its record, and the checkpoints removed."""
    from pendulum_lqg.envs.registration import ENV_ID
    from pendulum_lqg.scoreboard.sb3 import rl_versions
    from pendulum_lqg.util.files import replacing

    with replacing(ctx.path(".zip"), where="--out", what="model") as tmp:
        model.save(str(tmp))
    done = int(model.num_timesteps)              # PPO rolls out whole n_steps × envs: may exceed
    record = {"method": ctx.method, "seed": ctx.seed, "algo": m.algo, "suite": ctx.suite.name,
              **m.design().record(), "normalize_action": True, "obs_norm": obs_norm_of(venv),
              "wrappers": "VecNormalize(history(native_vec_env))", "env_id": ENV_ID,
              "env": ctx.suite.env, "reward": "v0 (exp(-c / (s·T)))",
              "budget": {"steps": done, "steps_requested": steps, "seed": ctx.seed,
                         "envs": m.envs, "env_seeds": f"{TRAIN_SEED_BASE + 1000 * ctx.seed} + i",
                         "resume_env_seeds": f"{TRAIN_SEED_BASE + 1000 * ctx.seed} + N + i after "
                                             "a resume at step N",
                         "wall_seconds": curve.wall_seconds(), "threads": 1, "kwargs": m.kwargs},
              "curve": {"eval_seed": EVAL_SEED, "episodes": EVAL_EPISODES},
              "versions": {**rl_versions(), **versions()}}
    write_json(ctx.path(".json"), record)
    for suffix in (".json", ".zip", "-vecnormalize.pkl", "-replay.pkl"):
        ctx.path(f"-checkpoint{suffix}").unlink(missing_ok=True)
