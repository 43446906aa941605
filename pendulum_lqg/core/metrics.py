"""Per-episode metrics streamed from the closed loop, and their aggregates.

Definitions (all integrals use the physics step h and the state at the start of each step, up to and
including the step in which the episode failed):

* ``cost`` — ``J = ∫ xᵀQx + uᵀRu dt`` (no ½; the optimal-cost check compares with ``x₀ᵀPx₀``);
* ``rms_*`` — ``sqrt(∫ s² dt / t_alive)``; ``max_abs_*`` — the largest magnitude seen, the
  sample that crossed a failure limit included;
* ``saturated_fraction`` — share of the alive time with ``|u|`` at the actuator limit;
* ``rms_est_err_*`` — RMS over control samples of ``x̂[n] − x[n]`` (the estimate the controller used);
* ``settling_time`` — the last time ``|θ|`` was above the scenario's ``settle_band`` (0 if never);
* ``time_to_failure`` — time of the first failing physics step (``nan`` for a success).

With a burn-in (``Scenario.burn_in``, ``skip`` whole control periods), the RMS metrics —
``rms_*``, ``rms_u`` and ``rms_est_err_*`` — take only the periods from ``skip`` on (their
integrals and their alive time); the cost, the maxima, the saturated fraction and the settling
time take the whole episode. Without one (the default) every sum is the one it always was.

The columns are named after the plant's :class:`~pendulum_lqg.model.interface.Layout`
(:func:`layout_fields`): the cart-pole's ``rms_theta``, ``rms_p``, … and the settling time of θ;
a plant file's ``rms_NAME`` and ``max_abs_NAME`` of every state, ``rms_est_err_NAME``, and no
settling time (it has no pole angle named as one).

Aggregates: success rate with its 95 % Wilson score interval; mean ± standard error for the rest.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from pendulum_lqg.core.rules import FAIL_NONE, FAIL_REASONS, period_integrals

if TYPE_CHECKING:
    from pendulum_lqg.model.interface import Layout


def est_fields(states: tuple[str, ...]) -> tuple[str, ...]:
    """The estimation-error columns of a plant with these state names."""
    return tuple(f"rms_est_err_{s}" for s in states)


def episode_fields(reported: tuple[str, ...], states: tuple[str, ...], *,
                   settle: bool, inputs: tuple[str, ...] = ("u",)) -> tuple[str, ...]:
    """The columns of one episode row: ``reported`` the states with RMS and max columns, in
    order; ``states`` every state (the estimation errors); ``settle`` a settling-time column;
    ``inputs`` the names of u (one input: ``u``), each with RMS and max columns."""
    per_state = [f"{kind}_{s}" for s in reported for kind in ("rms", "max_abs")]
    per_input = [f"{kind}_{s}" for s in inputs for kind in ("rms", "max_abs")]
    return ("episode", "seed", "success", "failure_reason", "time_to_failure", "duration", "cost",
            *per_state, *per_input, "saturated_fraction", *est_fields(states),
            *(("settling_time",) if settle else ()))


def layout_fields(layout: Layout) -> tuple[str, ...]:
    """The episode columns of a plant's :class:`~pendulum_lqg.model.interface.Layout`."""
    return episode_fields(tuple(layout.states[c] for c in layout.order), layout.states,
                          settle=layout.settle is not None, inputs=layout.inputs)


def summary_metrics(fields: tuple[str, ...]) -> tuple[str, ...]:
    """The metrics :func:`summarize` aggregates for episode rows with these columns."""
    return (*fields[fields.index("cost"):], "time_to_failure")




def _update(ids: np.ndarray | slice, arr: np.ndarray, op: Any, v: Any) -> None:
    """``arr[ids] = op(arr[ids], v)``, in place through a view when ``ids`` is a slice (``arr[ids]
    += v`` would also write the view back onto itself)."""
    view = arr[ids]
    if isinstance(ids, slice):
        op(view, v, out=view)
    else:
        arr[ids] = op(view, v)


