"""A stand-in of :mod:`pendulum_lqg.learn.closed_loop` (the closed-loop identification, written
apart): its API, with every round's controller the LQG designed on the suite's true model — so
that what the training pipeline does with the rounds (files, curve, clone) is tested against a
controller whose score is known (the reference's own: failure-aware score 1)."""

from __future__ import annotations

import types
from dataclasses import dataclass
from typing import Any


@dataclass
class RoundResult:
    logged_steps: int
    stepped_steps: int
    state_space: dict[str, Any]
    model: dict[str, Any]
    validation: dict[str, Any]


def true_lqg_state_space(suite: Any) -> dict[str, Any]:
    from pendulum_lqg.policies.loading import build_policy
    from pendulum_lqg.scoreboard.linear import lqg_state_space

    info = build_policy("dlqr+kalman", plant=suite.plants()[1],
                        scenario=suite.config.scenario).info
    return lqg_state_space(info["Phi"], info["Gamma"], info["C"], info["K"], info["L"])


def closed_loop_module(calls: list[dict[str, Any]]) -> types.ModuleType:
    """The stand-in module; each call's arguments are appended to ``calls``."""
    def identify_closed_loop(suite: Any, *, root: int, steps: int | None = None,
                             log: Any = None) -> list[RoundResult]:
        calls.append({"suite": suite.name, "root": root, "steps": steps})
        ss = true_lqg_state_space(suite)
        log("stand-in identification: 2 rounds")
        return [RoundResult(10_000, 10_400, ss, {"round": 1}, {"innovation_rms": [0.1, 0.1]}),
                RoundResult(40_000, 41_000, ss, {"round": 2}, {"innovation_rms": [0.1, 0.1]})]

    module = types.ModuleType("pendulum_lqg.learn.closed_loop")
    module.RoundResult = RoundResult            # type: ignore[attr-defined]
    module.identify_closed_loop = identify_closed_loop   # type: ignore[attr-defined]
    return module
