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
    """The stand-in module; each call's arguments are appended to ``calls``. Like the real one it
    calls ``on_stage(state, data)`` after its open-loop stage and each of its two rounds (a state
    of the real one's keys: what ``sysid-lqg``'s checkpoint holds) and continues after ``resume``'s
    stage."""
    import numpy as np

    def identify_closed_loop(suite: Any, *, root: int, steps: int | None = None,
                             log: Any = None, on_stage: Any = None,
                             resume: Any = None) -> list[RoundResult]:
        done = 0 if resume is None else int(resume[0]["stage"])
        calls.append({"suite": suite.name, "root": root, "steps": steps,
                      **({"resumed_after": done} if resume is not None else {})})
        ss = true_lqg_state_space(suite)
        log("stand-in identification: 2 rounds")
        logged = [(1_000, 1_000), (10_000, 10_400), (40_000, 41_000)]
        for stage in range(done + (resume is not None), 3):
            if on_stage is None:
                continue
            rng = np.random.default_rng([root, 3])
            on_stage({"stage": stage, "bursts": 10, "per_round": 1, "open_logged": 1_000,
                      "next_episode": 10 + stage, "stepped": logged[stage][1],
                      "state_space": ss, "models": [{"round": r} for r in range(stage + 1)],
                      "start": {"params": [0.0], "K_p": [[0.0]], "x0": [0.0], "delay": 1,
                                "weights": [1.0]},
                      "results": [[a, b, ss] for a, b in logged[:stage + 1]],
                      "rng": rng.bit_generator.state},
                     {"Y": np.zeros((stage, 3, 2)), "U": np.zeros((stage, 3, 1)),
                      "valid": np.ones((stage, 3), dtype=bool)})
        return [RoundResult(10_000, 10_400, ss, {"round": 1}, {"innovation_rms": [0.1, 0.1]}),
                RoundResult(40_000, 41_000, ss, {"round": 2}, {"innovation_rms": [0.1, 0.1]})]

    module = types.ModuleType("pendulum_lqg.learn.closed_loop")
    module.RoundResult = RoundResult            # type: ignore[attr-defined]
    module.identify_closed_loop = identify_closed_loop   # type: ignore[attr-defined]
    return module
