"""One schema per external JSON format: score files (``board``), stable-baselines3 training records
(``--agent sb3:PATH.zip``), linear controller files (``--agent linear:FILE.json``) and the check
records of a results folder's work units. Suite files are checked by
:func:`pendulum_lqg.scoreboard.suites.parse_suite` and experiment files by
:func:`pendulum_lqg.bench.experiments.parse_spec`, with the same validators
(:mod:`pendulum_lqg.boundary.fields`) and the same readers (:mod:`pendulum_lqg.boundary`).

Each schema returns the data it checked, with defaults filled in; an error is one line naming the
file and the key (``board: a.json: suites.lecture.fingerprint: missing``).
"""

from __future__ import annotations

import os
from typing import Any

from pendulum_lqg.boundary import read_json
from pendulum_lqg.boundary.fields import (
    Where,
    any_text,
    boolean,
    exactly,
    integer,
    list_of,
    number,
    one_of,
    table,
    text,
)

#: Version of the score files' layout.
SCORE_VERSION = 1
#: The algorithms a training record may name, and the package each comes from.
ALGORITHMS = {"PPO": "stable_baselines3", "SAC": "stable_baselines3", "TD3": "stable_baselines3",
              "A2C": "stable_baselines3", "DDPG": "stable_baselines3",
              "RecurrentPPO": "sb3_contrib", "TQC": "sb3_contrib"}
#: Ceiling of a training record's ``frame_stack`` (the agent keeps that many observations).
MAX_FRAME_STACK = 10_000
#: The estimators an observation design may show instead of ``y``
#: (:mod:`pendulum_lqg.scoreboard.obs_design`).
ESTIMATORS = ("kalman",)
#: What a suite's reference and built-in designs are designed on (a score file's ``designed_on``;
#: the rule: :func:`pendulum_lqg.scoreboard.suites.designed_on`).
DESIGNED_ON = ("plant played", "nominal MJCF", "nominal MJCF + model_overrides")
#: What the designs of a suite on a plant given as matrices are designed on (an LTI suite's score
#: files say it: :mod:`pendulum_lqg.scoreboard.lti_suite`).
DESIGNED_ON_LTI = "the plant played (its LTI file)"

_RATE = number(low=0.0, high=1.0)
_COST = number(nullable=True)


def _figures(where: Where, data: Any, *, gap: bool) -> dict[str, Any]:
    """The figures of a suite entry (``gap``) or of its reference / full-state bound."""
    data = where.check(data, table)
    out = {"success_rate": where.get(data, "success_rate", _RATE),
           "cost_mean": where.get(data, "cost_mean", _COST)}
    if gap:
        out["optimality_gap"] = where.get(data, "optimality_gap", _COST, default=None)
        out["gap_ci"] = where.get(data, "gap_ci", list_of(_COST, 2), default=[None, None])
    else:
        out["policy"] = where.get(data, "policy", text)
    return out


def score_suite(where: Where, data: Any) -> dict[str, Any]:
    """One ``suites.NAME`` entry of a score file, as the board reads it."""
    data = where.check(data, table)
    out = {"applicable": where.get(data, "applicable", boolean, default=True),
           "fingerprint": where.get(data, "fingerprint", text),
           "episodes": where.get(data, "episodes", integer(1)),
           # absent from the files written before the suites said it
           "designed_on": where.get(data, "designed_on", one_of((*DESIGNED_ON, DESIGNED_ON_LTI)),
                                  default=None)}
    if not out["applicable"]:
        out["reason"] = where.get(data, "reason", any_text, default="")
        return out
    out.update(_figures(where, data, gap=True))
    out["score_mean"] = where.get(data, "score_mean", _COST)
    out["score_ci"] = where.get(data, "score_ci", list_of(_COST, 2))
    for key in ("reference", "full_state_bound"):
        out[key] = _figures(where.at(key), where.get(data, key, table), gap=False)
    return out


