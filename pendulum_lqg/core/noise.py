"""Process and measurement noise with explicit units, drawn from per-episode generators.

Units (docs/theory.md §3.7) — every parameter says which kind it is:

* ``process_density`` is a **continuous-time spectral density** (diagonal of W):

  - ``process="state"`` (F = I₄, the lecture model): ``ẋ = f(x, u) + w``, W in
    ``[m²/s², rad²/s², m²/s⁴, rad²/s⁴] · s``. The simulator adds a jump ``δx ~ N(0, W·T)`` to the
    state once per control period T — exactly the lecture's ``x ← x + T·w`` with
    ``w ~ N(0, Σ_w)`` when ``W = Σ_w·T`` (``Σ_w = 0.04·I₄`` at T = 0.01 s gives W = 4·10⁻⁴·I₄).
  - ``process="force"``: ``M q̈ = … + f``, generalised forces ``f = [N, N·m]`` with density W in
    ``[N², N²m²]·s``, applied through ``qfrc_applied`` and redrawn every physics step h as
    ``f ~ N(0, W/h)`` (the sampled equivalent of white noise).

* ``measurement_variance`` is a **per-sample covariance** (diagonal of V) of ``v`` in
  ``y[n] = [p, θ] + v[n]``, units ``[m², rad²]``.

``scale`` multiplies the standard deviations of both noises (covariances by ``scale²``); 0 is
noise-free. The estimator designs use the nominal (``scale = 1``) model unless told otherwise.

Randomness: each episode owns a ``numpy.random.Generator``. Normals are drawn in order from it,
in blocks of at most :data:`CHUNK_PERIODS` control periods with a fixed layout, so an episode's
noise is the same whether it runs alone or in a batch, and memory does not grow with the episode
length.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import Literal

import numpy as np

from pendulum_lqg.errors import ConfigError, PendulumLQGError
from pendulum_lqg.problem import defaults
from pendulum_lqg.problem.declare import Converted, NonNegative, check, config_vector
from pendulum_lqg.util.limits import MAX_NOISE_SCALE

#: Where process noise enters: on the state (F = I₄) or as generalised forces.
Process = Literal["state", "force"]

#: Control periods of noise drawn at once per episode.
CHUNK_PERIODS = 256

#: With a ``horizon`` (:meth:`NoiseStream.reset`), each episode first draws this many periods,
#: then the rest in large blocks, a share of the batch per period (a staggered ring).
FIRST_PERIODS = 8

#: Held while a batch's generators draw one after another (a noise refill, the initial states), so
#: that the shards of a run take turns: each numpy draw releases and retakes the GIL, and two
#: shards drawing at once would contend for it at every one of their hundreds of draws, while in
#: turns one shard draws as the other's physics runs (the physics holds no GIL). The lock orders
#: nothing that changes a number: each row draws from its own generator.
DRAW_LOCK = threading.Lock()

#: The lecture's per-step process-noise covariance of w (``x ← x + T·w``) and its period.
LECTURE_W_STEP = 0.04
LECTURE_PERIOD = 0.01
LECTURE_V = defaults.MEASUREMENT_VARIANCE


def _scale(name: str, value: object) -> float:
    """``scale``, a number ≥ 0 up to the ceiling; its errors name the setting, ``noise_scale``."""
    scale = float(check("noise_scale", value, NonNegative))
    if scale > MAX_NOISE_SCALE:
        raise ConfigError(f"noise_scale: expected at most {MAX_NOISE_SCALE:g} (the "
                          f"ceiling), got {value!r}")
    return scale


class _Density(Converted[tuple[float, ...]]):
    """``process_density``: as many numbers ≥ 0 as the process has (4 on the state, 2 as
    forces; one number is repeated) — the ``process`` field, set before it, says which."""

    def __init__(self) -> None:
        super().__init__(lambda name, value: value, (LECTURE_W_STEP * LECTURE_PERIOD,) * 4)

    def __set__(self, obj: object, value: tuple[float, ...]) -> None:
        n = 4 if obj.__dict__["process"] == "state" else 2
        obj.__dict__[self.name] = config_vector(self.name, value, n, nonneg=True)


@dataclass(frozen=True)
class NoiseModel:
    """Noise of one scenario (see the module docstring for units).

    Attributes
    ----------
    process : "state" (F = I₄) or "force" (generalised forces on slider and hinge)
    process_density : diagonal of the continuous spectral density W (4 entries for "state",
        2 for "force")
    measurement_variance : diagonal of the per-sample covariance V of y = [p, θ]
    scale : multiplies both noises' standard deviations (0 = noise-free)
    """

    process: Converted[Process] = Converted(lambda name, value: check(name, value, Process), "state")
    process_density: _Density = _Density()
    measurement_variance: Converted[tuple[float, ...]] = Converted(
        lambda name, value: config_vector(name, value, 2, nonneg=True), (LECTURE_V, LECTURE_V))
    scale: Converted[float] = Converted(_scale, defaults.NOISE_SCALE)

    @classmethod
    def lecture(cls, *, scale: float = defaults.NOISE_SCALE) -> NoiseModel:
        """The lecture scenario: V = 0.01·I₂ per sample; ``x ← x + T·w``, w ~ N(0, 0.04·I₄) at
        T = 0.01 s, i.e. a state-noise density W = 0.04 · 0.01 · I₄ = 4·10⁻⁴·I₄."""
        return cls(scale=scale)

    def with_scale(self, scale: float) -> NoiseModel:
        return NoiseModel(self.process, self.process_density, self.measurement_variance, scale)

    # ---- matrices for the designs (nominal, i.e. without ``scale``) ------------------------
    @property
    def W(self) -> np.ndarray:
        """Continuous process-noise spectral density (nominal)."""
        return np.diag(self.process_density)

    @property
    def V(self) -> np.ndarray:
        """Per-sample measurement covariance (nominal)."""
        return np.diag(self.measurement_variance)

    def V_density(self, dt: float) -> np.ndarray:
        """Measurement density equivalent to per-sample covariance V at period dt: ``V·dt``."""
        return self.V * dt


class NoiseStream:
    """Per-episode noise for a batch, drawn in fixed blocks from each episode's own generator.

    Each control period consumes, per episode, ``n_proc`` process normals (``4`` for state noise,
    ``2·k`` for force noise redrawn every physics step) followed by 2 measurement normals. A block
    of :data:`CHUNK_PERIODS` periods (fewer with a ``horizon``, :meth:`reset`) is drawn at once
    and scaled to physical units on the spot, so a period's draw is a view: the state jump ``δx``
    (or the ``k`` generalised forces) and the measurement noise ``v``. The block is stored
    period-major, ``(periods, n, width)``, so a period's noise of the whole batch is one
    contiguous slab, read in one sweep of memory rather than one cache line per episode.

    While every row is at the same period (a batch run, or a single env) the stream keeps one
    cursor for all rows; per-row draws (vector envs, whose rows restart at different periods) switch
    it to per-row positions. Both give the same numbers.
    """

    def __init__(self, noise: NoiseModel, *, steps_per_period: int, dt: float, h: float,
                 covariances: tuple[np.ndarray, np.ndarray] | None = None) -> None:
        self.noise = noise
        self.k = steps_per_period
        s = noise.scale
        self._mix: np.ndarray | None = None          # see _lti_noise
        if covariances is not None:
            self.proc_std, self.meas_std = self._lti_noise(covariances, s)
        elif noise.process == "state":
            self.proc_std = s * np.sqrt(np.asarray(noise.process_density) * dt)   # δx per period
        else:
            self.proc_std = s * np.sqrt(np.asarray(noise.process_density) / h)    # f per step
        if covariances is None:
            self.meas_std = s * np.sqrt(np.asarray(noise.measurement_variance))
        self.n_proc = (2 * steps_per_period if noise.process == "force" and covariances is None
                       else self.proc_std.size)
        self.n_meas = self.meas_std.size
        self.width = self.n_proc + self.n_meas
        self.enabled = bool(s > 0 and (np.any(self.proc_std > 0) or np.any(self.meas_std > 0)))
        # std of each column of a period: process (force noise: [slider, hinge] per physics
        # step), then measurement
        self._scale = np.concatenate([np.tile(self.proc_std, self.n_proc // self.proc_std.size),
                                      self.meas_std])
        self._gens: list[np.random.Generator] = []
        self._chunk = CHUNK_PERIODS                          # periods per block
        self._set_block(np.zeros((self._chunk, 0, self.width)))
        self._unit = np.empty((self._chunk, self.width))     # one episode's normals, as drawn
        self._pos = np.zeros(0, dtype=np.int64)
        self._cursor: int | None = self._chunk       # the common position, or None (per row)
        self._horizon: int | None = None             # set: the staggered ring of a batch run
        self._period = 0                             # ring: periods drawn by the batch so far
        self._group = np.zeros(0, dtype=np.int64)    # ring: each row's top-up group
        self._drawn: list[int] = []                  # ring: periods in the ring, per group

    def _lti_noise(self, covariances: tuple[np.ndarray, np.ndarray], s: float,
                   ) -> tuple[np.ndarray, np.ndarray]:
        """An LTI plant's noise (its :class:`~pendulum_lqg.model.interface.Layout`'s covariances):
        the state's jump over a period
        ``δx ~ N(0, s²·Wd)`` and ``v ~ N(0, s²·V)``, each from as many unit normals as it has
        entries. Diagonal covariances scale the normals column by column (as the cart-pole's); a
        full one mixes them, ``[δx, v] = F z`` with ``F Fᵀ = s²·blockdiag(Wd, V)`` (Cholesky, or
        ``U √Λ`` of the eigendecomposition of a singular one). Returns the standard deviations."""
        covs = [np.asarray(c, dtype=float) for c in covariances]
        if any(np.any(c != np.diag(np.diag(c))) for c in covs):    # some block is full: mix
            Fw, Fv = (_factor(c) for c in covs)
            p, m = Fw.shape[0], Fv.shape[0]
            mix = np.zeros((p + m, p + m))
            mix[:p, :p], mix[p:, p:] = Fw, Fv
            self._mix = s * mix.T                    # a row of normals @ Fᵀ: one period's draw
        proc, meas = (s * np.sqrt(np.diag(c)) for c in covs)
        return proc, meas

    @property
    def n(self) -> int:
        return len(self._gens)

    def reset(self, generators: list[np.random.Generator], rows: np.ndarray | None = None, *,
              horizon: int | None = None) -> None:
        """Attach generators (all rows, or the given rows of an existing batch).

        ``horizon``: the generators serve these episodes only and none runs more than ``horizon``
        periods (a batch run). The noise is then drawn no further than that, and not all at the
        first period: each episode draws its first :data:`FIRST_PERIODS` periods there, and the
        rest in blocks of up to :data:`CHUNK_PERIODS` periods into a ring, one share of the
        batch per period (a 200-period run of 512 episodes: 64 episodes draw their periods
        8 … 199 at each of the periods 0 … 7). The numbers are the same — each episode's normals
        are drawn in order, whatever the blocks — and a run's threads do not all draw their whole
        batch at once before their physics can start (:data:`DRAW_LOCK`). Leave it ``None``
        when a generator outlives its episode (gymnasium envs: the next episode continues it, so
        where the noise stopped drawing is part of the results); per-row draws need that.
        """
        if rows is None:
            self._gens = list(generators)
            n = len(generators)
            self._horizon = None if horizon is None else max(1, int(horizon))
            self._chunk = (CHUNK_PERIODS if self._horizon is None
                           else min(CHUNK_PERIODS, self._horizon))
            self._set_block(np.zeros((self._chunk, n, self.width)))
            self._unit = np.empty((self._chunk, self.width))
            self._pos = np.full(n, self._chunk, dtype=np.int64)
            self._cursor = self._chunk
            if self._horizon is not None:
                first = min(FIRST_PERIODS, self._chunk)
                self._period = 0
                self._group = np.arange(n) % first
                self._drawn = [0] * first
        else:
            self._per_row()
            for r, g in zip(rows, generators, strict=True):
                self._gens[r] = g
            self._pos[rows] = self._chunk

    def _set_block(self, block: np.ndarray) -> None:
        """The block of drawn noise (periods, rows, width) and its process and measurement parts,
        views made once per block (a period's draw is then one index into each)."""
        self._block = block
        self._proc_block, self._meas_block = block[:, :, : self.n_proc], block[:, :, self.n_proc:]

    def __getstate__(self) -> dict[str, object]:
        state = dict(self.__dict__)
        del state["_proc_block"], state["_meas_block"]     # views would pickle as copies
        return state

    def __setstate__(self, state: dict[str, object]) -> None:
        self.__dict__.update(state)
        self._set_block(self._block)

    def _per_row(self) -> None:
        """Leave the common cursor: from now on each row keeps its own position."""
        if self._horizon is not None:
            raise PendulumLQGError("noise: per-row draws and resets need generators that outlive "
                                   "their episodes (a stream reset without a horizon)")
        if self._cursor is not None:
            self._pos[:] = self._cursor
            self._cursor = None

    def _draw(self, rows: list[int] | range, start: int, stop: int) -> None:
        """Periods ``start … stop−1`` of each of ``rows`` into the block (period q in slot
        q mod the block's periods: fixed blocks draw 0 … chunk−1, the ring wraps), scaled to
        physical units, the rows taking :data:`DRAW_LOCK` together."""
        c = self._chunk
        m, a = stop - start, start % c
        unit = self._unit[:m]
        split = min(m, c - a)                               # the part before the ring wraps
        scale = np.multiply if self._mix is None else np.matmul     # (see _lti_noise)
        by = self._scale if self._mix is None else self._mix
        with DRAW_LOCK:
            for r in rows:
                self._gens[r].standard_normal(out=unit)
                scale(unit[:split], by, out=self._block[a:a + split, r])
                if split < m:
                    scale(unit[split:], by, out=self._block[:m - split, r])

    def _draw_staggered(self) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`draw` of every row with a horizon: the ring, topped up one group at a time."""
        p, c, h = self._period, self._chunk, self._horizon
        assert h is not None
        if p >= h:
            raise PendulumLQGError(f"noise: period {p} drawn, past the horizon of {h} periods")
        groups = len(self._drawn)
        if p == 0:                                   # every episode's first periods
            self._draw(range(self.n), 0, groups)
            self._drawn = [groups] * groups
        g = p % groups
        drawn = self._drawn[g]
        # top up group g when its ring would not last until the group's next turn (p + groups),
        # or holds at most half a block ahead — never past period p + c − 1 (slot p mod c is
        # this period's)
        ahead = drawn - p
        if drawn < h and (ahead < groups or ahead <= c // 2):
            stop = min(p + c, h)
            self._draw(np.flatnonzero(self._group == g).tolist(), drawn, stop)
            self._drawn[g] = stop
        self._period = p + 1
        return self._proc_block[p % c], self._meas_block[p % c]

    def draw(self, rows: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The next period's noise of each row (default: every row), in physical units.

        Returns the process noise ``(len, n_proc)`` (state noise: the jump ``δx``; force noise:
        see :meth:`forces`) and the measurement noise ``v`` ``(len, 2)``. They may be views of the
        stream's block: use them before the next draw.
        """
        if not self.enabled:
            n = self.n if rows is None else len(rows)
            return np.zeros((n, self.n_proc)), np.zeros((n, self.n_meas))
        if self._horizon is not None:
            if rows is not None:
                self._per_row()                          # raises: not with a horizon
            return self._draw_staggered()
        c = self._cursor
        if rows is None and c is not None:                # the whole batch in step
            if c == self._chunk:
                self._draw(range(self.n), 0, c)
                c = 0
            self._cursor = c + 1
            return self._proc_block[c], self._meas_block[c]
        self._per_row()
        every = rows is None            # every row at its own position: no gather of positions
        idx = np.arange(self.n) if rows is None else np.asarray(rows)
        pos = self._pos if every else self._pos[idx]
        due = pos >= self._chunk
        if np.count_nonzero(due):
            refill = idx[due]
            self._draw(refill.tolist(), 0, self._chunk)
            self._pos[refill] = 0
            pos = self._pos if every else self._pos[idx]
        z = self._block[pos, idx]
        if every:
            pos += 1
        else:
            self._pos[idx] += 1
        return z[:, : self.n_proc], z[:, self.n_proc:]

    def select(self, rows: np.ndarray) -> None:
        """Keep only these rows (their generators and undrawn blocks).

        ``rows`` is increasing, so the blocks are compacted in place: dropping finished episodes
        never allocates a second copy of the (largest) noise buffer.
        """
        rows = np.asarray(rows)
        self._gens = [self._gens[r] for r in rows]
        if rows.size > 1 and np.any(np.diff(rows) <= 0):
            self._set_block(self._block[:, rows])    # not increasing: plain copy
        else:
            for i, r in enumerate(rows.tolist()):
                if i != r:
                    self._block[:, i] = self._block[:, r]
            self._set_block(self._block[:, : rows.size])
        self._pos = self._pos[rows]
        if self._horizon is not None:
            self._group = self._group[rows]

    def forces(self, w: np.ndarray) -> np.ndarray:
        """Generalised forces (len, k, 2) of a force-noise draw, one per physics step."""
        return w.reshape(-1, self.k, 2)


def _factor(cov: np.ndarray) -> np.ndarray:
    """F with ``F Fᵀ = cov`` (PSD): Cholesky, or ``U √Λ`` of a singular one."""
    try:
        return np.linalg.cholesky(cov)
    except np.linalg.LinAlgError:                     # singular (noise on a subspace)
        lam, U = np.linalg.eigh(cov)
        return U * np.sqrt(np.clip(lam, 0.0, None))


class UniformStream:
    """Per-episode uniforms in [0, 1), one per control period, in blocks of :data:`CHUNK_PERIODS`.

    The random sample losses (``Scenario.dropout``) are drawn here, from each episode's *child*
    generator (see :func:`pendulum_lqg.core.seeding.child_generator`), so the episode's noise stream is the
    same with and without dropouts. Like :class:`NoiseStream`, each row keeps its own position, so
    rows may restart at different periods (vector envs) and a row's draws do not depend on the batch.
    """

    def __init__(self) -> None:
        self._gens: list[np.random.Generator] = []
        self._block = np.zeros((0, CHUNK_PERIODS))
        self._pos = np.zeros(0, dtype=np.int64)

    def reset(self, generators: list[np.random.Generator], rows: np.ndarray | None = None) -> None:
        """Attach generators (all rows, or the given rows of an existing batch)."""
        if rows is None:
            self._gens = list(generators)
            self._block = np.zeros((len(generators), CHUNK_PERIODS))
            self._pos = np.full(len(generators), CHUNK_PERIODS, dtype=np.int64)
            return
        for r, g in zip(np.asarray(rows).tolist(), generators, strict=True):
            self._gens[r] = g
        self._pos[rows] = CHUNK_PERIODS

    def draw(self, rows: np.ndarray | None = None) -> np.ndarray:
        """The next period's uniform of each row (default: every row), shape (len,)."""
        rows = np.arange(len(self._gens)) if rows is None else np.asarray(rows)
        for r in rows[self._pos[rows] >= CHUNK_PERIODS].tolist():   # once per CHUNK_PERIODS
            self._gens[r].random(out=self._block[r])
            self._pos[r] = 0
        pos = self._pos[rows]
        self._pos[rows] += 1
        return self._block[rows, pos]

    def select(self, rows: np.ndarray) -> None:
        """Keep only these rows."""
        self._gens = [self._gens[r] for r in np.asarray(rows).tolist()]
        self._block = self._block[rows]
        self._pos = self._pos[rows]
