"""The parameter tables of the studies an experiment file may name (``study = "margins"`` or
``"roa"`` with a ``[margins]``/``[roa]`` table): their keys, defaults and checks. They are read with
the experiment (:mod:`pendulum_lqg.bench.experiments`); the studies themselves are
:mod:`pendulum_lqg.analysis.studies`'."""

from __future__ import annotations

import numpy as np

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.util.config import check_keys
from pendulum_lqg.util.limits import MAX_FREQUENCIES, MAX_MAP_POINTS, check_at_most

#: Parameters of each study and their defaults.
STUDY_PARAMS: dict[str, dict[str, object]] = {
    "margins": {
        "q": [0.01, 0.1, 1.0, 10.0, 100.0, 1000.0, 10000.0],  # LTR recovery parameters
        "omega_min": 1e-3, "omega_max": 1e3, "n_omega": 4000,  # frequency grid [rad/s]
        "nyquist_points": 400,                                 # points per stored Nyquist curve
    },
    "roa": {
        "level": 0.95,            # required success fraction of a noisy batch
        "theta_lo": 0.05, "theta_hi": 1.2, "tolerance": 0.01,  # bisection bracket [rad]
        "map_theta": [-1.2, 1.2, 25],      # noise-free map: θ₀ from, to, points [rad]
        "map_theta_dot": [-3.0, 3.0, 25],  # θ̇₀ from, to, points [rad/s]
        "settle_fraction": 0.8,   # "recovered" on the map: settled within this share of the episode
    },
}

def parse_study_params(study: str, table: dict[str, object]) -> dict[str, object]:
    """Validate a study's ``[NAME]`` table; returns every parameter (defaults filled in)."""
    if study not in STUDY_PARAMS:
        raise ConfigError(f"study: unknown {study!r}; expected one of " + ", ".join(STUDY_PARAMS))
    defaults = STUDY_PARAMS[study]
    check_keys(study, table, list(defaults))
    out = {**defaults, **table}
    for key, default in defaults.items():
        value = out[key]
        where = f"{study}.{key}"
        if isinstance(default, list):
            if not isinstance(value, list) or not value or not all(
                    isinstance(v, int | float) and not isinstance(v, bool) and np.isfinite(v)
                    for v in value):
                raise ConfigError(f"{where}: expected a list of numbers, got {value!r}")
            if key in ("map_theta", "map_theta_dot") and (
                    len(value) != 3 or value[0] >= value[1] or int(value[2]) < 2):
                raise ConfigError(f"{where}: expected [from, to, points] with from < to and "
                                  f"points ≥ 2, got {value!r}")
            if key == "q" and any(v <= 0 for v in value):
                raise ConfigError(f"{where}: expected positive numbers, got {value!r}")
        elif isinstance(default, int):
            if isinstance(value, bool) or not isinstance(value, int) or value < 2:
                raise ConfigError(f"{where}: expected an integer ≥ 2, got {value!r}")
        else:
            if isinstance(value, bool) or not isinstance(value, int | float) \
                    or not np.isfinite(value) or value <= 0:
                raise ConfigError(f"{where}: expected a positive number, got {value!r}")
    if study == "margins":
        for key in ("n_omega", "nyquist_points"):
            check_at_most(f"margins.{key}", out[key], MAX_FREQUENCIES,  # type: ignore[arg-type]
                          "frequencies held in memory at once")
        check_at_most("margins.q", len(out["q"]), 100, "recovery parameters")  # type: ignore[arg-type]
    if study == "roa":
        for key in ("map_theta", "map_theta_dot"):
            points = out[key][2]  # type: ignore[index]
            if points != int(points):
                raise ConfigError(f"roa.{key}: the number of points must be a whole number, "
                                  f"got {points!r}")
        check_at_most("roa.map_theta × map_theta_dot points",
                      int(out["map_theta"][2]) * int(out["map_theta_dot"][2]),  # type: ignore[index]
                      MAX_MAP_POINTS, "one episode each, run as one batch")
    if study == "margins" and not out["omega_min"] < out["omega_max"]:  # type: ignore[operator]
        raise ConfigError("margins.omega_min: must be below omega_max")
    if study == "roa":
        if not out["level"] <= 1:  # type: ignore[operator]
            raise ConfigError(f"roa.level: expected a fraction in (0, 1], got {out['level']!r}")
        if not out["theta_lo"] < out["theta_hi"]:  # type: ignore[operator]
            raise ConfigError("roa.theta_lo: must be below theta_hi")
    return out