class MetricsAccumulator:
    """Running sums per episode id; :meth:`rows` turns them into episode records.

    Parameters
    ----------
    n : episode ids expected (``0 … n−1``; the arrays grow if a larger id starts)
    h : physics step [s]; k : physics steps per control period
    weights : (5,) ``h·[diag(Q), R]`` (see :func:`~pendulum_lqg.core.rules.period_integrals`)
    u_max : actuator limit [N] (the saturated-time metric)
    settle_band : the ``|θ|`` band of the settling time [rad]
    layout : the plant's :class:`~pendulum_lqg.model.interface.Layout` (its columns)
    skip : control periods at the start of each episode left out of the RMS metrics (the
        burn-in; module docstring)

    ``ids`` given to :meth:`accumulate` may be an integer array or a ``slice`` (the batch's rows
    are episodes ``start … stop−1`` in order: in-place sums, no gather and scatter).
    """

    _SUMS = ("alive", "cost", "u2", "sat", "n_est", "settle", "max_u", "fail_time", "rms_alive")
    _ROWS = ("sq", "peak", "est2")
    # the running sums (one entry per episode id), made by _alloc from _SUMS; per reported state
    # column c (the layout's first ``m``): sq[:, c] = ∫ x_c² dt, peak[:, c] = max |x_c|
    alive: np.ndarray
    cost: np.ndarray
    u2: np.ndarray
    sat: np.ndarray
    n_est: np.ndarray
    settle: np.ndarray
    max_u: np.ndarray
    fail_time: np.ndarray
    rms_alive: np.ndarray           # the alive time after the burn-in (used only with one)

    def __init__(self, n: int, *, h: float, k: int, weights: np.ndarray, u_max: float | np.ndarray,
                 settle_band: float, layout: Layout, skip: int = 0) -> None:
        self.h, self.k = h, k
        # a period enters the RMS sums when its start time t ≥ (skip − ½)·T: t is a running
        # float sum of T, so half a period of margin decides exactly the periods n ≥ skip
        self.skip_time = (skip - 0.5) * k * h if skip > 0 else 0.0
        self.weights, self.u_max = weights, u_max
        self.band = settle_band
        lay = layout
        self.m, self.nx, self.order, self.settle_col = lay.reported, lay.n, lay.order, lay.settle
        self.names = tuple(lay.states[c] for c in lay.order)
        self.inputs = lay.inputs
        self.fields = layout_fields(lay)
        self.est_fields = est_fields(lay.states)
        self._steps = np.arange(1, k + 1)[:, None]      # (k, 1): 1 … k, the settling-time index
        self._alloc(max(n, 1))

    def _alloc(self, n: int) -> None:
        self.size = n
        for name in self._SUMS:
            setattr(self, name, np.zeros(n))
        self.sq, self.peak = np.zeros((n, self.m)), np.zeros((n, self.m))
        self.est2 = np.zeros((n, self.nx))
        if len(self.inputs) > 1:                   # per input: ∫ u_j² dt and max |u_j|
            self.u2, self.max_u = np.zeros((n, len(self.inputs))), np.zeros((n, len(self.inputs)))
        self.reason = np.zeros(n, dtype=np.int8)
        self.done = np.zeros(n, dtype=bool)
        self.fail_time[:] = np.nan

    def _grow(self, need: int) -> None:
        if need <= self.size:
            return
        old = {name: getattr(self, name) for name in (*self._SUMS, *self._ROWS, "reason", "done")}
        self._alloc(max(need, 2 * self.size))
        for name, arr in old.items():
            getattr(self, name)[: arr.shape[0]] = arr

    def start(self, ids: np.ndarray, x0: np.ndarray) -> None:
        self._grow(int(np.max(ids, initial=-1)) + 1)
        self.restart(ids)

    def restart(self, ids: np.ndarray) -> None:
        self._grow(int(np.max(ids, initial=-1)) + 1)
        for name in (*self._SUMS, *self._ROWS):
            getattr(self, name)[ids] = 0.0
        self.fail_time[ids] = np.nan
        self.reason[ids] = FAIL_NONE
        self.done[ids] = False

    def accumulate(self, ids: np.ndarray | slice, z: np.ndarray, u: np.ndarray,
                   x_hat: np.ndarray | None, failed: np.ndarray, reason: np.ndarray,
                   fail_step: np.ndarray | None, t: np.ndarray,
                   x_fail: np.ndarray | None = None) -> np.ndarray:
        """Add one control period (``z``, ``fail_step``: see
        :func:`~pendulum_lqg.core.rules.period_integrals`; ``u`` (n,)
        the applied force; ``x_fail`` (n, n_x) the state at the end of each row's failing step —
        the sample that crossed the limit, counted in the ``max_abs_*`` metrics); returns the
        period's cost per row."""
        h, m = self.h, self.m
        x_start = z[:, 0, :self.nx]
        z, t_alive, cost = period_integrals(z, fail_step, h=h, weights=self.weights)
        _update(ids, self.cost, np.add, cost)
        _update(ids, self.alive, np.add, t_alive)
        # after the burn-in (1.0 for every row without one: the sums below are then unchanged)
        keep = (t >= self.skip_time).astype(float) if self.skip_time else None
        if keep is not None:
            _update(ids, self.rms_alive, np.add, keep * t_alive)
        for c in self.order:                       # ∫ x_c² dt, column by column (the same sums)
            col = z[:, :, c]
            sq = h * np.einsum("nk,nk->n", col, col)
            _update(ids, self.sq[:, c], np.add, sq if keep is None else keep * sq)
        if u.ndim == 1:
            u2 = u * u * t_alive
            _update(ids, self.u2, np.add, u2 if keep is None else keep * u2)
            _update(ids, self.sat, np.add, (np.abs(u) >= self.u_max * (1 - 1e-12)) * t_alive)
        else:                                      # (n, m): saturated when any input is
            alive = np.asarray(t_alive)
            u2 = u * u * (alive[:, None] if alive.ndim else alive)
            _update(ids, self.u2, np.add, u2 if keep is None else keep[:, None] * u2)
            _update(ids, self.sat, np.add,
                    np.any(np.abs(u) >= self.u_max * (1 - 1e-12), axis=1) * t_alive)
        # |x_c| as (m, k, n), each component one contiguous block: the row maxima are then
        # one reduction over the middle axis with long inner loops (on the (n, k) views numpy
        # loops over k = 10 numbers at a time); a max is exact, so its order changes nothing
        a = np.abs(z[:, :, :m].transpose(2, 1, 0), order="C")
        row_max = a.max(axis=1)                                  # (m, n): max |x_c|
        for c in self.order:
            _update(ids, self.peak[:, c], np.maximum, row_max[c])
        _update(ids, self.max_u, np.maximum, np.abs(u))
        if self.settle_col is not None:
            self._settling(ids, a[self.settle_col], row_max[self.settle_col], t)
        if x_hat is not None:
            err = x_hat - x_start
            with np.errstate(over="ignore", invalid="ignore"):     # a diverged row: inf is honest
                np.multiply(err, err, out=err)
                _update(ids, self.est2, np.add, err if keep is None else keep[:, None] * err)
            _update(ids, self.n_est, np.add, 1.0 if keep is None else keep)
        if fail_step is not None:
            f = self._index(ids)[failed]
            if x_fail is not None:          # the crossing sample (nan of a diverged row ignored)
                self.peak[f] = np.fmax(self.peak[f], np.abs(x_fail[failed, :m]))
            self.fail_time[f] = t[failed] + (fail_step[failed] + 1) * h
            self.reason[f] = reason[failed]
            self.done[f] = True
        return cost

    def _settling(self, ids: np.ndarray | slice, a: np.ndarray, row_max: np.ndarray,
                  t: np.ndarray) -> None:
        """The settling time: the end of each row's last physics step with ``|x_c|`` (the pole's
        angle) above the band; ``a`` (k, n) the magnitudes, ``row_max`` (n,) their maxima. The
        alive part of z holds no nan (a nan state ends its episode at the step that made it), so
        a row's largest value is above the band exactly when one of its steps is."""
        has = row_max > self.band
        if has.any():
            # 1 + the index of each row's last step above the band (0: none), as an integer
            last = np.multiply(a > self.band, self._steps).max(axis=0)
            settled = t + last * self.h
            if isinstance(ids, slice):
                np.copyto(self.settle[ids], settled, where=has)
            else:
                self.settle[ids[has]] = settled[has]

    @staticmethod
    def _index(ids: np.ndarray | slice) -> np.ndarray:
        return np.arange(ids.start, ids.stop) if isinstance(ids, slice) else ids

    def rows(self, ids: np.ndarray, seeds: np.ndarray | None = None) -> list[dict[str, Any]]:
        """Episode records (:attr:`fields`, the layout's) for the ids.

        Computed column by column over the ids (the same IEEE divisions and square roots as one
        episode at a time, at a fraction of the per-number cost), then turned into dicts."""
        ids = np.asarray(ids, dtype=np.int64)
        raw_alive = self.alive[ids]
        alive = np.where(raw_alive > 0, raw_alive, np.nan)
        rms_time = self.rms_alive[ids] if self.skip_time else raw_alive
        rms_alive = np.where(rms_time > 0, rms_time, np.nan) if self.skip_time else alive
        n_est = self.n_est[ids]
        columns: dict[str, list[Any]] = {}
        with np.errstate(divide="ignore", invalid="ignore"):
            est = np.sqrt(self.est2[ids] / n_est[:, None])
            for c, name in zip(self.order, self.names, strict=True):
                columns[f"rms_{name}"] = np.sqrt(self.sq[ids, c] / rms_alive).tolist()
                columns[f"max_abs_{name}"] = self.peak[ids, c].tolist()
            u2, max_u = self.u2[ids].reshape(ids.size, -1), self.max_u[ids].reshape(ids.size, -1)
            for j, name in enumerate(self.inputs):
                columns[f"rms_{name}"] = np.sqrt(u2[:, j] / rms_alive).tolist()
                columns[f"max_abs_{name}"] = max_u[:, j].tolist()
            columns["saturated_fraction"] = (self.sat[ids] / alive).tolist()
        est[n_est <= 0] = np.nan
        for j, name in enumerate(self.est_fields):
            columns[name] = est[:, j].tolist()
        if self.settle_col is not None:
            columns["settling_time"] = self.settle[ids].tolist()
        reason = self.reason[ids].tolist()
        time_to_failure, duration = self.fail_time[ids].tolist(), raw_alive.tolist()
        cost = self.cost[ids].tolist()
        seed_list = [-1] * ids.size if seeds is None else np.asarray(seeds).tolist()
        metrics = self.fields[7:]                    # after "cost", in order
        out: list[dict[str, Any]] = []
        for i, e in enumerate(ids.tolist()):
            row: dict[str, Any] = {
                "episode": e,
                "seed": int(seed_list[i]),
                "success": reason[i] == FAIL_NONE,
                "failure_reason": FAIL_REASONS[reason[i]],
                "time_to_failure": time_to_failure[i],
                "duration": duration[i],
                "cost": cost[i],
            }
            for name in metrics:
                row[name] = columns[name][i]
            out.append(row)
        return out


