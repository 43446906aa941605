"""The parameter tables of the analysis studies an experiment file may name (``study = "margins"``
or ``"roa"`` with a ``[margins]`` / ``[roa]`` table), declared: type and bounds, default, help. The
cross-parameter rules (a bracket's ends in order, the ceilings) are
:func:`pendulum_lqg.bench.study_params.parse_study_params`'."""

from __future__ import annotations

from typing import Annotated

import msgspec

from pendulum_lqg.problem.declare import Finite, Positive, setting

_FILE = ("file",)
AtLeast2 = Annotated[int, msgspec.Meta(ge=2)]
Positives = Annotated[tuple[Positive, ...], msgspec.Meta(min_length=1)]
#: A grid ``[from, to, points]``.
Grid = Annotated[tuple[Finite, Finite, Finite], msgspec.Meta()]
Fraction = Annotated[float, msgspec.Meta(gt=0.0, le=1.0)]


class MarginsParams(msgspec.Struct, frozen=True, kw_only=True, forbid_unknown_fields=True):
    """``[margins]``: LQ vs LQG margins, LTR, sampled loops."""

    q: Annotated[Positives, setting("LTR recovery parameters", fronts=_FILE)] = (
        0.01, 0.1, 1.0, 10.0, 100.0, 1000.0, 10000.0)
    omega_min: Annotated[Positive, setting("lowest frequency", unit="rad/s",
                                           fronts=_FILE)] = 1e-3
    omega_max: Annotated[Positive, setting("highest frequency", unit="rad/s",
                                           fronts=_FILE)] = 1e3
    n_omega: Annotated[AtLeast2, setting("frequencies of the grid", fronts=_FILE)] = 4000
    nyquist_points: Annotated[AtLeast2, setting("points per stored Nyquist curve",
                                                fronts=_FILE)] = 400


class RoaParams(msgspec.Struct, frozen=True, kw_only=True, forbid_unknown_fields=True):
    """``[roa]``: the region of attraction."""

    level: Annotated[Fraction, setting("required success fraction of a noisy batch",
                                       fronts=_FILE)] = 0.95
    theta_lo: Annotated[Positive, setting("bisection bracket, low end", unit="rad",
                                          fronts=_FILE)] = 0.05
    theta_hi: Annotated[Positive, setting("bisection bracket, high end", unit="rad",
                                          fronts=_FILE)] = 1.2
    tolerance: Annotated[Positive, setting("bisection tolerance", unit="rad",
                                           fronts=_FILE)] = 0.01
    map_theta: Annotated[Grid, setting("noise-free map: θ₀ from, to, points", unit="rad",
                                       fronts=_FILE)] = (-1.2, 1.2, 25)
    map_theta_dot: Annotated[Grid, setting("noise-free map: θ̇₀ from, to, points",
                                           unit="rad/s", fronts=_FILE)] = (-3.0, 3.0, 25)
    settle_fraction: Annotated[Positive, setting(
        "'recovered' on the map: settled within this share of the episode",
        fronts=_FILE)] = 0.8


#: The studies and their declared tables.
STUDIES: dict[str, type[msgspec.Struct]] = {"margins": MarginsParams, "roa": RoaParams}
