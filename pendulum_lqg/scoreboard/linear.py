"""Linear controllers of a y/u history as files: ``score --agent linear:FILE.json``.

A learned linear controller — random search over a linear policy (ARS), or an LQG controller
designed on an identified model — is a linear map from what the controller has seen to the force.
Its input at control period ``k`` is ``z_k = [p_k, θ_k, u_{k−1} / s]``: the measurement (a lost or
not yet delivered sample replaced by the last one received, zeros before the first) and the force
applied in the previous period (saturated by :func:`~pendulum_lqg.core.rules.saturate`, 0 before
the first), in units of the file's ``action_scale`` ``s`` [N]. Two forms::

    {"format": "pendulum-lqg linear controller", "version": 1,
     "method": "ars-history", "seed": 0,            # the run (optional): board aggregates by method
     "action_scale": 10.0,                          # s [N]: u_k = sat(s · v_k)
     "form": "history",                             # v_k = w · (h_k − mean) / std + bias, h_k the
     "history": {"frames": K, "weights": [3K], "bias": 0.0, "mean": [3K], "std": [3K]},
                                                    # last K inputs z, oldest first (zeros before
                                                    # the first period)
     "env": {...}, "training": {...}}               # what it was trained on, how (free-form)

or ``"form": "state_space"`` with ``"state_space": {"A": n×n, "B": n×3, "C": 1×n, "D": 1×3}``:
``v_k = C ξ_k + D z_k``, ``ξ_{k+1} = A ξ_k + B z_k``, ``ξ_0 = 0``. The schema is
:func:`~pendulum_lqg.boundary.schemas.linear_controller` (one line naming the file and the key).

Scoring plays the suite's episodes through the core's batch (:func:`linear_rows`:
:func:`~pendulum_lqg.core.runner.run_episodes`, the path of the built-in policies, with the same
saturation, failure rule, cost and noise), all episodes at once; a Gymnasium env can also run the
controller one episode at a time (:class:`LinearAgent`), with the same rows. A steady-state LQG
controller in current-estimator form is a state-space controller exactly
(:func:`lqg_state_space`), so ``dlqr+kalman`` written as a file scores as the built-in does.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from pendulum_lqg.boundary.schemas import LINEAR_FORMAT, LINEAR_VERSION, linear_inputs
from pendulum_lqg.core.rules import saturate
from pendulum_lqg.errors import ConfigError, NotApplicable
from pendulum_lqg.scoreboard.obs_design import ObservationDesign, ObservationHistory

__all__ = ["HistoryPolicy", "LinearAgent", "LinearFactory", "StateSpacePolicy", "controller_file",
           "linear_agent", "linear_policy", "linear_rows", "lqg_state_space"]


class _LinearPolicy:
    """The part both forms share: the held inputs ``z`` of every row and the saturated output.

    A policy of the core's protocol (``reset(n)``, ``act(y) -> u`` [N], ``select(rows)``);
    ``outputs``: the p of ``y`` (2 on the cart-pole, ``z = [y, u_prev/s]`` has p + 1 numbers)."""

    independent_rows = True

    def __init__(self, frames: int, action_scale: float, u_max: float, outputs: int = 2) -> None:
        self.design = ObservationDesign(frames, past_actions=True)
        self.scale, self.u_max = float(action_scale), float(u_max)
        self.outputs = int(outputs)
        self.history: ObservationHistory | None = None
        self.u: np.ndarray | None = None
        #: the inputs (n, frames·(p + 1)) of the last period, oldest first
        self.inputs = np.zeros((0, (self.outputs + 1) * frames))

    def reset(self, n: int, x_hat0: np.ndarray | None = None) -> None:
        self.history = ObservationHistory(self.design, n, self.outputs, -np.inf, np.inf)
        self.u = None

    def act(self, y: np.ndarray) -> np.ndarray:
        assert self.history is not None, "reset(n) first"
        y = np.asarray(y, dtype=float).reshape(-1, self.outputs)
        if self.u is None:
            self.inputs = self.history.reset(y)
        else:
            self.inputs = self.history.step(y, self.u[:, None] / self.scale)
        # the core's rule; the next input is the force the actuator applies
        self.u = saturate(self.scale * self.output(self.inputs), self.u_max)
        return self.u.copy()

    def output(self, inputs: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def select(self, rows: np.ndarray) -> None:
        assert self.history is not None and self.u is not None
        self.history.select(rows)
        self.u, self.inputs = self.u[rows], self.inputs[rows]


class HistoryPolicy(_LinearPolicy):
    """``v = w · (h − mean) / std + bias`` of the last ``frames`` inputs ``h``. ``weights`` is
    one vector (3·frames,) for every row, or a matrix (n, 3·frames) with one per row (random
    search evaluates its perturbations as rows of one batch); ``bias`` likewise."""

    def __init__(self, weights: Any, mean: Any, std: Any, *, frames: int, action_scale: float,
                 u_max: float, bias: Any = 0.0, outputs: int = 2) -> None:
        super().__init__(frames, action_scale, u_max, outputs)
        self.weights = np.asarray(weights, dtype=float)
        self.bias = np.asarray(bias, dtype=float)
        self.mean, self.std = np.asarray(mean, dtype=float), np.asarray(std, dtype=float)

    def output(self, inputs: np.ndarray) -> np.ndarray:
        f = (inputs - self.mean) / self.std
        if self.weights.ndim == 1:
            return f @ self.weights + self.bias
        return np.einsum("ij,ij->i", f, self.weights) + self.bias

    def select(self, rows: np.ndarray) -> None:
        super().select(rows)
        if self.weights.ndim == 2:
            self.weights = self.weights[rows]
        if self.bias.ndim == 1:
            self.bias = self.bias[rows]


class StateSpacePolicy(_LinearPolicy):
    """``v = C ξ + D z``, ``ξ⁺ = A ξ + B z``, ``ξ_0 = 0`` (``z``: this period's input)."""

    def __init__(self, A: Any, B: Any, C: Any, D: Any, *, action_scale: float,
                 u_max: float) -> None:
        super().__init__(1, action_scale, u_max, np.asarray(D).shape[-1] - 1)
        self.A, self.B = np.asarray(A, dtype=float), np.asarray(B, dtype=float)
        self.C, self.D = np.asarray(C, dtype=float), np.asarray(D, dtype=float)
        self.xi = np.zeros((0, self.A.shape[0]))

    def reset(self, n: int, x_hat0: np.ndarray | None = None) -> None:
        super().reset(n)
        self.xi = np.zeros((n, self.A.shape[0]))

    def output(self, inputs: np.ndarray) -> np.ndarray:
        v = self.xi @ self.C[0] + inputs @ self.D[0]
        self.xi = self.xi @ self.A.T + inputs @ self.B.T
        return v

    def select(self, rows: np.ndarray) -> None:
        super().select(rows)
        self.xi = self.xi[rows]


def lqg_state_space(Phi: np.ndarray, Gamma: np.ndarray, C: np.ndarray, K: np.ndarray,
                    L: np.ndarray) -> dict[str, list[list[float]]]:
    """The steady-state LQG controller ``u = −K x̂`` with the current-form estimator
    ``x̂_k = x̄_k + L (y_k − C x̄_k)``, ``x̄_{k+1} = Φ x̂_k + Γ u_k`` (the built-ins'
    :class:`~pendulum_lqg.policies.estimators.CurrentEstimator`), as a state-space controller of
    ``z_k = [y_k, u_{k−1}]`` (``action_scale`` 1 N).

    With ``ξ_k = x̂_{k−1}``: ``x̄_k = Φ ξ_k + Γ u_{k−1}``, so ``x̂_k = (I − LC)(Φ ξ_k + Γ u_{k−1})
    + L y_k = A ξ_k + B z_k`` with ``A = (I − LC)Φ``, ``B = [L, (I − LC)Γ]``; then ``ξ_{k+1} =
    x̂_k`` and ``u_k = −K x̂_k = −K A ξ_k − K B z_k``. ``ξ_0 = 0`` is ``x̄_0 = 0`` (``x̂₀ = 0``)."""
    n = Phi.shape[0]
    E = np.eye(n) - L @ C
    A = E @ Phi
    B = np.hstack([L, E @ Gamma.reshape(n, 1)])
    K = np.asarray(K, dtype=float).reshape(1, n)
    return {"A": A.tolist(), "B": B.tolist(), "C": (-K @ A).tolist(), "D": (-K @ B).tolist()}


def controller_file(form: str, params: dict[str, Any], *, action_scale: float,
                    env: dict[str, Any], method: str | None = None, seed: int | None = None,
                    training: dict[str, Any] | None = None) -> dict[str, Any]:
    """The JSON document of a linear controller (see the module docstring)."""
    out: dict[str, Any] = {"format": LINEAR_FORMAT, "version": LINEAR_VERSION}
    if method is not None:
        out.update(method=method, seed=seed)
    out.update({"form": form, "action_scale": float(action_scale), form: params, "env": env,
                "training": training or {}})
    return out


def linear_policy(doc: dict[str, Any], u_max: float, *, outputs: int | None = None,
                  name: str = "agent") -> _LinearPolicy:
    """The policy of a checked controller document ``doc`` for an actuator limit ``u_max`` [N];
    ``outputs``: the p of the plant it plays (its ``z`` must have p + 1 numbers, else
    :class:`~pendulum_lqg.errors.NotApplicable` naming ``name``)."""
    scale, q = doc["action_scale"], linear_inputs(doc)
    if outputs is not None and q != outputs + 1:
        raise NotApplicable(f"agent {name!r} takes {q - 1} outputs (z = [y, u_prev/s] of {q} "
                            f"numbers); this plant has {outputs}")
    if doc["form"] == "history":
        h = doc["history"]
        return HistoryPolicy(h["weights"], h["mean"], h["std"], frames=h["frames"],
                             bias=h["bias"], action_scale=scale, u_max=u_max, outputs=q - 1)
    m = doc["state_space"]
    return StateSpacePolicy(m["A"], m["B"], m["C"], m["D"], action_scale=scale, u_max=u_max)


class LinearAgent:
    """A linear controller as a Gymnasium agent of one env (the env saturates as the core does,
    so the rows equal :func:`linear_rows`'s)."""

    def __init__(self, env: Any, doc: dict[str, Any], name: str) -> None:
        from pendulum_lqg.core.rules import limits

        base: Any = env.unwrapped
        if base.normalize_action:
            raise ConfigError(f"agent {name!r}: a linear controller acts in newtons; score it on "
                              "an env without normalize_action")
        if base.observation_mode != "measurement":
            raise NotApplicable(f"agent {name!r} takes y = [p, θ]; this env gives the state x")
        self.policy = linear_policy(doc, limits(base.plant, base.scenario)[2],
                                    outputs=int(base.observation_space.shape[0]), name=name)

    def reset(self) -> None:
        self.policy.reset(1)

    def act(self, observation: np.ndarray) -> np.ndarray:
        return self.policy.act(np.asarray(observation, dtype=float)[None, :]).reshape(1)


class LinearFactory:
    """The agent of ``linear:FILE.json``: ``factory(env)`` is a :class:`LinearAgent`;
    :func:`linear_rows` scores it batched. ``run`` (``method``, ``seed``, the file's sha256) goes
    into the score file."""

    normalize_action = False

    def __init__(self, path_text: str, doc: dict[str, Any]) -> None:
        from pendulum_lqg.scoreboard.sb3 import file_sha256

        self.path_text, self.doc = path_text, doc
        self.name = f"linear:{path_text}"
        self.run: dict[str, Any] = {"model_sha256": file_sha256(Path(path_text))}
        self.run.update({k: doc[k] for k in ("method", "seed") if doc.get(k) is not None})

    def __call__(self, env: Any) -> LinearAgent:
        return LinearAgent(env, self.doc, self.name)


def linear_agent(path_text: str) -> LinearFactory:
    """The factory of ``linear:FILE.json``, its file checked."""
    from pendulum_lqg.boundary.schemas import linear_controller
    from pendulum_lqg.util.resources import TRAINED_MODELS_NOTE

    if not Path(path_text).is_file():
        raise ConfigError(f"agent: linear:{path_text}: no such controller file "
                          f"({TRAINED_MODELS_NOTE})")
    return LinearFactory(path_text, linear_controller(path_text, where_text="agent"))


def linear_rows(suite: Any, doc: dict[str, Any], *, name: str, nthread: int | None = None,
                ) -> list[dict[str, Any]]:
    """The rows of the controller document ``doc`` (named ``name`` in errors) on ``suite``: every
    episode through the core's batch, as a built-in policy's
    (:func:`~pendulum_lqg.scoreboard.episodes.policy_rows`)."""
    from pendulum_lqg.core.rules import limits
    from pendulum_lqg.core.runner import run_episodes

    if suite.observes_state:
        raise NotApplicable(f"agent {name!r} takes y = [p, θ]; suite {suite.name!r} "
                            "gives the true state")
    simulated, design = suite.plants()
    scenario = suite.config.scenario
    policy = linear_policy(doc, limits(design, scenario)[2],
                           outputs=design.layout(scenario).p, name=name)
    res = run_episodes(simulated, scenario, policy, seed=suite.seed,
                       episodes=range(suite.episodes), nthread=nthread)
    return [{"episode": r["episode"], "seed": r["seed"], "success": r["success"],
             "failure_reason": r["failure_reason"], "cost": r["cost"]} for r in res.rows]


def write_controller(path: Path, doc: dict[str, Any]) -> None:
    """Write ``doc`` (:func:`controller_file`) as JSON, under the output rule
    (:func:`~pendulum_lqg.util.files.atomic_write`: whole or not at all, only over a regular
    file)."""
    from pendulum_lqg.util.files import atomic_write

    atomic_write(path, json.dumps(doc, indent=1, allow_nan=False) + "\n")