def wilson_interval(successes: int, n: int, z: float = 1.959963984540054) -> tuple[float, float]:
    """95 % Wilson score interval of a binomial proportion (Wilson 1927)."""
    if n <= 0:
        return (float("nan"), float("nan"))
    p = successes / n
    denom = 1 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / denom
    return (max(0.0, centre - half), min(1.0, centre + half))


def mean_se(values: np.ndarray) -> tuple[float, float]:
    """Mean and standard error of the finite values (nan if there are none)."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return (float("nan"), float("nan"))
    se = float(v.std(ddof=1) / math.sqrt(v.size)) if v.size > 1 else float("nan")
    return (float(v.mean()), se)


def _row_metrics(rows: list[dict[str, Any]]) -> tuple[str, ...]:
    """The metrics of these rows: those of the rows' own columns (from ``cost`` on; none for
    rows without one)."""
    keys = tuple(rows[0]) if rows else ()
    if "cost" not in keys:
        return ()
    return tuple(dict.fromkeys((*summary_metrics(keys), "time_to_failure")))


def summarize(rows: list[dict[str, Any]], metrics: tuple[str, ...] | None = None,
              ) -> dict[str, Any]:
    """Aggregate episode rows: success rate with Wilson 95 % CI, mean ± SE of each metric
    (``metrics``: by default :func:`summary_metrics` of the rows' own columns, so any plant is
    summarised by its state names).

    ``cost`` and ``settling_time`` are averaged over the successful episodes only (a failed
    episode's cost stops at the failure and would flatter it); the others over all episodes, and
    ``time_to_failure`` over the failures.
    """
    if metrics is None:
        metrics = _row_metrics(rows)
    n = len(rows)
    succ = np.array([bool(r["success"]) for r in rows], dtype=bool)
    s = int(succ.sum())
    lo, hi = wilson_interval(s, n)
    out: dict[str, Any] = {"episodes": n, "successes": s,
                              "success_rate": s / n if n else float("nan"),
                              "success_ci95": [lo, hi]}
    reasons: dict[str, int] = {}
    for r in rows:
        if r["failure_reason"]:
            reasons[str(r["failure_reason"])] = reasons.get(str(r["failure_reason"]), 0) + 1
    out["failures"] = reasons
    for name in metrics:
        vals = np.array([float(r[name]) for r in rows], dtype=np.float64)
        if name in ("cost", "settling_time"):
            vals = vals[succ]
        elif name == "time_to_failure":
            vals = vals[~succ]
        mean, se = mean_se(vals)
        out[name] = {"mean": mean, "se": se}
    return out
