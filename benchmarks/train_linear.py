"""Train the control literature's two baselines — ARS and nominal system identification — without torch.

::

    python benchmarks/train_linear.py ars-history --seed 3     # one run (also: train_agents.py ars-history)
    python benchmarks/train_linear.py sysid-lqg --seed 3
    python benchmarks/train_linear.py ars-history --seed 100 --steps 200000 --alpha 0.02   # a pilot run

One run writes, in ``--out`` (default ``experiments/agents/models``), ``METHOD-seedS.json`` — the
controller (:mod:`pendulum_lqg.scoreboard.linear`, scored by ``pendulum-lqg score --agent
linear:METHOD-seedS.json``) with its training record — and ``METHOD-seedS-curve.csv``, the learning
curve with the columns of ``train_agents.py``'s (``env_steps, wall_seconds, success_rate,
score_mean, score_ci_lo, score_ci_hi``) on the same 20 fixed episodes (``train_agents.EVAL_SEED``,
never a suite's seed), played through the scorer's path.

Both train on the ``lecture`` suite's ``[env]`` in the native vector env
(:class:`~pendulum_lqg.envs.vector.CartPoleLQGVectorEnv`, one batched simulator), observing only
``y = [p, θ]``. Run seed ``S`` has the root ``TRAIN_SEED_BASE + 1000·S`` (``train_agents.py``'s);
episode ``i`` of the run is seeded ``episode_seed(root, i)`` (a ``SeedSequence`` child), so no run
meets another run's or a suite's episodes. The data budget is the env steps of the episodes used.

**ars-history** — Augmented Random Search (Mania, Guy & Recht 2018, ARS V2-t): a linear policy
``u = s · M (h − μ)/σ`` (``s`` the actuator limit) of the history ``h`` of the last ``K`` inputs
``[p, θ, u_{k−1}/s]``, ``M`` starting at 0. Each iteration draws ``N`` directions ``δ_j ~ N(0, I)``
and plays ``M ± ν δ_j`` as the ``2N`` rows of one vector env, direction ``j``'s two rows on the
same episode (common random numbers: the ± difference sees the same noise); the return is the sum
of the env's reward (v0, the deep-RL baselines' reward). The ``b`` best directions (by
``max(r₊, r₋)``) update ``M ← M + α/(b σ_R) Σ (r₊ − r₋) δ`` (``σ_R`` the std of their ``2b``
returns), and ``μ, σ`` are the running mean and std of every history the rollouts saw (V2).
Settings ``N = 16, b = 8``; ``α, ν, K`` below; budget 1 000 000 env steps, a curve point every
50 000.

*Pilot* (planned, not yet run: pilot seeds 100 and 101 only, 300 000 steps each):
``α ∈ {0.02, 0.05}``, ``ν ∈ {0.02, 0.05}``, ``K ∈ {4, 16}`` (8 settings); the selection rule is
the highest mean over the two seeds of the last curve point's failure-aware score, ties broken by
success rate. Until it has run, the settings are the unpiloted defaults ``α = 0.02, ν = 0.05,
K = 16`` (:class:`ARSSettings`). ``--alpha``, ``--nu``, ``--frames`` set a pilot run's.

**sysid-lqg** — nominal identification (:mod:`pendulum_lqg.design.sysid`): open-loop episodes of
``H = 30`` periods (the pole falls from θ₀ in about half a second: no stabilising controller is
assumed), the input a random ±``u_exc`` sequence (``u_exc`` = half the actuator limit, so the
actuator never saturates and the logged input is the applied one), samples after a failure
dropped; least squares of the Markov parameters and the free response, the structured model in the
basis ``[y, ẏ]``, the noise covariances, then LQG (discrete LQR of the sampled cost and the
steady-state Kalman filter, :func:`~pendulum_lqg.design.sysid.lqg_gains`) written as a state-space
controller. The curve identifies from the first 5k, 10k, 20k, 50k, 100k, 200k, 500k and 1M logged steps; the
file keeps the largest budget's controller.
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from train_agents import EVAL_EPISODES, EVAL_SEED, TRAIN_SEED_BASE, eval_suite

METHODS = {"ars-history": "ARS V2-t: random search over a linear policy of the last K (y, u)",
           "sysid-lqg": "least-squares identification from open-loop episodes, then LQG"}
SYSID_BUDGETS = (5_000, 10_000, 20_000, 50_000, 100_000, 200_000, 500_000, 1_000_000)


@dataclass(frozen=True)
class ARSSettings:
    """The hyperparameters of one ARS run (see the module docstring)."""

    alpha: float = 0.02
    nu: float = 0.05
    frames: int = 16
    directions: int = 16
    top: int = 8
    steps: int = 1_000_000
    eval_every: int = 50_000


def run_root(seed: int) -> int:
    return TRAIN_SEED_BASE + 1000 * seed


class Curve:
    """The learning curve: the controller's figures on the curve's 20 episodes, through the scorer's
    batch path (:func:`~pendulum_lqg.scoreboard.linear.linear_rows`)."""

    def __init__(self, suite: Any) -> None:
        from pendulum_lqg.scoreboard import episodes as ep

        self.suite = eval_suite(suite)
        self.reference = ep.policy_rows(self.suite, suite.reference, nthread=1)
        self.points: list[dict[str, Any]] = []
        self.t0 = time.perf_counter()

    def add(self, env_steps: int, doc: dict[str, Any], label: str) -> None:
        from pendulum_lqg.scoreboard.linear import linear_rows
        from pendulum_lqg.scoreboard.score import success_figures
        from pendulum_lqg.scoreboard.stats import failure_aware_figures

        rows = linear_rows(self.suite, doc, name=f"({label})", nthread=1)
        fig = failure_aware_figures(rows, self.reference)
        lo, hi = fig["score_ci"]
        self.points.append({"env_steps": int(env_steps),
                            "wall_seconds": round(time.perf_counter() - self.t0, 1),
                            "success_rate": success_figures(rows)["success_rate"],
                            "score_mean": fig["score_mean"], "score_ci_lo": lo, "score_ci_hi": hi})
        p = self.points[-1]
        print(f"{label}: {env_steps:,} steps, success {p['success_rate']:.2f}, score "
              f"{p['score_mean']:.3f}", flush=True)


def _u_max(suite: Any) -> float:
    from pendulum_lqg.core.rules import limits

    return float(limits(suite.plants()[1], suite.config.scenario)[2])


def _controller(method: str, seed: int, suite: Any, form: str, params: dict[str, Any],
                scale: float, training: dict[str, Any]) -> dict[str, Any]:
    from pendulum_lqg.scoreboard.linear import controller_file

    return controller_file(form, params, action_scale=scale, env=suite.env, method=method,
                           seed=seed, training=training)


# ---- ARS ------------------------------------------------------------------------------------------
class RunningStats:
    """Running mean and variance of the histories seen (Chan et al.'s parallel update)."""

    def __init__(self, size: int) -> None:
        self.n, self.mean, self.m2 = 0, np.zeros(size), np.zeros(size)

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
    order = np.argsort(-np.maximum(r_plus, r_minus))[:top]
    sigma = float(np.std(np.concatenate([r_plus[order], r_minus[order]])))
    step = (r_plus[order] - r_minus[order]) @ deltas[order]
    return M + alpha / (top * (sigma if sigma > 0 else 1.0)) * step


def ars_rollouts(env: Any, policy: Any, seeds: list[int], stats: RunningStats,
                 ) -> tuple[np.ndarray, int]:
    """Every row's return (the sum of the env's rewards until its episode ends) and the env steps
    used; the histories seen go into ``stats``."""
    obs, _ = env.reset(seed=seeds)
    n = len(seeds)
    policy.reset(n)
    alive, returns, steps = np.ones(n, dtype=bool), np.zeros(n), 0
    while alive.any():
        u = policy.act(obs)
        stats.add(policy.inputs[alive])
        obs, reward, terminated, truncated, _ = env.step(u)
        returns[alive] += reward[alive]
        steps += int(alive.sum())
        alive &= ~(terminated | truncated)
    return returns, steps


def train_ars(seed: int, out: Path, s: ARSSettings, method: str = "ars-history") -> Path:
    from pendulum_lqg.core.seeding import episode_seeds
    from pendulum_lqg.envs.vector import CartPoleLQGVectorEnv
    from pendulum_lqg.scoreboard.linear import HistoryPolicy
    from pendulum_lqg.scoreboard.suites import load_suite

    suite = load_suite("lecture")
    scale = _u_max(suite)
    size = 3 * s.frames
    env = CartPoleLQGVectorEnv(2 * s.directions, nthread=1, **suite.env)
    rng = np.random.default_rng([run_root(seed), 1])       # the directions' stream
    M, stats = np.zeros(size), RunningStats(size)
    curve, name = Curve(suite), f"{method}-seed{seed}"
    steps, episodes, iteration, next_eval = 0, 0, 0, s.eval_every

    def doc() -> dict[str, Any]:
        params = {"frames": s.frames, "weights": M.tolist(), "bias": 0.0,
                  "mean": stats.mean.tolist(), "std": stats.std().tolist()}
        training = {"algo": "ARS V2-t", "settings": s.__dict__, "iterations": iteration,
                    "budget": {"steps": steps, "episodes": episodes, "root_seed": run_root(seed),
                               "env_seeds": "episode_seed(root, i)"},
                    "curve": {"eval_seed": EVAL_SEED, "episodes": EVAL_EPISODES}}
        return _controller(method, seed, suite, "history", params, scale, training)

    while steps < s.steps:
        deltas = rng.standard_normal((s.directions, size))
        weights = np.vstack([M + s.nu * deltas, M - s.nu * deltas])
        policy = HistoryPolicy(weights, stats.mean.copy(), stats.std(), frames=s.frames,
                               action_scale=scale, u_max=scale)
        pair = episode_seeds(run_root(seed), range(episodes, episodes + s.directions))
        returns, used = ars_rollouts(env, policy, pair + pair, stats)
        steps, episodes, iteration = steps + used, episodes + s.directions, iteration + 1
        M = ars_update(M, deltas, returns[:s.directions], returns[s.directions:],
                       alpha=s.alpha, top=s.top)
        if steps >= next_eval or steps >= s.steps:
            curve.add(steps, doc(), name)
            next_eval += s.eval_every
    env.close()
    return _write(out, name, doc(), curve)


# ---- nominal identification ------------------------------------------------------------------------
def sysid_data(seed: int, suite: Any, episodes: int, horizon: int, u_exc: float, chunk: int = 500,
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``Y`` (E, H, 2), ``U`` (E, H, 1) and the mask of samples logged before each episode ended,
    of ``episodes`` open-loop episodes driven by random ±``u_exc`` inputs."""
    from pendulum_lqg.core.rules import saturate
    from pendulum_lqg.core.seeding import episode_seeds
    from pendulum_lqg.envs.vector import CartPoleLQGVectorEnv

    rng = np.random.default_rng([run_root(seed), 2])       # the excitation's stream
    u_max = _u_max(suite)
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


def train_sysid(seed: int, out: Path, budgets: tuple[int, ...] = SYSID_BUDGETS, horizon: int = 30,
                method: str = "sysid-lqg") -> Path:
    from pendulum_lqg.errors import PendulumLQGError
    from pendulum_lqg.scoreboard.suites import load_suite

    suite = load_suite("lecture")
    u_exc = 0.5 * _u_max(suite)
    curve, name = Curve(suite), f"{method}-seed{seed}"
    # episodes that fail early log fewer than H steps: a fifth more episodes than H·E covers
    Y, U, valid = sysid_data(seed, suite, -(-max(budgets) * 6 // (5 * horizon)), horizon, u_exc)
    steps_of = np.cumsum(valid.sum(axis=1))                  # logged steps of the first e episodes
    doc: dict[str, Any] = {}
    for budget in budgets:
        e = min(int(np.searchsorted(steps_of, budget)) + 1, len(steps_of))
        try:
            params, model = sysid_controller(Y[:e], U[:e], valid[:e], suite)
        except (PendulumLQGError, np.linalg.LinAlgError, ValueError) as exc:
            print(f"{name}: {budget:,} steps: no design ({' '.join(str(exc).split())[:120]})")
            continue
        training = {"algo": "nominal sysid + LQG", "horizon": horizon, "u_exc": u_exc,
                    "budget": {"steps": int(steps_of[e - 1]), "episodes": e,
                               "root_seed": run_root(seed), "env_seeds": "episode_seed(root, i)"},
                    "model": {"A": model.A.tolist(), "B": model.B.tolist(),
                              "W": np.diag(model.W).tolist(), "V": np.diag(model.V).tolist()},
                    "curve": {"eval_seed": EVAL_SEED, "episodes": EVAL_EPISODES}}
        doc = _controller(method, seed, suite, "state_space", params, 1.0, training)
        curve.add(int(steps_of[e - 1]), doc, name)
    if not doc:
        raise SystemExit(f"{name}: no budget gave a design")
    return _write(out, name, doc, curve)


def _write(out: Path, name: str, doc: dict[str, Any], curve: Curve) -> Path:
    from train_agents import _write_curve

    from pendulum_lqg.scoreboard.linear import write_controller

    out.mkdir(parents=True, exist_ok=True)
    doc["training"]["wall_seconds"] = curve.points[-1]["wall_seconds"] if curve.points else None
    path = out / f"{name}.json"
    write_controller(path, doc)
    _write_curve(out / f"{name}-curve.csv", curve.points)
    return path


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("method", choices=sorted(METHODS))
    ap.add_argument("--seed", type=int, default=0, help="the run's training seed (default 0)")
    ap.add_argument("--steps", type=int, default=None, help="ARS: env steps (default 1 000 000)")
    ap.add_argument("--alpha", type=float, default=None, help="ARS: step size α")
    ap.add_argument("--nu", type=float, default=None, help="ARS: exploration ν")
    ap.add_argument("--frames", type=int, default=None, help="ARS: history length K")
    ap.add_argument("--eval-every", type=int, default=None, help="ARS: steps between curve points")
    ap.add_argument("--out", type=Path, default=Path("experiments/agents/models"))
    args = ap.parse_args(argv)
    for key in ("seed", "steps", "frames", "eval_every"):
        value = getattr(args, key)
        if value is not None and value < (0 if key == "seed" else 1):
            ap.error(f"--{key.replace('_', '-')}: expected a "
                     f"{'non-negative' if key == 'seed' else 'positive'} integer, got {value}")
    for key in ("alpha", "nu"):
        value = getattr(args, key)
        if value is not None and not (np.isfinite(value) and value > 0):
            ap.error(f"--{key}: expected a finite positive number, got {value}")
    if args.method == "sysid-lqg":
        path = train_sysid(args.seed, args.out)
    else:
        chosen = {k: getattr(args, k) for k in ("alpha", "nu", "frames", "steps", "eval_every")
                  if getattr(args, k) is not None}
        path = train_ars(args.seed, args.out, ARSSettings(**chosen))
    print(f"wrote {path} and {path.stem}-curve.csv", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
