"""Augmented Random Search over a linear policy of the y/u history (``ars-history``,
``ars-history-clone``), torch-free, stoppable and resumable bit for bit.

ARS V2-t (Mania, Guy & Recht 2018): a linear policy ``u = s · M (h − μ)/σ`` (``s`` the actuator
limit) of the history ``h`` of the last ``K`` inputs ``z = [p, θ, u_{k−1}/s]`` (3K numbers; the
file form of :mod:`pendulum_lqg.scoreboard.linear`). On a plant of ``p`` outputs and one input
(``train --plant``) ``z = [y, u_{k−1}/s]`` and ``h`` has ``(p + 1)·K`` numbers
(:func:`history_inputs`: read from the suite's plant, never written here). Each iteration draws
``N`` directions ``δ_j ~ N(0, I)`` and plays ``M ± ν δ_j`` as the ``2N`` rows of one native vector
env, direction ``j``'s two rows on the same episode (common random numbers: the ± difference sees
the same noise); the return is the sum of the env's reward (v0, the deep-RL baselines' reward). The
``b`` best directions (by ``max(r₊, r₋)``) update ``M ← M + α/(b σ_R) Σ (r₊ − r₋) δ`` (``σ_R`` the
std of their ``2b`` returns), and ``μ, σ`` are the running mean and std of every history the
rollouts saw (V2: observation normalisation).

Why ``K = 64``: the LQG compensator is a linear policy of a short history, but that form is so
ill-conditioned that a relative perturbation of 1e-4 of its weights loses every episode, while
least-squares clones of the LQG need ``K ≈ 64`` to balance; a search over ``K = 16`` cannot land
in the stabilising set. ``ars-history`` starts from ``M = 0``; ``ars-history-clone`` from a
least-squares clone (``--init FILE``, written by ``pendulum-lqg train ls-clone``): its weights and
its normalisation statistics (as ``μ, σ`` with the clone's sample count), so ARS's first policy is
the clone, and the record says what ARS added to its start.

Seeds: episode ``i`` of run ``S`` is ``episode_seed(run_root(S), i)``; the directions come from
``default_rng([run_root(S), 1])``. A checkpoint (every curve point, and where Ctrl-C stops the
run, at the end of an iteration) holds ``M``, the running statistics, the generator's state and the
counters: ``--resume`` continues the same seed stream and ends at the same controller.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.learn.methods import ARS_STEPS
from pendulum_lqg.learn.runs import RunContext, Stopped, run_root, versions, write_json

CHECKPOINT = "-checkpoint.json"


@dataclass(frozen=True)
class ARSSettings:
    """The hyperparameters of one ARS run (see the module docstring)."""

    alpha: float = 0.02
    nu: float = 0.03
    frames: int = 64
    directions: int = 16
    top: int = 8
    steps: int = ARS_STEPS                  # what the committed runs used


class RunningStats:
    """Running mean and variance of the histories seen (Chan et al.'s parallel update)."""

    def __init__(self, size: int, *, n: int = 0, mean: Any = None, m2: Any = None) -> None:
        self.n = int(n)
        self.mean = np.zeros(size) if mean is None else np.asarray(mean, dtype=float)
        self.m2 = np.zeros(size) if m2 is None else np.asarray(m2, dtype=float)

    def add(self, rows: np.ndarray) -> None:
        if rows.shape[0] == 0:
            return
        k, mean = rows.shape[0], rows.mean(axis=0)
        m2 = ((rows - mean) ** 2).sum(axis=0)
        total = self.n + k
        delta = mean - self.mean
        self.mean = self.mean + delta * k / total
        self.m2 = self.m2 + m2 + delta ** 2 * self.n * k / total
        self.n = total

    def std(self) -> np.ndarray:
        """The std (1 before two samples; at least 1e-3: a constant input stays finite)."""
        if self.n < 2:
            return np.ones_like(self.mean)
        return np.maximum(np.sqrt(self.m2 / self.n), 1e-3)


def ars_update(M: np.ndarray, deltas: np.ndarray, r_plus: np.ndarray, r_minus: np.ndarray, *,
               alpha: float, top: int) -> np.ndarray:
    """ARS's step: the ``top`` directions by ``max(r₊, r₋)``, ``M + α/(b σ_R) Σ (r₊ − r₋) δ``."""
    order = np.argsort(-np.maximum(r_plus, r_minus), kind="stable")[:top]
    sigma = float(np.std(np.concatenate([r_plus[order], r_minus[order]])))
    step = (r_plus[order] - r_minus[order]) @ deltas[order]
    return M + alpha / (top * (sigma if sigma > 0 else 1.0)) * step


def ars_rollouts(env: Any, policy: Any, seeds: list[int], stats: RunningStats,
                 ) -> tuple[np.ndarray, np.ndarray]:
    """Every row's return (the sum of the env's rewards until its episode ends) and length; the
    histories seen go into ``stats``."""
    obs, _ = env.reset(seed=seeds)
    n = len(seeds)
    policy.reset(n)
    alive, returns, lengths = np.ones(n, dtype=bool), np.zeros(n), np.zeros(n, dtype=int)
    while alive.any():
        u = policy.act(obs)
        stats.add(policy.inputs[alive])
        obs, reward, terminated, truncated, _ = env.step(u)
        returns[alive] += reward[alive]
        lengths += alive
        alive &= ~(terminated | truncated)
    return returns, lengths


def renormalized(M: np.ndarray, bias: float, mean0: np.ndarray, std0: np.ndarray,
                 stats: RunningStats) -> tuple[np.ndarray, float]:
    """``M`` and the bias re-expressed in the statistics' new coordinates, the policy unchanged:
    ``M (h − μ₀)/σ₀ + b = M' (h − μ₁)/σ₁ + b'`` for every ``h`` gives ``M' = M σ₁/σ₀`` and
    ``b' = b + M · (μ₁ − μ₀)/σ₀``."""
    std1 = stats.std()
    return M * std1 / std0, float(bias + M @ ((stats.mean - mean0) / std0))


class ARSState:
    """Everything an ARS run needs to continue: ``M``, the statistics, the direction generator's
    state, the counters and the training log since the last curve point."""

    def __init__(self, s: ARSSettings, seed: int, start: dict[str, Any] | None,
                 inputs: int = 3) -> None:
        size = inputs * s.frames
        self.M, self.stats = np.zeros(size), RunningStats(size)
        self.start, self.bias = "zero", 0.0
        if start is not None:
            self.bias = float(start["bias"])
            self.M = np.asarray(start["weights"], dtype=float)
            self.stats = RunningStats(size, n=start["n"], mean=start["mean"],
                                      m2=np.square(start["std"]) * start["n"])
            self.start = start["path"]
        self.rng = np.random.default_rng([run_root(seed), 1])       # the directions' stream
        self.steps = self.episodes = self.iteration = 0
        self.log_return = self.log_length = 0.0
        self.log_count = 0

    def to_dict(self) -> dict[str, Any]:
        return {"M": self.M.tolist(), "n": self.stats.n, "mean": self.stats.mean.tolist(),
                "m2": self.stats.m2.tolist(), "rng": self.rng.bit_generator.state,
                "steps": self.steps, "episodes": self.episodes, "iteration": self.iteration,
                "log": [self.log_return, self.log_length, self.log_count], "start": self.start,
                "bias": self.bias}

    def load(self, d: dict[str, Any]) -> None:
        self.M = np.asarray(d["M"], dtype=float)
        self.stats = RunningStats(self.M.size, n=d["n"], mean=d["mean"], m2=d["m2"])
        self.rng.bit_generator.state = d["rng"]
        self.steps, self.episodes, self.iteration = d["steps"], d["episodes"], d["iteration"]
        self.log_return, self.log_length, self.log_count = d["log"]
        self.start, self.bias = d["start"], d["bias"]

    def take_log(self) -> dict[str, float]:
        """The mean return and length of the training episodes since the last call."""
        n = self.log_count
        out = {"train_return": self.log_return / n if n else math.nan,
               "train_length": self.log_length / n if n else math.nan}
        self.log_return = self.log_length = 0.0
        self.log_count = 0
        return out


#: The clone's start: perturbations ν·δ (norm ≈ ν·√(3K)) must stay inside the stabilising set
#: around the clone's weights, which is narrow (the compensator's form is ill-conditioned), and a
#: step (norm ≈ α·√(3K)) far below the weights' own norm; the pilot chooses within this scale.
CLONE_SETTINGS = ARSSettings(alpha=2e-4, nu=5e-4)


def settings_of(ctx: RunContext) -> ARSSettings:
    """The run's settings: the method's defaults, with ``--alpha``, ``--nu``, ``--frames`` and
    ``--steps`` where given."""
    from dataclasses import replace

    base = CLONE_SETTINGS if ctx.method == "ars-history-clone" else ARSSettings()
    chosen = {k: ctx.options[k] for k in ("alpha", "nu", "frames") if ctx.options.get(k)}
    if ctx.steps is not None:
        chosen["steps"] = ctx.steps
    return replace(base, **chosen)


def history_inputs(suite: Any) -> int:
    """The inputs per frame ``z = [y, u_{k−1}/s]`` on ``suite``'s plant: its outputs + 1 (3 on
    the cart-pole)."""
    return int(suite.plants()[1].layout(suite.config.scenario).p) + 1


def load_start(path: Path, frames: int, inputs: int = 3) -> dict[str, Any]:
    """The clone a run starts from: a history controller file of ``frames`` frames of
    ``inputs`` numbers each."""
    from pendulum_lqg.boundary.fields import Where, integer, table
    from pendulum_lqg.boundary.schemas import linear_controller, linear_inputs

    doc = linear_controller(path, where_text="--init")
    if doc["form"] != "history" or doc["history"]["frames"] != frames:
        raise ConfigError(f"--init: {path}: expected a history controller of {frames} frames "
                          "(pendulum-lqg train ls-clone), got "
                          f"{doc['form']} form" + (f" of {doc['history']['frames']} frames"
                                                   if doc["form"] == "history" else ""))
    if linear_inputs(doc) != inputs:
        raise ConfigError(f"--init: {path}: expected {inputs} inputs per frame (the plant's "
                          f"{inputs - 1} outputs and u), got {linear_inputs(doc)}")
    h = doc["history"]
    where = Where(f"--init: {path}", ("training",))
    training = where.check(doc.get("training") or {}, table)
    n = where.get(training, "samples", integer(0), default=2)
    budget = where.get(training, "budget", table, default={})
    where.at("budget").get(budget, "steps", integer(0), default=0)
    return {"weights": h["weights"], "bias": h["bias"], "mean": h["mean"], "std": h["std"],
            "n": max(n, 2), "path": str(path), "budget": budget}


def train_ars(ctx: RunContext) -> list[Path]:
    """Train ARS run ``ctx.seed``; write its controller and curve (and checkpoints) to ``ctx.out``."""
    from pendulum_lqg.core.rules import limits
    from pendulum_lqg.envs.vector import CartPoleLQGVectorEnv
    from pendulum_lqg.learn.curve import Curve

    s = settings_of(ctx)
    start = None
    if ctx.method == "ars-history-clone":
        if not ctx.options.get("init"):
            raise ConfigError("--init: ars-history-clone starts from a clone: give --init FILE "
                              "(a controller written by pendulum-lqg train ls-clone)")
        start = ctx.options.get("start") or load_start(Path(ctx.options["init"]), s.frames,
                                                       history_inputs(ctx.suite))
    scale = float(limits(ctx.suite.plants()[1], ctx.suite.config.scenario)[2])
    inputs = history_inputs(ctx.suite)
    state = ARSState(s, ctx.seed, start, inputs)
    points = None
    if ctx.resume:
        saved = ctx.resumed()       # checked at the boundary before any work
        state.load(saved["state"])
        points = saved["curve"]
    curve = Curve(ctx.suite, ctx.path("-curve.csv"), name=ctx.name, log=ctx.log, points=points)
    if not ctx.resume:                         # the start itself: what ARS adds is measured from it
        curve.add_linear(0, _document(ctx, s, state, curve, scale, start))
    env = CartPoleLQGVectorEnv(2 * s.directions, nthread=1, **ctx.suite.env)
    try:
        _iterate(ctx, s, state, env, curve, scale, start, inputs)
    finally:
        env.close()
    write_json(ctx.path(".json"), _document(ctx, s, state, curve, scale, start))
    ctx.path(CHECKPOINT).unlink(missing_ok=True)
    return [ctx.path(".json"), ctx.path("-curve.csv")]


def _iterate(ctx: RunContext, s: ARSSettings, state: ARSState, env: Any, curve: Any,
             scale: float, start: dict[str, Any] | None, inputs: int = 3) -> None:
    """ARS iterations until ``s.steps``; a curve point and a checkpoint every ``ctx.eval_every``
    steps; a Ctrl-C stops after the iteration it interrupted, with a checkpoint."""
    from pendulum_lqg.core.seeding import episode_seeds
    from pendulum_lqg.scoreboard.linear import HistoryPolicy

    size = inputs * s.frames
    with ctx.stop.installed():
        while state.steps < s.steps:
            if ctx.stop.requested:
                _checkpoint(ctx, s, state, curve)
                raise Stopped(state.steps, [ctx.path("-curve.csv"), ctx.path(CHECKPOINT)])
            deltas = state.rng.standard_normal((s.directions, size))
            weights = np.vstack([state.M + s.nu * deltas, state.M - s.nu * deltas])
            mean0, std0 = state.stats.mean.copy(), state.stats.std()
            policy = HistoryPolicy(weights, mean0, std0, frames=s.frames, action_scale=scale,
                                   u_max=scale, bias=state.bias, outputs=inputs - 1)
            pair = episode_seeds(run_root(ctx.seed),
                                 range(state.episodes, state.episodes + s.directions))
            returns, lengths = ars_rollouts(env, policy, pair + pair, state.stats)
            before = state.steps
            state.steps += int(lengths.sum())
            state.episodes += s.directions
            state.iteration += 1
            state.log_return += float(returns.sum())
            state.log_length += float(lengths.sum())
            state.log_count += returns.size
            M = ars_update(state.M, deltas, returns[:s.directions], returns[s.directions:],
                           alpha=s.alpha, top=s.top)
            state.M, state.bias = renormalized(M, state.bias, mean0, std0, state.stats)
            if state.steps // ctx.eval_every > before // ctx.eval_every or state.steps >= s.steps:
                curve.add_linear(state.steps, _document(ctx, s, state, curve, scale, start),
                                 **state.take_log())
                if state.steps < s.steps:
                    _checkpoint(ctx, s, state, curve)


def _checkpoint(ctx: RunContext, s: ARSSettings, state: ARSState, curve: Any) -> None:
    write_json(ctx.path(CHECKPOINT), {"settings": asdict(s), "suite": ctx.suite.fingerprint(),
                                      "points": len(curve.points), "state": state.to_dict(),
                                      "wall_seconds": curve.wall_seconds()})


def _document(ctx: RunContext, s: ARSSettings, state: ARSState, curve: Any, scale: float,
              start: dict[str, Any] | None) -> dict[str, Any]:
    """The controller file of the current ``M`` with its training record."""
    from pendulum_lqg.learn.runs import EVAL_EPISODES, EVAL_SEED
    from pendulum_lqg.scoreboard.linear import controller_file

    params = {"frames": s.frames, "weights": state.M.tolist(), "bias": state.bias,
              "mean": state.stats.mean.tolist(), "std": state.stats.std().tolist()}
    start_steps = int((start or {}).get("budget", {}).get("steps", 0))
    training = {"algo": "ARS V2-t", "settings": asdict(s), "iterations": state.iteration,
                "directions_per_iteration": s.directions, "start": state.start,
                "suite": ctx.suite.name,
                "budget": {"steps": state.steps, "stepped_steps": state.steps,
                           "logged_steps": 0, "start_steps": start_steps,
                           "episodes": state.episodes, "root_seed": run_root(ctx.seed),
                           "env_seeds": "episode_seed(root, i)",
                           "directions_seed": f"default_rng([{run_root(ctx.seed)}, 1])"},
                "resume": "the same seed stream: episodes, directions and statistics continue "
                          "from the checkpoint exactly",
                "curve": {"eval_seed": EVAL_SEED, "episodes": EVAL_EPISODES},
                "wall_seconds": curve.wall_seconds(), "versions": versions()}
    return controller_file("history", params, action_scale=scale, env=ctx.suite.env,
                           method=ctx.method, seed=ctx.seed, training=training)
