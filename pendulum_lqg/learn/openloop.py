"""``sysid-openloop``: nominal identification from open-loop bursts, then LQG — kept as the
evidence of what open-loop data gives (the earlier ``sysid-lqg`` recipe, renamed).

Open-loop episodes of ``H = 30`` periods (the pole falls from θ₀ in about half a second: no
stabilising controller is assumed), the input a random ±``u_exc`` sequence (``u_exc`` = half the
actuator limit, so the actuator never saturates and the logged input is the applied one), samples
after a failure dropped; least squares of the Markov parameters and the free response, the
structured model in the basis ``[y, ẏ]``, the noise covariances, then LQG (discrete LQR of the
sampled cost and the steady-state Kalman filter, :func:`~pendulum_lqg.design.sysid.lqg_gains`)
written as a state-space controller. The curve identifies from the first 5k, 10k, 20k, 50k, 100k,
200k, 500k and 1M logged steps (those up to ``--steps``, and ``--steps`` itself); the file keeps
the largest budget's controller.

Why it is not the method to use: 0.3 s bursts from one x₀ cannot separate the cart's response to
θ from the velocity terms, so the identified dynamics vary from seed to seed while the noise
covariances come out right; ``sysid-lqg`` (closed-loop identification) is the method.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from pendulum_lqg.learn.runs import RunContext, Stopped, run_root, versions, write_json

BUDGETS = (5_000, 10_000, 20_000, 50_000, 100_000, 200_000, 500_000, 1_000_000)
HORIZON = 30
CHECKPOINT = "-checkpoint.json"


def u_max_of(suite: Any) -> float:
    """The suite's actuator limit [N] (the nominal plant's, as the designs see it)."""
    from pendulum_lqg.core.rules import limits

    return float(limits(suite.plants()[1], suite.config.scenario)[2])


def sysid_data(seed: int, suite: Any, episodes: int, horizon: int, u_exc: float, chunk: int = 500,
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``Y`` (E, H, 2), ``U`` (E, H, 1) and the mask of samples logged before each episode ended,
    of ``episodes`` open-loop episodes driven by random ±``u_exc`` inputs."""
    from pendulum_lqg.core.rules import saturate
    from pendulum_lqg.core.seeding import episode_seeds
    from pendulum_lqg.envs.vector import CartPoleLQGVectorEnv

    rng = np.random.default_rng([run_root(seed), 2])       # the excitation's stream
    u_max = u_max_of(suite)
    Y, U = np.zeros((episodes, horizon, 2)), np.zeros((episodes, horizon, 1))
    valid = np.zeros((episodes, horizon), dtype=bool)
    for start in range(0, episodes, chunk):
        n = min(chunk, episodes - start)
        env = CartPoleLQGVectorEnv(n, nthread=1, **suite.env)
        obs, _ = env.reset(seed=episode_seeds(run_root(seed), range(start, start + n)))
        alive = np.ones(n, dtype=bool)
        for k in range(horizon):
            rows = slice(start, start + n)
            Y[rows, k], valid[rows, k] = obs, alive
            u = saturate(u_exc * rng.choice([-1.0, 1.0], size=n), u_max)
            U[rows, k, 0] = u
            obs, _, terminated, truncated, _ = env.step(u)
            alive &= ~(terminated | truncated)
        env.close()
    return Y, U, valid


def sysid_controller(Y: np.ndarray, U: np.ndarray, valid: np.ndarray, suite: Any,
                     ) -> tuple[dict[str, Any], Any]:
    """The state-space LQG controller designed on the model identified from the data, and the
    model."""
    from pendulum_lqg.design.sysid import identify, lqg_gains
    from pendulum_lqg.scoreboard.linear import lqg_state_space

    sc = suite.config.scenario
    model = identify(Y, U, valid, float(sc.control_period))
    K, L = lqg_gains(model, np.diag(sc.cost_Q), np.array([[sc.cost_R]]))
    return lqg_state_space(model.Phi, model.Gamma, model.C, K, L), model


