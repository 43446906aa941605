"""The rules of a control period, each defined once.

Every path that steps the plant — a batch of episodes, the single Gymnasium env (a one-row batch),
the native vector env — applies these functions and no other copy of them:

=====================  =======================================================================
rule                   function
=====================  =======================================================================
limits in force        :func:`limits` — ``θ_max``, the track and the force limit of a scenario on
                       a plant (the scenario's, else the MJCF model's; ``inf``: switched off)
saturation             :func:`saturate` — the requested force clipped to ``±u_max``
                       (the actuator's ``ctrlrange``)
non-finite force       :func:`nonfinite_forces` — a nan/inf request ends its episode as
                       ``diverged`` (the physics runs 0 N for it)
failure                :func:`failure_bounds` + :func:`all_inside` (the fast check) and
                       :func:`detect_failure` (the full rule: which rows, why, at which step)
period cost            :func:`period_integrals` / :func:`period_cost` — the rectangle rule of
                       ``∫ xᵀ diag(Q) x + R u² dt`` at the physics step (its form for given
                       weights: :func:`period_cost_of`)
state noise            :func:`end_of_period` — the jump ``x ← x + δx`` at the end of the period
=====================  =======================================================================

The failure rule: an episode fails at the first physics step where ``|θ| > theta_max``, or the
cart reaches the end of the track (``|p| ≥ track_limit``, the slider's ``range`` in the MJCF), or
the state is not finite or runs away (``|x_i| > RUNAWAY``, or MuJoCo reset the data after an
instability); the reason is ``pole_fell``, ``track_limit`` or ``diverged``. The end-of-period state
(after the state noise) is checked for divergence too.

An LTI plant (:class:`~pendulum_lqg.model.interface.Layout`) has no pole and no track: only its declared
``state_limits`` (``|x_i| > limit_i``: ``state_limit``) and divergence end its episodes.

The arrays these rules read are one control period of each row in the layout of
:class:`~pendulum_lqg.core.period.PeriodBuffer`: ``(n, k+2, n_x+1)`` rows of ``z = [x, u]``
(the cart-pole's ``[p, θ, ṗ, θ̇, u]``) at the start of the period, after each of the k physics
steps, and at the end (after the state noise).
"""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING, overload

import numpy as np

if TYPE_CHECKING:
    from collections.abc import Callable

    from pendulum_lqg.core.period import PeriodView
    from pendulum_lqg.core.scenario import Scenario
    from pendulum_lqg.model.interface import SimulatedPlant

#: Any state component beyond this magnitude counts as divergence.
RUNAWAY = 1e6

FAIL_NONE, FAIL_POLE, FAIL_TRACK, FAIL_DIVERGED, FAIL_STATE = 0, 1, 2, 3, 4
#: Failure codes (int8 in the arrays) and the names the results use (``state_limit``: an LTI
#: plant's declared limit).
FAIL_REASONS: dict[int, str] = {FAIL_NONE: "", FAIL_POLE: "pole_fell", FAIL_TRACK: "track_limit",
                                FAIL_DIVERGED: "diverged", FAIL_STATE: "state_limit"}


# ---- limits -------------------------------------------------------------------------------------
def limits(plant: SimulatedPlant, scenario: Scenario) -> tuple[float, float, float]:
    """``(theta_max, track_limit, u_max)`` in force for ``scenario`` on ``plant`` [rad, m, N].

    The scenario's ``track_limit`` / ``force_limit`` when given, else the MJCF slider ``range`` and
    actuator ``ctrlrange``; any of them may be ``inf`` (the rule switched off). MuJoCo itself stops
    the cart at the slider's ``range`` and clips the force to ``ctrlrange``, so on the MuJoCo plant
    a larger limit would be a rule the physics never lets fire: it is refused (one line naming
    the limit); the linear plants take any. An LTI plant (:mod:`pendulum_lqg.model.lti`) has no pole and
    no track (``θ_max`` and the track are ``inf``: its own ``state_limits`` are the failure rule,
    :func:`detect_failure`) and its file's ``force_limit`` unless the scenario sets one. Each
    plant holds its rule (:meth:`SimulatedPlant.limits
    <pendulum_lqg.model.interface.SimulatedPlant.limits>`).
    """
    return plant.limits(scenario)


# ---- saturation ---------------------------------------------------------------------------------
@overload
def saturate(u: float, u_max: float) -> float: ...
@overload
def saturate(u: np.ndarray, u_max: float | np.ndarray) -> np.ndarray: ...
def saturate(u: np.ndarray | float, u_max: float | np.ndarray) -> np.ndarray | float:
    """The force the actuator can apply for a requested force ``u`` [N]: ``min(max(u, −u_max),
    u_max)`` (the symmetric ``ctrlrange``). A float gives a float, an array a new array; the two
    give the same numbers (a min and a max are exact). For (n, m) inputs ``u_max`` may hold one
    limit per input (m,)."""
    if isinstance(u, float):                     # a float force has one limit (the overloads)
        return min(max(u, -u_max), u_max)
    return np.minimum(np.maximum(u, -u_max), u_max)


