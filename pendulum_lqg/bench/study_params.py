"""The parameter tables of the studies an experiment file may name (``study = "margins"`` or
``"roa"`` with a ``[margins]``/``[roa]`` table): their keys, defaults and checks. They are read with
the experiment (:mod:`pendulum_lqg.bench.experiments`); the studies themselves are
:mod:`pendulum_lqg.analysis.studies`'."""

from __future__ import annotations

from typing import Any

import msgspec

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.problem.errors import check_keys, convert
from pendulum_lqg.problem.study import STUDIES
from pendulum_lqg.util.limits import MAX_FREQUENCIES, MAX_MAP_POINTS, check_at_most

#: Parameters of each study and their defaults (declared in :mod:`pendulum_lqg.problem.study`).
STUDY_PARAMS: dict[str, dict[str, object]] = {
    name: {k: list(v) if isinstance(v, tuple) else v
           for k, v in msgspec.structs.asdict(struct()).items()}
    for name, struct in STUDIES.items()}


def parse_study_params(study: str, table: dict[str, object]) -> dict[str, object]:
    """Validate a study's ``[NAME]`` table; returns every parameter (defaults filled in)."""
    if study not in STUDY_PARAMS:
        raise ConfigError(f"study: unknown {study!r}; expected one of " + ", ".join(STUDY_PARAMS))
    check_keys(study, table, list(STUDY_PARAMS[study]))
    convert(table, STUDIES[study], key=study)          # the declared types and bounds
    out: dict[str, Any] = {**STUDY_PARAMS[study], **table}     # the values as the file gives them
    for key in ("map_theta", "map_theta_dot"):
        value = out.get(key)
        if value is not None and (value[0] >= value[1] or int(value[2]) < 2):
            raise ConfigError(f"{study}.{key}: expected [from, to, points] with from < to and "
                              f"points ≥ 2, got {table.get(key, value)!r}")
    if study == "margins":
        for key in ("n_omega", "nyquist_points"):
            check_at_most(f"margins.{key}", out[key], MAX_FREQUENCIES,
                          "frequencies held in memory at once")
        check_at_most("margins.q", len(out["q"]), 100, "recovery parameters")
    if study == "roa":
        for key in ("map_theta", "map_theta_dot"):
            points = out[key][2]
            if points != int(points):
                raise ConfigError(f"roa.{key}: the number of points must be a whole number, "
                                  f"got {points!r}")
        check_at_most("roa.map_theta × map_theta_dot points",
                      int(out["map_theta"][2]) * int(out["map_theta_dot"][2]),
                      MAX_MAP_POINTS, "one episode each, run as one batch")
    if study == "margins" and not out["omega_min"] < out["omega_max"]:
        raise ConfigError("margins.omega_min: must be below omega_max")
    if study == "roa":
        if not out["theta_lo"] < out["theta_hi"]:
            raise ConfigError("roa.theta_lo: must be below theta_hi")
    return out