def budgets_for(steps: int | None) -> tuple[int, ...]:
    """The curve's budgets: :data:`BUDGETS` up to ``steps``, then ``steps`` (default 1 000 000)."""
    if steps is None:
        return BUDGETS
    return (*(b for b in BUDGETS if b < steps), steps)


def train_openloop(ctx: RunContext) -> list[Path]:
    """Identify from open-loop bursts at each budget; write the largest budget's controller."""
    from pendulum_lqg.errors import ConfigError, PendulumLQGError
    from pendulum_lqg.learn.curve import Curve

    budgets, suite = budgets_for(ctx.steps), ctx.suite
    u_exc = 0.5 * u_max_of(suite)
    done, points = 0, None
    if ctx.resume:
        saved = ctx.resumed()       # checked at the boundary before any work
        done, points = saved["done"], saved["curve"]
    curve = Curve(suite, ctx.path("-curve.csv"), name=ctx.name, log=ctx.log, points=points)
    # episodes that fail early log fewer than H steps: a fifth more episodes than H·E covers
    Y, U, valid = sysid_data(ctx.seed, suite, -(-max(budgets) * 6 // (5 * HORIZON)), HORIZON,
                             u_exc)
    steps_of = np.cumsum(valid.sum(axis=1))                  # logged steps of the first e episodes
    doc: dict[str, Any] = {}
    with ctx.stop.installed():
        for i, budget in enumerate(budgets):
            e = min(int(np.searchsorted(steps_of, budget)) + 1, len(steps_of))
            try:
                params, model = sysid_controller(Y[:e], U[:e], valid[:e], suite)
            except (PendulumLQGError, np.linalg.LinAlgError, ValueError) as exc:
                ctx.log(f"{ctx.name}: {budget:,} steps: no design "
                        f"({' '.join(str(exc).split())[:120]})")
                continue
            doc = _document(ctx, params, model, u_exc, int(steps_of[e - 1]), e, curve)
            if i >= done:
                curve.add_linear(int(steps_of[e - 1]), doc)
            if ctx.stop.requested and i + 1 < len(budgets):
                write_json(ctx.path(CHECKPOINT), {"budgets": list(budgets), "done": i + 1,
                                                  "points": len(curve.points),
                                                  "suite": suite.fingerprint()})
                raise Stopped(int(steps_of[e - 1]), [ctx.path("-curve.csv"),
                                                     ctx.path(CHECKPOINT)])
    if not doc:
        raise ConfigError(f"{ctx.name}: no budget gave a design")
    doc["training"]["wall_seconds"] = curve.wall_seconds()
    write_json(ctx.path(".json"), doc)
    ctx.path(CHECKPOINT).unlink(missing_ok=True)
    return [ctx.path(".json"), ctx.path("-curve.csv")]


def _document(ctx: RunContext, params: dict[str, Any], model: Any, u_exc: float, steps: int,
              episodes: int, curve: Any) -> dict[str, Any]:
    from pendulum_lqg.learn.runs import EVAL_EPISODES, EVAL_SEED
    from pendulum_lqg.scoreboard.linear import controller_file

    training = {"algo": "nominal sysid from open-loop bursts + LQG", "horizon": HORIZON,
                "u_exc": u_exc, "suite": ctx.suite.name,
                "budget": {"steps": steps, "logged_steps": steps, "stepped_steps": steps,
                           "episodes": episodes, "root_seed": run_root(ctx.seed),
                           "env_seeds": "episode_seed(root, i)"},
                "model": {"A": model.A.tolist(), "B": model.B.tolist(),
                          "W": np.diag(model.W).tolist(), "V": np.diag(model.V).tolist()},
                "curve": {"eval_seed": EVAL_SEED, "episodes": EVAL_EPISODES},
                "wall_seconds": curve.wall_seconds(), "versions": versions()}
    return controller_file("state_space", params, action_scale=1.0, env=ctx.suite.env,
                           method=ctx.method, seed=ctx.seed, training=training)