def nonfinite_forces(u: np.ndarray) -> np.ndarray | None:
    """The rows (bool mask) whose requested force (n,) — or any of whose inputs (n, m) — is nan or
    ±inf, or ``None`` when every force is finite (a finite sum has finite terms: one sum is the
    check in the common case)."""
    if np.isfinite(u.sum()):
        return None
    bad = ~np.isfinite(u)
    if bad.ndim > 1:                      # (n, m) inputs: a row with any non-finite one
        bad = bad.any(axis=1)
    return bad if bad.any() else None


# ---- failure ------------------------------------------------------------------------------------
def failure_bounds(*, theta_max: float, track_limit: float, u_max: float | np.ndarray,
                   state_limits: np.ndarray | None = None) -> np.ndarray:
    """The bounds ``[track, θ_max, RUNAWAY, RUNAWAY, 2·u_max]`` of one ``z`` row for the fast check
    :func:`all_inside`: strictly inside them no part of the failure rule can fire (a saturated force
    is inside; a nan is never inside). An LTI plant's row ``[x, u]``: ``[min(limit_i, RUNAWAY)…,
    2·u_max]`` with its ``state_limits``."""
    if state_limits is not None:            # u_max: one limit, or one per input (m,)
        return np.append(np.minimum(state_limits, RUNAWAY), 2.0 * np.asarray(u_max))
    return np.array([track_limit, theta_max, RUNAWAY, RUNAWAY, 2.0 * u_max])


def all_inside(view: PeriodView) -> bool:
    """The failure rule's fast check: every ``|z_i| < bound_i`` over the rows of ``view`` (start and
    end states included — stricter than :func:`detect_failure`, which then finds nothing).

    It runs on the rows flattened to one contiguous run of numbers with a bound per number
    (``view.flat``, ``view.bounds``) and preallocated scratch, so the check makes no temporaries.
    """
    np.less(np.abs(view.flat, view.scratch), view.bounds, view.inside)    # outputs positional:
    # numpy parses them faster than the ``out=`` keyword (same results)
    # "All True": a numpy bool is one byte, 0 or 1, so a small mask is all True when its bytes
    # hold no 0 — a copy and a byte search, cheaper than setting up a reduction; a large one is
    # reduced by .all() (count_nonzero is slower than either).
    inside = view.inside
    return 0 not in inside.tobytes() if view.small else bool(inside.all())