def score_file(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The score file ``path`` (``pendulum-lqg score … --out FILE``), checked for every key the
    board reads."""
    data = read_json(path, where="board")
    where = Where(f"board: {path}")
    data = where.check(data, table)
    where.get(data, "score_version", exactly(SCORE_VERSION))
    suites = where.get(data, "suites", table)
    return {"policy": where.get(data, "policy", text),
            "kind": where.get(data, "kind", any_text, default=""),
            "method": where.get(data, "method", text, default=None),
            "seed": where.get(data, "seed", integer(0), default=None),
            "suites": {name: score_suite(where.at("suites").at(name), entry)
                       for name, entry in suites.items()}}


def _obs_norm(where: Where, data: Any) -> dict[str, Any] | None:
    if data is None:
        return None
    data = where.check(data, table)
    return {"mean": where.get(data, "mean", list_of(number())),
            "var": where.get(data, "var", list_of(number(low=0.0))),
            "clip": where.get(data, "clip", number(low=0.0), default=10.0),
            "epsilon": where.get(data, "epsilon", number(low=0.0), default=1e-8)}


def training_record(path: str | os.PathLike[str], *, where_text: str) -> dict[str, Any]:
    """The training record beside a stable-baselines3 model (``PATH.json``; format in
    :mod:`pendulum_lqg.scoreboard.sb3`)."""
    from pendulum_lqg.names import OBSERVATION_MODES

    data = read_json(path, where=where_text)
    where = Where(f"{where_text}: {path}")
    data = where.check(data, table)
    env = where.get(data, "env", table, default={})
    where.at("env").get(env, "observation_mode", one_of(OBSERVATION_MODES), default="measurement")
    frames = where.get(data, "frame_stack", integer(1), default=1)
    if frames > MAX_FRAME_STACK:
        raise where.error(f"at most {MAX_FRAME_STACK:,} (observations the agent keeps), got "
                          f"{frames:,}", "frame_stack")
    return {"algo": where.get(data, "algo", one_of(tuple(ALGORITHMS))),
            "method": where.get(data, "method", text, default=None),
            "seed": where.get(data, "seed", integer(0), default=None),
            "frame_stack": frames,
            "past_actions": where.get(data, "past_actions", boolean, default=False),
            "estimator": where.get(data, "estimator", one_of(ESTIMATORS), default=None),
            "obs_norm": _obs_norm(where.at("obs_norm"), data.get("obs_norm")),
            "normalize_action": where.get(data, "normalize_action", boolean, default=False),
            "env": dict(env), "budget": data.get("budget")}


#: The ``format`` and ``version`` of a linear controller file (``--agent linear:FILE.json``).
LINEAR_FORMAT, LINEAR_VERSION = "pendulum-lqg linear controller", 1
#: Ceiling of a linear controller's state dimension (a matrix of that many rows is kept per row).
MAX_LINEAR_STATES = 1_000
#: Inputs of a linear controller per control period: ``z = [p, θ, u_prev / action_scale]``.
LINEAR_INPUTS = 3


def _matrix(rows: int | None, cols: int | None) -> Any:
    """A list of ``rows`` lists of ``cols`` finite numbers (``None``: any count)."""
    return list_of(list_of(number(), cols), rows)


def _history_form(where: Where, data: Any) -> dict[str, Any]:
    data = where.check(data, table)
    frames = where.get(data, "frames", integer(1))
    if frames > MAX_FRAME_STACK:
        raise where.error(f"at most {MAX_FRAME_STACK:,} (frames the controller keeps), got "
                          f"{frames:,}", "frames")
    size = LINEAR_INPUTS * frames
    return {"frames": frames, "weights": where.get(data, "weights", list_of(number(), size)),
            "bias": where.get(data, "bias", number(), default=0.0),
            "mean": where.get(data, "mean", list_of(number(), size)),
            "std": where.get(data, "std", list_of(number(low=1e-12), size))}


def _state_space_form(where: Where, data: Any) -> dict[str, Any]:
    data = where.check(data, table)
    A = where.get(data, "A", _matrix(None, None))
    n = len(A)
    if not 1 <= n <= MAX_LINEAR_STATES:
        raise where.error(f"expected 1 … {MAX_LINEAR_STATES:,} states, got {n}", "A")
    return {"A": where.get(data, "A", _matrix(n, n)),
            "B": where.get(data, "B", _matrix(n, LINEAR_INPUTS)),
            "C": where.get(data, "C", _matrix(1, n)),
            "D": where.get(data, "D", _matrix(1, LINEAR_INPUTS))}


def linear_controller(path: str | os.PathLike[str], *, where_text: str) -> dict[str, Any]:
    """A linear controller file (``--agent linear:FILE.json``; the format:
    :mod:`pendulum_lqg.scoreboard.linear`), checked; errors are one line naming the file and
    key."""
    data = read_json(path, where=where_text)
    where = Where(f"{where_text}: {path}")
    data = where.check(data, table)
    where.get(data, "format", exactly(LINEAR_FORMAT))
    where.get(data, "version", exactly(LINEAR_VERSION))
    form = where.get(data, "form", one_of(("history", "state_space")))
    parse = _history_form if form == "history" else _state_space_form
    env = where.get(data, "env", table, default={})
    where.at("env").get(env, "observation_mode", one_of(("measurement",)),
                        default="measurement")
    return {"form": form, form: parse(where.at(form), where.get(data, form, table)),
            "action_scale": where.get(data, "action_scale", number(low=1e-12)),
            "method": where.get(data, "method", text, default=None),
            "seed": where.get(data, "seed", integer(0), default=None),
            "env": dict(env), "training": data.get("training")}


def unit_record(path: str | os.PathLike[str]) -> dict[str, Any]:
    """A work unit's check record (``units/KEY.json`` of a results folder; its fields:
    :func:`pendulum_lqg.bench.results.ResultsDir.write_unit`); errors name the file and key."""
    data = read_json(path, where="unit")
    where = Where(f"unit: {path}")
    data = where.check(data, table)
    out = {key: where.get(data, key, check) for key, check in (
        ("fingerprint", text), ("config", integer(0)), ("start", integer(0)),
        ("stop", integer(0)), ("sha256", text), ("rows", integer(0)),
        ("columns", list_of(any_text)))}
    if "plugin_source" in data:
        out["plugin_source"] = where.get(data, "plugin_source", text)
    return out


__all__ = ["ALGORITHMS", "DESIGNED_ON", "DESIGNED_ON_LTI", "ESTIMATORS", "LINEAR_FORMAT", "LINEAR_INPUTS",
           "LINEAR_VERSION", "MAX_FRAME_STACK", "MAX_LINEAR_STATES", "SCORE_VERSION",
           "linear_controller", "score_file", "score_suite", "training_record", "unit_record"]
