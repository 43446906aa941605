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

from pendulum_lqg.boundary import read_bytes, read_json, read_text
from pendulum_lqg.boundary.fields import (
    Kind,
    Where,
    any_text,
    boolean,
    exactly,
    integer,
    list_of,
    number,
    one_of,
    short,
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
#: Inputs of a linear controller per control period on the cart-pole: ``z = [p, θ, u_prev /
#: action_scale]``; on a plant of p outputs (``--plant``) ``z = [y (p), u_prev / action_scale]``,
#: p + 1 numbers (:func:`linear_inputs`).
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
    weights = where.get(data, "weights", list_of(number()))
    size = len(weights)
    if size % frames or size // frames < 2:
        raise where.error(f"expected frames × (outputs + 1) numbers, {frames} × q with q ≥ 2 "
                          f"(z = [y, u_prev/s] per frame), got {size}", "weights")
    return {"frames": frames, "weights": weights,
            "bias": where.get(data, "bias", number(), default=0.0),
            "mean": where.get(data, "mean", list_of(number(), size)),
            "std": where.get(data, "std", list_of(number(low=1e-12), size))}


def _state_space_form(where: Where, data: Any) -> dict[str, Any]:
    data = where.check(data, table)
    A = where.get(data, "A", _matrix(None, None))
    n = len(A)
    if not 1 <= n <= MAX_LINEAR_STATES:
        raise where.error(f"expected 1 … {MAX_LINEAR_STATES:,} states, got {n}", "A")
    B = where.get(data, "B", _matrix(n, None))
    q = len(B[0])
    if q < 2:
        raise where.error(f"expected n × q with q ≥ 2 columns (z = [y, u_prev/s]), got {q}", "B")
    return {"A": where.get(data, "A", _matrix(n, n)),
            "B": where.get(data, "B", _matrix(n, q)),
            "C": where.get(data, "C", _matrix(1, n)),
            "D": where.get(data, "D", _matrix(1, q))}


def linear_inputs(doc: dict[str, Any]) -> int:
    """The inputs per control period ``q`` of a checked linear controller document: ``z = [y,
    u_prev/s]``, so the controller takes ``q − 1`` outputs (3 on the cart-pole's ``[p, θ]``)."""
    if doc["form"] == "history":
        h = doc["history"]
        return len(h["weights"]) // int(h["frames"])
    return len(doc["state_space"]["D"][0])


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


# ---- training checkpoints (``pendulum-lqg train --resume``) and learning curves ----------------
#: The columns of a learning curve (``METHOD-seedS-curve.csv``, :mod:`pendulum_lqg.learn.curve`).
CURVE_COLUMNS = ("env_steps", "wall_seconds", "success_rate", "score_mean", "score_ci_lo",
                 "score_ci_hi", "train_return", "train_length")
_COUNT, _SECONDS = integer(0), number(low=0.0)


def curve_file(path: str | os.PathLike[str], *, where_text: str) -> list[dict[str, Any]]:
    """The points of a learning curve ``path``: its header the columns, every cell a number
    (``env_steps`` a count that never decreases; empty: no score / no training episode); an error
    is one line naming the file, the line and the column."""
    import csv
    import math

    text = read_text(path, where=where_text)
    where = Where(f"{where_text}: {path}")
    rows = list(csv.reader(text.splitlines()))
    if not rows or tuple(rows[0]) != CURVE_COLUMNS:
        raise where.error("expected the header " + ",".join(CURVE_COLUMNS))
    points: list[dict[str, Any]] = []
    for line, row in enumerate(rows[1:], start=2):
        at = Where(f"{where.file}: line {line}")      # FILE: line N: COLUMN: …
        if len(row) != len(CURVE_COLUMNS):
            raise at.error(f"expected {len(CURVE_COLUMNS)} cells, got {len(row)}")
        point: dict[str, Any] = {}
        for key, cell in zip(CURVE_COLUMNS, row, strict=True):
            if cell == "" and key != "env_steps":
                point[key] = None if key.startswith("score") else math.nan
                continue
            try:
                value: Any = int(cell, 10) if key == "env_steps" else float(cell)
            except ValueError:
                value = None
            if value is None or not math.isfinite(value) or (value < 0 and key in (
                    "env_steps", "wall_seconds", "success_rate")):
                raise at.error(f"expected {'a count' if key == 'env_steps' else 'a number'}, "
                               f"got {cell!r}", key)
            point[key] = value
        if points and point["env_steps"] < points[-1]["env_steps"]:
            raise at.error(f"expected at least {points[-1]['env_steps']:,} (the steps never "
                           f"decrease), got {point['env_steps']:,}", "env_steps")
        points.append(point)
    return points


def _generator_state(where: Where, data: Any) -> dict[str, Any]:
    """The state of a numpy ``PCG64`` bit generator (``Generator.bit_generator.state``)."""
    import numpy as np

    data = where.check(data, table)
    where.get(data, "bit_generator", exactly("PCG64"))
    inner = where.at("state").check(where.get(data, "state", table), table)
    for key in ("state", "inc"):
        where.at("state").get(inner, key, _COUNT)
    for key in ("has_uint32", "uinteger"):
        where.get(data, key, _COUNT)
    try:
        np.random.PCG64().state = data
    except (TypeError, ValueError, OverflowError):
        raise where.error("expected the state of numpy's PCG64 generator") from None
    return dict(data)


def _curve_points(where: Where, data: Any, curve: list[dict[str, Any]] | None) -> int:
    points = where.get(data, "points", _COUNT)
    if curve is not None and points > len(curve):
        raise where.error(f"expected at most {len(curve):,} (the points of the curve beside "
                          f"it), got {points:,}", "points")
    return points


def _steps_before(where: Where, data: Any, key: str, total: int) -> int:
    """A checkpoint's step count: a count below the run's budget (a checkpoint is written only
    before the run's end)."""
    steps = where.get(data, key, _COUNT)
    if steps >= total:
        raise where.error(f"expected fewer than {total:,} (the run's budget: a checkpoint is "
                          f"written before its end), got {steps:,}", key)
    return steps


def ars_checkpoint(path: str | os.PathLike[str], *, where_text: str, settings: dict[str, Any],
                   suite: str, curve: list[dict[str, Any]] | None,
                   inputs: int = LINEAR_INPUTS) -> dict[str, Any]:
    """An ARS run's checkpoint (:mod:`pendulum_lqg.learn.ars`), checked against the run resumed:
    its ``settings`` and ``suite`` fingerprint the run's, every array of the policy's size
    (``inputs`` per frame: the plant's outputs + 1)."""
    data = read_json(path, where=where_text)
    where = Where(f"{where_text}: {path}")
    data = where.check(data, table)
    saved = where.get(data, "settings", table)
    if saved != settings:
        raise where.error(f"expected the run's settings {settings}, got {short(saved)}; resume "
                          "with the same --alpha, --nu, --frames and --steps", "settings")
    if where.get(data, "suite", text) != suite:
        raise where.error("written on another suite; resume with the same --suite", "suite")
    points = _curve_points(where, data, curve)
    at = where.at("state")
    state = at.check(where.get(data, "state", table), table)
    size = inputs * int(settings["frames"])
    out = {"M": at.get(state, "M", list_of(number(), size)),
           "n": at.get(state, "n", _COUNT),
           "mean": at.get(state, "mean", list_of(number(), size)),
           "m2": at.get(state, "m2", list_of(number(low=0.0), size)),
           "rng": _generator_state(at.at("rng"), at.get(state, "rng", table)),
           "steps": _steps_before(at, state, "steps", int(settings["steps"])),
           "episodes": at.get(state, "episodes", _COUNT),
           "iteration": at.get(state, "iteration", _COUNT),
           "log": at.get(state, "log", list_of(number(), 3)),
           "start": at.get(state, "start", text),
           "bias": at.get(state, "bias", number())}
    if out["log"][2] < 0 or out["log"][2] != int(out["log"][2]):
        raise at.error(f"expected a count of episodes, got {out['log'][2]!r}", "log")
    if curve and points and curve[points - 1]["env_steps"] > out["steps"]:
        raise at.error(f"expected at least {curve[points - 1]['env_steps']:,} (the curve's last "
                       f"point), got {out['steps']:,}", "steps")
    return {"settings": saved, "suite": suite, "points": points, "state": out,
            "wall_seconds": where.get(data, "wall_seconds", _SECONDS, default=0.0)}


def openloop_checkpoint(path: str | os.PathLike[str], *, where_text: str, budgets: list[int],
                        suite: str, curve: list[dict[str, Any]] | None) -> dict[str, Any]:
    """A ``sysid-openloop`` run's checkpoint (:mod:`pendulum_lqg.learn.openloop`)."""
    data = read_json(path, where=where_text)
    where = Where(f"{where_text}: {path}")
    data = where.check(data, table)
    if where.get(data, "budgets", list_of(integer(1))) != budgets:
        raise where.error(f"expected the run's budgets {budgets}; resume with the same --steps",
                          "budgets")
    if where.get(data, "suite", text) != suite:
        raise where.error("written on another suite; resume with the same --suite", "suite")
    done = where.get(data, "done", integer(1))
    if done >= len(budgets):
        raise where.error(f"expected fewer than {len(budgets)} (the budgets: a checkpoint is "
                          f"written before the last), got {done}", "done")
    return {"budgets": budgets, "done": done, "points": _curve_points(where, data, curve),
            "suite": suite}


def sb3_checkpoint(path: str | os.PathLike[str], *, where_text: str, algo: str, suite: str,
                   steps: int, curve: list[dict[str, Any]] | None) -> dict[str, Any]:
    """An SB3 run's checkpoint record (:mod:`pendulum_lqg.learn.deep`); the model, statistics
    and replay buffer it names are checked to be regular files by the caller."""
    data = read_json(path, where=where_text)
    where = Where(f"{where_text}: {path}")
    data = where.check(data, table)
    if where.get(data, "algo", one_of(tuple(ALGORITHMS))) != algo:
        raise where.error(f"written for {data['algo']}, this method is {algo}; resume with the "
                          "same method", "algo")
    if where.get(data, "suite", text) != suite:
        raise where.error("written on another suite; resume with the same --suite", "suite")
    return {"algo": algo, "suite": suite, "steps": _steps_before(where, data, "steps", steps),
            "points": _curve_points(where, data, curve),
            "wall_seconds": where.get(data, "wall_seconds", _SECONDS, default=0.0)}


def _state_space(where: Where, data: Any) -> dict[str, Any]:
    """A controller's state-space matrices (``lqg_state_space``'s ``A``, ``B``, ``C``, ``D``)."""
    data = where.check(data, table)
    A = where.get(data, "A", _matrix(None, None))
    n = len(A)
    return {"A": where.get(data, "A", _matrix(n, n)), "B": where.get(data, "B", _matrix(n, None)),
            "C": where.get(data, "C", _matrix(None, n)), "D": where.get(data, "D", _matrix(None,
                                                                                         None))}


def _identification(where: Where, data: Any) -> dict[str, Any]:
    """The identification's state after a stage (``identify_closed_loop``'s ``on_stage``; it
    checks the stage against its plan when it resumes)."""
    data = where.check(data, table)
    stage = where.get(data, "stage", _COUNT)
    start = where.at("start").check(where.get(data, "start", table), table)
    at = where.at("start")
    results = where.get(data, "results", list_of(list_of(Kind(Any, "a value"), 3)))
    if len(results) != stage + 1:
        raise where.error(f"expected {stage + 1} (one per stage done), got {len(results)}",
                          "results")
    for i, (logged, stepped, ss) in enumerate(results):
        where.at("results").at(str(i)).check(logged, _COUNT)
        where.at("results").at(str(i)).check(stepped, _COUNT)
        _state_space(where.at("results").at(str(i)), ss)
    models = where.get(data, "models", list_of(table))
    if len(models) != stage + 1:
        raise where.error(f"expected {stage + 1} (one per stage done), got {len(models)}",
                          "models")
    return {"stage": stage, "bursts": where.get(data, "bursts", integer(1)),
            "per_round": where.get(data, "per_round", integer(1)),
            "open_logged": where.get(data, "open_logged", _COUNT),
            "next_episode": where.get(data, "next_episode", _COUNT),
            "stepped": where.get(data, "stepped", _COUNT),
            "state_space": _state_space(where.at("state_space"), where.get(data, "state_space",
                                                                          table)),
            "models": models,
            "start": {"params": at.get(start, "params", list_of(number())),
                      "K_p": at.get(start, "K_p", _matrix(None, None)),
                      "x0": at.get(start, "x0", list_of(number())),
                      "delay": at.get(start, "delay", _COUNT),
                      "weights": at.get(start, "weights", list_of(number(low=0.0)))},
            "results": results,
            "rng": _generator_state(where.at("rng"), where.get(data, "rng", table))}


def _identification_data(path: os.PathLike[str], *, where_text: str, episodes: int,
                         ) -> dict[str, Any]:
    """The closed-loop episodes of a ``sysid-lqg`` checkpoint (``.npz``, no pickles): ``Y``
    (E, H, 2), ``U`` (E, H, 1), ``valid`` (E, H) booleans, ``E`` the episodes the stages played."""
    import io
    import zipfile
    import zlib

    import numpy as np

    raw = read_bytes(path, where=where_text)
    where = Where(f"{where_text}: {path}")
    try:
        # np.savez stores its members uncompressed: a compressed member is not ours, and its
        # size once inflated is not bounded by the file's (read_bytes' ceiling would not hold)
        with zipfile.ZipFile(io.BytesIO(raw)) as archive:
            stored = all(m.compress_type == zipfile.ZIP_STORED for m in archive.infolist())
        arrays = {}
        if stored:
            with np.load(io.BytesIO(raw), allow_pickle=False) as npz:
                arrays = {k: npz[k] for k in npz.files}
    except (OSError, ValueError, EOFError, KeyError, zipfile.BadZipFile, zlib.error) as exc:
        raise where.error(f"not a .npz file of arrays ({' '.join(str(exc).split())[:80]})"
                          ) from None
    if not stored:
        raise where.error("expected the uncompressed .npz that train writes (a member is "
                          "compressed)")
    shapes = {"Y": (episodes, None, 2), "U": (episodes, None, 1), "valid": (episodes, None)}
    horizon = None
    for key, shape in shapes.items():
        if key not in arrays:
            raise where.error("missing", key)
        a = arrays[key]
        horizon = a.shape[1] if horizon is None and a.ndim > 1 else horizon
        want = tuple(horizon if s is None else s for s in shape)
        if a.shape != want or (key == "valid") != (a.dtype == np.bool_) or (
                key != "valid" and a.dtype.kind != "f"):
            raise where.error(f"expected an array of shape {want} of "
                              f"{'booleans' if key == 'valid' else 'numbers'}, got {a.shape} of "
                              f"{a.dtype}", key)
    if not np.isfinite(arrays["U"]).all() or not np.isfinite(arrays["Y"][arrays["valid"]]).all():
        raise where.error("expected finite numbers where the episodes are logged", "Y")
    return arrays


def sysid_checkpoint(path: str | os.PathLike[str], *, where_text: str, suite: str, seed: int,
                     steps: int | None, curve: list[dict[str, Any]] | None,
                     data: os.PathLike[str]) -> dict[str, Any]:
    """A ``sysid-lqg`` run's checkpoint (:mod:`pendulum_lqg.learn.sysid_lqg`) and, while the
    identification is under way, the episodes file beside it, checked against the run resumed."""
    raw = read_json(path, where=where_text)
    where = Where(f"{where_text}: {path}")
    raw = where.check(raw, table)
    where.get(raw, "method", text)
    if where.get(raw, "seed", _COUNT) != seed:
        raise where.error(f"written for --seed {raw['seed']}, this run is --seed {seed}", "seed")
    if where.get(raw, "steps", Kind(int | None, "an integer or null")) != steps:
        raise where.error(f"written for --steps {raw['steps']}, this run's is {steps}; resume "
                          "with the same --steps", "steps")
    if where.get(raw, "suite", text) != suite:
        raise where.error("written on another suite; resume with the same --suite", "suite")
    out: dict[str, Any] = {"points": _curve_points(where, raw, curve), "rounds": None,
                           "identification": None, "data": None,
                           "wall_seconds": where.get(raw, "wall_seconds", _SECONDS, default=0.0)}
    done = where.get(raw, "rounds", Kind(list | None, "a list or null"))
    if done is not None:
        out["rounds"] = []
        for i, entry in enumerate(done):
            r = where.at("rounds").at(str(i))
            entry = r.check(entry, table)
            out["rounds"].append({
                "logged_steps": r.get(entry, "logged_steps", _COUNT),
                "stepped_steps": r.get(entry, "stepped_steps", _COUNT),
                "state_space": _state_space(r.at("state_space"),
                                            r.get(entry, "state_space", table)),
                "model": r.get(entry, "model", table),
                "validation": r.get(entry, "validation", table)})
        if not out["rounds"] or out["points"] > len(out["rounds"]):
            raise where.error(f"expected at least {max(1, out['points'])} rounds, got "
                              f"{len(out['rounds'])}", "rounds")
        return out
    if out["points"]:
        raise where.error("expected 0 before the identification has ended, got "
                          f"{out['points']}", "points")
    state = _identification(where.at("identification"),
                            where.get(raw, "identification", table))
    out["identification"] = state
    out["data"] = _identification_data(data, where_text=where_text,
                                       episodes=state["stage"] * state["per_round"])
    return out


__all__ = [
    "ALGORITHMS",
    "CURVE_COLUMNS",
    "DESIGNED_ON",
    "DESIGNED_ON_LTI",
    "ESTIMATORS",
    "LINEAR_FORMAT",
    "LINEAR_INPUTS",
    "LINEAR_VERSION",
    "MAX_FRAME_STACK",
    "MAX_LINEAR_STATES",
    "SCORE_VERSION",
    "ars_checkpoint",
    "curve_file",
    "linear_controller",
    "linear_inputs",
    "openloop_checkpoint",
    "sb3_checkpoint",
    "score_file",
    "score_suite",
    "sysid_checkpoint",
    "training_record",
    "unit_record",
]