def detect_failure(view: PeriodView, reset: np.ndarray | None, theta_max: float,
                   track_limit: float, state_limits: np.ndarray | None = None,
                   bad_force: np.ndarray | None = None,
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """Which rows of the period in ``view`` fail, why, and at which physics step.

    Parameters
    ----------
    view : the period's rows (see the module docstring for the layout)
    reset : (n,) bool, the rows MuJoCo reset after an instability (they diverged), or ``None``
        when no row was reset
    theta_max, track_limit : the failure limits [rad], [m]
    state_limits : an LTI plant's (n_x,) limits: ``|x_i| > limit_i`` fails as ``state_limit``
        in place of the pole and track rules (``theta_max``, ``track_limit`` then unused), or
        ``None`` (the cart-pole)
    bad_force : (n,) bool rows whose requested force was not finite (:func:`nonfinite_forces`):
        they fail as ``diverged`` at step 0

    Returns
    -------
    failed : (n,) bool; reason : (n,) int8 ``FAIL_*`` codes (both read-only); fail_step : (n,)
    the first failing physics step 0 … k−1 (``k`` for rows that did not fail), or ``None`` when
    no row failed
    """
    n, k = view.n, view.k
    if n == 0 or (bad_force is None and reset is None and all_inside(view)):
        return _none_failed(n)
    reason = np.zeros(n, dtype=np.int8)                      # FAIL_NONE is 0
    with np.errstate(invalid="ignore"):
        mag = np.abs(view.states)                            # (n, k, 4) after each step
        # ``not (|x| <= RUNAWAY)`` is true for nan, inf and runaway values alike
        bad: np.ndarray = ~np.all(mag <= RUNAWAY, axis=2)
        limit_code = FAIL_TRACK
        if state_limits is None:
            pole: np.ndarray = mag[:, :, 1] > theta_max
            track: np.ndarray = mag[:, :, 0] >= track_limit
        else:
            pole, limit_code = np.zeros_like(bad), FAIL_STATE
            track = np.any(mag > state_limits, axis=2)
        end_bad: np.ndarray = ~np.all(np.abs(view.end) <= RUNAWAY, axis=1)
    bad[:, -1] |= end_bad if reset is None else end_bad | reset
    if bad_force is not None:
        bad[:, 0] |= bad_force
    any_fail: np.ndarray = bad | pole | track
    failed = np.any(any_fail, axis=1)
    if not failed.any():
        return failed, reason, None
    fail_step = np.where(failed, np.argmax(any_fail, axis=1), k)
    idx = np.nonzero(failed)[0]
    s = fail_step[idx]
    reason[idx] = np.where(bad[idx, s], FAIL_DIVERGED, np.where(pole[idx, s], FAIL_POLE, limit_code))
    failed.flags.writeable = reason.flags.writeable = False
    return failed, reason, fail_step


@functools.lru_cache(maxsize=64)
def _none_failed(n: int) -> tuple[np.ndarray, np.ndarray, None]:
    """:func:`detect_failure`'s answer when no row of ``n`` failed: made once per ``n`` (the
    common case of every period) and shared, hence read-only."""
    failed, reason = np.zeros(n, dtype=bool), np.zeros(n, dtype=np.int8)
    failed.flags.writeable = reason.flags.writeable = False
    return failed, reason, None


# ---- cost ---------------------------------------------------------------------------------------
def cost_weights(cost_Q: tuple[float, ...], cost_R: float, h: float, *,
                 matrix: np.ndarray | None = None) -> np.ndarray:
    """``h·[diag(Q), R]`` (n_x+1,): the weights of one physics step's ``z²`` in the period cost;
    or, given the full weight ``matrix`` ``[[Q, N], [Nᵀ, R]]`` (n_x+m, n_x+m) of an LTI plant
    with a full Q, a cross term or several inputs, ``h`` times it."""
    if matrix is not None:
        return h * np.asarray(matrix, dtype=float)
    return h * np.append(np.asarray(cost_Q, dtype=float), cost_R)


def period_cost(z: np.ndarray, weights: np.ndarray) -> np.ndarray:
    """``Σ_j Σ_i weights_i · z[j, i]²`` per row of a period's (n, k, 5) ``z`` (nothing masked);
    with a weight matrix (:func:`cost_weights`), ``Σ_j z[j]ᵀ weights z[j]``.

    One ``einsum`` (no temporaries the size of ``z``); a row's result does not depend on the other
    rows, so a batch and a single row give the same floats."""
    return period_cost_of(weights)(z, weights)


def period_cost_of(weights: np.ndarray) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """The sum :func:`period_cost` computes for ``weights``, as a function of ``(z, weights)``:
    the form (a vector of diagonal weights or a matrix) is the weights' own, so a caller that
    steps many periods with the same weights (the single env) chooses it once, not per period."""
    return _matrix_cost if weights.ndim == 2 else _diagonal_cost


def _diagonal_cost(z: np.ndarray, weights: np.ndarray) -> np.ndarray:
    return np.einsum("nki,nki,i->n", z, z, weights)          # weights h·[diag(Q), R]


def _matrix_cost(z: np.ndarray, weights: np.ndarray) -> np.ndarray:
    return np.einsum("nki,ij,nkj->n", z, weights, z)         # weights h·[[Q, N], [Nᵀ, R]]


def period_integrals(z: np.ndarray, fail_step: np.ndarray | None, *, h: float,
                     weights: np.ndarray) -> tuple[np.ndarray, float | np.ndarray, np.ndarray]:
    """The integrals of one control period — the one definition of the period's cost.

    With ``z = [x, u]`` at the start of each physics step and ``weights = h·[diag(Q), R]``,
    ``cost = Σ_j Σ_i weights_i · z[j, i]²``: the rectangle rule at the physics step h for
    ``∫ xᵀQx + R u² dt``, up to and including the step in which the episode failed.

    Parameters
    ----------
    z : (n, k, 5) ``[p, θ, ṗ, θ̇, u]`` at the start of each physics step: the period's initial
        state, then the states after physics steps 1 … k−1; ``u`` the applied (saturated) force
    fail_step : ``None`` if no row failed, else (n,) first failing physics step (``k`` if none)
    h : physics step [s]; weights : (5,) ``h·[diag(Q), R]``

    Returns
    -------
    z : (n, k, 5) the same, zeroed after a row's failing step;
    t_alive : alive time in the period [s], a float (``k·h``) when no row failed, else (n,);
    cost : (n,) ``∫ xᵀ diag(Q) x + R u² dt`` over the alive part of the period
    """
    k = z.shape[1]
    t_alive: float | np.ndarray
    if fail_step is None:
        t_alive = k * h
    else:
        mask = np.arange(k)[None, :] <= fail_step[:, None]                 # (n, k)
        t_alive = mask.sum(axis=1) * h
        z = np.where(mask[:, :, None], z, 0.0)
    return z, t_alive, period_cost(z, weights)


# ---- state noise --------------------------------------------------------------------------------
def end_of_period(view: PeriodView, w: np.ndarray | None) -> None:
    """The state at the end of the period, ``view.end``: the state after the k-th physics step plus
    the period's state-noise jump ``δx = w`` (``x ← x + δx``, drawn by
    :class:`~pendulum_lqg.core.noise.NoiseStream` with covariance ``W·T``), or unchanged when the
    process noise is off or enters as forces (``w = None``)."""
    if w is None:
        view.end[...] = view.last
    else:
        np.add(view.last, w, view.end)
