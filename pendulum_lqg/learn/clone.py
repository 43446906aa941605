"""``ls-clone``: a linear policy of the y/u history fitted by least squares to the actions of the
identified LQG on closed-loop data.

The teacher is the last round of the closed-loop identification (``sysid-lqg``,
:mod:`pendulum_lqg.learn.sysid_lqg`): a certainty-equivalent LQG controller ``u = f(z_k, ξ_k)``.
It is played on ``E`` episodes of the suite's env (native vector env, episode ``i`` seeded
``episode_seed(run_root(S) + 500, i)``: neither the identification's episodes nor another run's),
with a white dither of ``DITHER`` N added to the applied force so that the histories explore
around the closed loop. Every period logs the history ``h_k`` of the last ``K`` inputs
``z = [p, θ, u_{k−1}/s]`` (the applied force, ``s`` the actuator limit) and the teacher's action
``u_k / s``; the clone is ``v = w · (h − μ)/σ`` with ``μ, σ`` the samples' mean and std and ``w``
the least-squares solution over the samples logged before each episode ended.

Why a long history: a stable LQG compensator is an infinite impulse response in ``z``; a history
of ``K`` periods truncates it after ``K·T``, and the reference's slowest estimator mode decays
over about 70 periods (docs/leaderboard.md, the reference controller's memory): short clones lose
episodes, clones of ``K ≥ 64`` cover that memory. The clone is the stabilising start of
``ars-history-clone``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from pendulum_lqg.learn.runs import RunContext, run_root, versions, write_json

#: History length of the clone (and of the ARS runs that start from it).
FRAMES = 64
#: Std of the white dither added to the teacher's force [N].
DITHER = 1.0
#: Default closed-loop data of the fit, in logged env steps.
CLONE_STEPS = 20_000


def closed_loop_samples(teacher: dict[str, Any], suite: Any, *, root: int, steps: int,
                        frames: int, rng: np.random.Generator,
                        ) -> tuple[np.ndarray, np.ndarray, int]:
    """``(H, t, stepped)``: the histories (samples, 3·frames) and the teacher's actions ``u/s``
    (samples,) logged in closed loop until ``steps`` samples, and the env steps taken."""
    from pendulum_lqg.core.rules import limits, saturate
    from pendulum_lqg.core.seeding import episode_seeds
    from pendulum_lqg.envs.vector import CartPoleLQGVectorEnv
    from pendulum_lqg.scoreboard.linear import HistoryPolicy, linear_policy

    u_max = float(limits(suite.plants()[1], suite.config.scenario)[2])
    rows, episodes, stepped = 8, 0, 0
    H: list[np.ndarray] = []
    t: list[np.ndarray] = []
    env = CartPoleLQGVectorEnv(rows, nthread=1, **suite.env)
    try:
        while sum(x.size for x in t) < steps:
            policy = linear_policy(teacher, u_max)
            recorder = HistoryPolicy(np.zeros(3 * frames), np.zeros(3 * frames),
                                     np.ones(3 * frames), frames=frames, action_scale=u_max,
                                     u_max=u_max)
            obs, _ = env.reset(seed=episode_seeds(root, range(episodes, episodes + rows)))
            policy.reset(rows)
            recorder.reset(rows)
            alive = np.ones(rows, dtype=bool)
            while alive.any():
                u = policy.act(obs)
                recorder.act(obs)                      # the history, its previous force applied
                H.append(recorder.inputs[alive].copy())
                t.append(u[alive] / u_max)
                applied = saturate(u + DITHER * rng.standard_normal(rows), u_max)
                policy.u, recorder.u = applied.copy(), applied.copy()
                obs, _, terminated, truncated, _ = env.step(applied)
                stepped += int(alive.sum())
                alive &= ~(terminated | truncated)
            episodes += rows
    finally:
        env.close()
    return np.concatenate(H)[:steps], np.concatenate(t)[:steps], stepped


def fit_clone(H: np.ndarray, t: np.ndarray) -> dict[str, Any]:
    """The history form ``{frames, weights, bias, mean, std}`` of the least-squares clone."""
    mean, std = H.mean(axis=0), np.maximum(H.std(axis=0), 1e-3)
    w, *_ = np.linalg.lstsq((H - mean) / std, t - t.mean(), rcond=None)
    return {"frames": H.shape[1] // 3, "weights": w.tolist(), "bias": float(t.mean()),
            "mean": mean.tolist(), "std": std.tolist()}


def train_clone(ctx: RunContext) -> list[Path]:
    """Identify (``sysid-lqg``'s rounds), clone the last round's LQG, write the clone."""
    from pendulum_lqg.core.rules import limits
    from pendulum_lqg.errors import ConfigError
    from pendulum_lqg.learn.curve import Curve
    from pendulum_lqg.learn.runs import EVAL_EPISODES, EVAL_SEED
    from pendulum_lqg.learn.sysid_lqg import identified_rounds, round_document
    from pendulum_lqg.scoreboard.linear import controller_file

    if ctx.resume:
        raise ConfigError(f"--resume: {ctx.method} is not resumed (identification and fit take "
                          "about a minute); start it again with --force")
    frames = int(ctx.options.get("frames") or FRAMES)
    curve = Curve(ctx.suite, ctx.path("-curve.csv"), name=ctx.name, log=ctx.log)
    sysid = ctx.method.replace("ls-clone", "sysid-lqg")
    rounds = identified_rounds(ctx, steps=None)      # --steps is the fit's samples
    if not rounds:
        raise ConfigError(f"{ctx.name}: the identification gave no controller")
    teacher = round_document(ctx, rounds[-1], 0.0, len(rounds))
    rng = np.random.default_rng([run_root(ctx.seed), 3])           # the dither's stream
    H, t, stepped = closed_loop_samples(teacher, ctx.suite, root=run_root(ctx.seed) + 500,
                                        steps=ctx.steps or CLONE_STEPS, frames=frames, rng=rng)
    params = fit_clone(H, t)
    logged = int(rounds[-1].logged_steps) + len(t)
    scale = float(limits(ctx.suite.plants()[1], ctx.suite.config.scenario)[2])
    training = {"algo": "least-squares clone of the identified LQG", "teacher": sysid,
                "suite": ctx.suite.name, "frames": frames, "dither": DITHER,
                "samples": len(t), "fit_rms": float(np.sqrt(np.mean(
                    ((H - params["mean"]) / params["std"] @ params["weights"]
                     + params["bias"] - t) ** 2))),
                "budget": {"steps": logged, "logged_steps": logged,
                           "stepped_steps": int(rounds[-1].stepped_steps) + stepped,
                           "identification_steps": int(rounds[-1].logged_steps),
                           "clone_steps": len(t), "root_seed": run_root(ctx.seed),
                           "env_seeds": "episode_seed(root + 500, i)"},
                "curve": {"eval_seed": EVAL_SEED, "episodes": EVAL_EPISODES},
                "wall_seconds": 0.0, "versions": versions()}
    doc = controller_file("history", params, action_scale=scale, env=ctx.suite.env,
                          method=ctx.method, seed=ctx.seed, training=training)
    curve.add_linear(logged, doc)
    doc["training"]["wall_seconds"] = curve.wall_seconds()
    write_json(ctx.path(".json"), doc)
    return [ctx.path(".json"), ctx.path("-curve.csv")]
