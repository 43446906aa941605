"""One control period of every row, in one buffer the physics, the rules and the metrics share.

Layout of :class:`PeriodBuffer`, ``(capacity, k+2, 5)`` float64, C-contiguous: for each row, the
``z = [p, θ, ṗ, θ̇, u]`` rows

* ``0`` — the state at the start of the period and the force of physics step 0,
* ``1 … k−1`` — the state after physics step j and the force of step j,
* ``k`` — the state after the last physics step (its ``u`` column is 0),
* ``k+1`` — the state at the end of the period, after the state noise (``u`` 0).

So ``z[:, :k]`` is ``[x, u]`` at the start of each physics step — what the cost integrates — and
``z[:, 1:k+1, :4]`` the state after each step — what the failure rule checks. A backend writes the
k states (rows 1 … k, columns 0 … 3), the loop the start state, the forces and the end state.

An LTI plant of ``n_x`` states and ``m`` inputs (:class:`~pendulum_lqg.model.interface.Layout`) has rows
``z = [x, u]`` of ``n_x + m`` numbers, the same layout: the width is the length of the bounds row.
"""

from __future__ import annotations

import numpy as np


def as_slice(values: np.ndarray) -> np.ndarray | slice:
    """``slice(a, a + n)`` when ``values`` are the consecutive integers ``a … a+n−1``, else
    ``values`` itself: a slice indexes a view (in-place sums, no gather and scatter)."""
    n = values.shape[0]
    if n and int(values[-1]) - int(values[0]) == n - 1 and (
            n == 1 or bool((np.diff(values) == 1).all())):
        return slice(int(values[0]), int(values[0]) + n)
    return values


#: The fast failure check's masks up to this many numbers are tested by their bytes, larger ones
#: by a reduction (:func:`~pendulum_lqg.core.rules.all_inside`; the faster way for each size).
SMALL_MASK = 8192


class PeriodBuffer:
    """The period buffer of a simulator with room for ``capacity`` rows (layout: module docstring).

    ``bounds_row`` (n_x+m,): the failure rule's fast-check bounds of one ``z`` row
    (:func:`~pendulum_lqg.core.rules.failure_bounds`), tiled over the buffer; its length is the
    width of a row. ``inputs``: m, the length of u (an LTI plant's may exceed 1).
    """

    def __init__(self, capacity: int, k: int, bounds_row: np.ndarray, *, inputs: int = 1) -> None:
        self.capacity, self.k, self.inputs = capacity, k, inputs
        width = bounds_row.shape[0]
        self.buf = np.zeros((capacity, k + 2, width))
        size = self.buf.size
        self.bounds = np.tile(bounds_row, size // width)
        self.scratch = np.empty(size)
        self.inside = np.empty(size, dtype=bool)
        self._views: dict[int, PeriodView] = {}

    def view(self, n: int) -> PeriodView:
        """The views of the first ``n`` rows (made once per row count: slicing a 3-d array costs as
        much as the small copies made through the slices)."""
        v = self._views.get(n)
        if v is None:
            v = self._views[n] = PeriodView(self, n)
        return v

    def __getstate__(self) -> dict[str, object]:
        return {**self.__dict__, "_views": {}}       # views pickle as copies: made again


class PeriodView:
    """The first ``n`` rows of a :class:`PeriodBuffer`, cut into named views.

    ``buf`` (n, k+2, 5); ``z`` (n, k, 5) ``[x, u]`` at the start of each physics step; ``states``
    (n, k, 4) the state after each step; ``u`` (n, k) the force of each step (``u_by_step``, its
    transpose); ``start``, ``last``, ``end`` (n, 4) the state at the start, after the k-th step
    and at the end of the period. For
    the fast failure check: ``flat`` the rows as one run of numbers, ``bounds`` a bound per
    number, ``scratch`` and ``inside`` its work arrays, ``small`` whether ``inside`` is at most
    :data:`SMALL_MASK` long. ``direct`` (1, k, 5), for one row only
    (else ``None``): the buffer's numbers 4 … 4+5k−1, where a backend may record in place.
    """

    def __init__(self, period: PeriodBuffer, n: int) -> None:
        k = period.k
        self.n, self.k = n, k
        self.buf = b = period.buf[:n]
        m = period.inputs
        nx = b.shape[2] - m                           # the state's length (the cart-pole's 4)
        self.z, self.states = b[:, :k], b[:, 1:k + 1, :nx]
        if m == 1:
            self.u = b[:, :k, nx]
            self.u_by_step = self.u.T                 # (k, n): a held force (n,) broadcasts in
        else:                                         # (n, k, m), and (k, n, m) for u (n, m)
            self.u = b[:, :k, nx:]
            self.u_by_step = self.u.swapaxes(0, 1)
        self.start, self.last, self.end = b[:, 0, :nx], b[:, k, :nx], b[:, k + 1, :nx]
        size = b.size
        self.flat, self.bounds = b.reshape(-1), period.bounds[:size]
        self.scratch, self.inside = period.scratch[:size], period.inside[:size]
        self.small = size <= SMALL_MASK
        # One row: its u at step 0 and rows 1 … k are one C-contiguous run of 5k numbers, which
        # read as k records [·, p, θ, ṗ, θ̇] — a backend recording [time, qpos, qvel] after each
        # step can write them in place (the times land in the u column, overwritten by the loop).
        self.direct = (b.reshape(-1)[nx:nx + (nx + 1) * k].reshape(1, k, nx + 1) if n == 1
                       else None)
