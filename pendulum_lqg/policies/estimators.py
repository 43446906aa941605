"""Runtime state estimators, vectorised over a batch of episodes.

Every estimator keeps the textbook intermediates of its last step as attributes (filterpy style) so
recordings and benchmarks can read them:

* ``x_prior`` — x̄[n], the estimate of x[n] before the measurement y[n] (kept until the next sample);
* ``x_hat`` — the estimate the controller uses at this sample;
* ``innovation`` — ``y − C x̄``;
* for Kalman filters ``P`` (a-posteriori covariance), ``M`` (a-priori) and ``gain``.

:meth:`Estimator.error_covariances` gives the covariance of ``x̂ − x`` at every sample of one
episode, from the filter's start (what an episode's figure draws as ``x̂ ± 2σ``): a steady-gain
filter's ``P`` is the limit it reaches, not its covariance during the start-up transient.

The interface is two calls per control period: ``estimate(y) -> x̂`` and then ``update(u)`` with the
input actually applied.

A lost sample (``Scenario.dropout``, or a measurement delay's first samples) arrives as a row of
``nan``: every estimator here then runs its prediction only for that row — the estimate is the
a-priori one (``x̂ = x̄``) and the next prior its time update with the input alone; the row's
``innovation`` is ``nan``. (The time-varying Kalman filter keeps the gain schedule of its age.)

Products with small matrices use ``einsum`` (no BLAS) so a row's result does
not depend on the batch size: batched and single-episode runs agree bit for bit.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Callable

import numpy as np

from pendulum_lqg.design.kalman import joseph_update, measurement_update
from pendulum_lqg.errors import ShapeError

_Step = Callable[[np.ndarray], np.ndarray]      # a covariance map M ↦ M′


def matvec(M: np.ndarray, X: np.ndarray) -> np.ndarray:
    """Row-wise ``M @ x`` for a batch ``X`` (n, j) → (n, i); bitwise independent of n
    (``einsum`` sums each row on its own, with no BLAS kernel choosing by size)."""
    return np.einsum("ij,nj->ni", M, X)


def lost_rows(y: np.ndarray) -> np.ndarray | None:
    """Rows of ``y`` with a nan (lost samples), or ``None`` when every entry is finite (one sum
    is the fast check)."""
    if math.isfinite(y.sum()):
        return None
    lost = ~np.isfinite(y).all(axis=1)
    return lost if lost.any() else None


def predict_only(lost: np.ndarray | None, prior: np.ndarray, posterior: np.ndarray,
                 ) -> np.ndarray:
    """``posterior`` with the lost rows replaced by their ``prior`` (no measurement update)."""
    return posterior if lost is None else np.where(lost[:, None], prior, posterior)


class Estimator(ABC):
    """Base: a batch of ``n`` estimates of ``x = [p, θ, ṗ, θ̇]``."""

    #: True if the estimator wants the true state instead of the measurement.
    needs_state: bool = False
    #: "current" (uses y[n] for x̂[n]) or "predictor" (x̂[n] uses y up to n−1).
    form: str = "current"

    def __init__(self, n_state: int = 4) -> None:
        self.n_state = n_state
        self._prior = np.zeros((0, n_state))      # running a-priori estimate for the next sample
        self.x_prior = np.zeros((0, n_state))
        self.x_hat = np.zeros((0, n_state))
        self.innovation = np.zeros((0, 2))

    def reset(self, x_hat0: np.ndarray, rows: np.ndarray | None = None) -> None:
        """Set the initial estimate (n, 4) — for all rows, or the given rows only."""
        x_hat0 = np.asarray(x_hat0, dtype=float)
        if x_hat0.ndim != 2 or x_hat0.shape[1] != self.n_state:
            raise ShapeError(f"x_hat0: expected shape (n, {self.n_state}), found {x_hat0.shape}")
        if rows is None:
            self._prior = x_hat0.copy()
            self.x_prior = x_hat0.copy()
            self.x_hat = x_hat0.copy()
            self.innovation = np.zeros((x_hat0.shape[0], 2))
        else:
            self._prior[rows] = x_hat0
            self.x_prior[rows] = x_hat0
            self.x_hat[rows] = x_hat0
            self.innovation[rows] = 0.0

    @abstractmethod
    def estimate(self, y: np.ndarray) -> np.ndarray:
        """Measurement (n, p) → the estimate x̂[n] (n, 4) the controller uses now."""

    @abstractmethod
    def update(self, u: np.ndarray) -> None:
        """Time update with the force (n, 1) actually applied over the coming period."""

    def select(self, rows: np.ndarray) -> None:
        """Keep only the given rows (episodes that ended are dropped from the batch)."""
        self._prior = self._prior[rows]
        self.x_prior = self.x_prior[rows]
        self.x_hat = self.x_hat[rows]
        self.innovation = self.innovation[rows]

    def error_covariances(self, received: np.ndarray) -> np.ndarray | None:
        """The covariance of ``x̂ − x`` at each sample ``k`` of one episode (N, n, n), started
        from the filter's a-priori covariance ``M0`` of ``x̄₀ − x₀``; ``received`` (N,) says which
        samples arrived (a lost one is a prediction only). ``None``: the estimator has no model
        of its error (no covariance, or none given at its start)."""
        return None


class TrueState(Estimator):
    """No observer: the controller sees the true state (the full-information reference)."""

    needs_state = True

    def estimate(self, y: np.ndarray) -> np.ndarray:
        self.x_prior = self.x_hat = np.array(y, dtype=float)
        self.innovation = np.zeros((self.x_hat.shape[0], 2))
        return self.x_hat

    def update(self, u: np.ndarray) -> None:
        return None


class FilterStart:
    r"""What a steady-gain filter's error covariance starts from and is driven by: the a-priori
    covariance ``M0`` of ``x̄₀ − x₀``, the process noise ``Qd`` per period and the measurement
    noise ``V``. The recursion does not depend on the data, only on which samples arrived, so the
    sequence of an episode whose every sample arrived is computed once and kept.

    .. math:: P_k = (I - LC) M_k (I - LC)^T + L V L^T,\qquad M_{k+1} = \Phi P_k \Phi^T + Q_d

    (current form; a lost sample has :math:`P_k = M_k`). With the steady gain it tends to the
    stationary :math:`P`, from :math:`M_0` instead of from :math:`P` itself.
    """

    def __init__(self, M0: np.ndarray, Qd: np.ndarray, V: np.ndarray) -> None:
        self.M0, self.Qd, self.V = (np.asarray(a, dtype=float) for a in (M0, Qd, V))
        self._kept: dict[tuple[str, int], np.ndarray] = {}

    def propagate(self, received: np.ndarray, update: _Step, Phi: np.ndarray) -> np.ndarray:
        """The a-posteriori covariances (N, n, n): ``update(M)`` the measurement update of an
        a-priori ``M``, ``Phi`` the time update."""
        return self._run("posterior", received, update, Phi)

    def propagate_prior(self, received: np.ndarray, step: _Step, Phi: np.ndarray) -> np.ndarray:
        """The a-priori covariances (N, n, n) of a predictor: ``step(M)`` the next ``M`` after a
        sample that arrived, ``Φ M Φᵀ + Q_d`` after a lost one."""
        return self._run("prior", received, step, Phi)

    def _run(self, kind: str, received: np.ndarray, step: _Step, Phi: np.ndarray) -> np.ndarray:
        received = np.asarray(received, dtype=bool)
        key = (kind, received.size)
        if received.all() and key in self._kept:
            return self._kept[key]
        out = np.empty((received.size, *self.M0.shape))
        M = self.M0
        for k, got in enumerate(received.tolist()):
            if kind == "posterior":
                out[k] = step(M) if got else M
                M = Phi @ out[k] @ Phi.T + self.Qd
            else:
                out[k] = M
                M = step(M) if got else Phi @ M @ Phi.T + self.Qd
        if received.all():
            self._kept[key] = out
        return out


class CurrentEstimator(Estimator):
    r"""Current-estimate (filter) form with a constant gain — steady-state Kalman or Luenberger.

    .. math:: \hat x_n = \bar x_n + L(y_n - C\bar x_n), \qquad
              \bar x_{n+1} = \Phi\hat x_n + \Gamma u_n
    """

    form = "current"

    def __init__(self, Phi: np.ndarray, Gamma: np.ndarray, C: np.ndarray, L: np.ndarray, *,
                 P: np.ndarray | None = None, M: np.ndarray | None = None,
                 start: FilterStart | None = None) -> None:
        super().__init__(Phi.shape[0])
        self.Phi, self.Gamma, self.C, self.gain = Phi, Gamma, C, L
        self.P, self.M = P, M                     # steady covariances (Kalman only)
        self.start = start

    def error_covariances(self, received: np.ndarray) -> np.ndarray | None:
        start = self.start
        if start is None:
            return None
        return start.propagate(received, lambda M: joseph_update(M, self.gain, self.C, start.V),
                               self.Phi)

    def estimate(self, y: np.ndarray) -> np.ndarray:
        self.x_prior = self._prior
        self.innovation = y - matvec(self.C, self.x_prior)                     # y − C x̄
        self.x_hat = self.x_prior + matvec(self.gain, self.innovation)         # x̂ = x̄ + L(y − Cx̄)
        self.x_hat = predict_only(lost_rows(y), self.x_prior, self.x_hat)
        return self.x_hat

    def update(self, u: np.ndarray) -> None:
        self._prior = matvec(self.Phi, self.x_hat) + matvec(self.Gamma, u)         # x̄⁺ = Φx̂ + Γu


class PredictorEstimator(Estimator):
    r"""Predictor form, a general affine recursion driven by the held input and the measurement.

    .. math:: \hat x_{n+1} = F\hat x_n + G_u u_n + G_y y_n

    For a discrete predictor observer ``F = Φ − L_p C``, ``G_u = Γ``, ``G_y = L_p``; for an emulated
    continuous observer (Kalman–Bucy) the ZOH of ``ẋ̂ = (A − LC)x̂ + Bu + Ly``. The control at sample
    n uses ``x̂_n``, which has seen measurements up to n − 1 only. A lost sample's row is predicted
    with the model alone, ``x̂_{n+1} = Φ x̂_n + Γ u_n`` (``Phi``, ``Gamma``; default ``F + G_y C`` and
    ``G_u``, exact for the discrete predictor).
    """

    form = "predictor"

    def __init__(self, F: np.ndarray, G_u: np.ndarray, G_y: np.ndarray, C: np.ndarray, *,
                 gain: np.ndarray | None = None, P: np.ndarray | None = None,
                 M: np.ndarray | None = None, Phi: np.ndarray | None = None,
                 Gamma: np.ndarray | None = None, start: FilterStart | None = None) -> None:
        super().__init__(F.shape[0])
        self.F, self.G_u, self.G_y, self.C = F, G_u, G_y, C
        self.Phi = F + G_y @ C if Phi is None else Phi
        self.Gamma = G_u if Gamma is None else Gamma
        self.gain = G_y if gain is None else gain
        self.P, self.M = P, M
        self.start = start
        self._y = np.zeros((0, C.shape[0]))

    def error_covariances(self, received: np.ndarray) -> np.ndarray | None:
        """The discrete predictor ``x̂⁺ = F x̂ + G_u u + G_y y`` (``F = Φ − G_y C``): its estimate
        is its prior, so its error covariance ``M`` steps as ``F M Fᵀ + G_y V G_yᵀ + Q_d`` after a
        sample that arrived (``Φ M Φᵀ + Q_d`` after a lost one)."""
        start = self.start
        if start is None:
            return None
        return start.propagate_prior(
            received, lambda M: self.F @ M @ self.F.T + self.G_y @ start.V @ self.G_y.T + start.Qd,
            self.Phi)

    def estimate(self, y: np.ndarray) -> np.ndarray:
        self._y = y
        self.x_prior = self.x_hat = self._prior
        self.innovation = y - matvec(self.C, self.x_prior)
        return self.x_hat

    def update(self, u: np.ndarray) -> None:
        self._prior = matvec(self.F, self.x_hat) + matvec(self.G_u, u) + matvec(self.G_y, self._y)
        lost = lost_rows(self._y)
        if lost is not None:                                # prediction only: Φ x̂ + Γ u
            model = matvec(self.Phi, self.x_hat) + matvec(self.Gamma, u)
            self._prior = predict_only(lost, model, self._prior)

    def select(self, rows: np.ndarray) -> None:
        super().select(rows)
        self._y = self._y[rows]


class TimeVaryingKalman(Estimator):
    r"""Time-varying discrete Kalman filter (current form) from an initial covariance ``M0``.

    .. math::
        P_a = M_a - M_aC^T(CM_aC^T + V)^{-1}CM_a,\quad L_a = P_aC^TV^{-1},\quad
        \hat x = \bar x + L_a(y - C\bar x),\quad M_{a+1} = \Phi P_a\Phi^T + Q_d

    where ``a`` is the number of samples since the episode started (``M_0 = M0``). The covariance
    recursion does not depend on the data, so the ``(M_a, P_a, L_a)`` sequence is computed once, as
    far as the oldest episode has got, and shared: rows that (re)start at different samples (a
    vector env's autoresets) each use the entry of their own age. Attributes ``M``, ``P``, ``gain``
    are those of the batch's age, or per row ``(n, …)`` while the rows' ages differ.
    """

    form = "current"

    def __init__(self, Phi: np.ndarray, Gamma: np.ndarray, C: np.ndarray, Qd: np.ndarray,
                 V: np.ndarray, M0: np.ndarray) -> None:
        super().__init__(Phi.shape[0])
        self.Phi, self.Gamma, self.C, self.Qd, self.V, self.M0 = Phi, Gamma, C, Qd, V, M0
        self._M: list[np.ndarray] = [M0.copy()]          # M_a, P_a, L_a for a = 0, 1, …
        self._P: list[np.ndarray] = []
        self._L: list[np.ndarray] = []
        self._age = np.zeros(0, dtype=np.int64)
        self.M, self.P = M0.copy(), M0.copy()
        self.gain = np.zeros((self.n_state, C.shape[0]))

    def _covariances(self, a: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(M_a, P_a, L_a)``, extending the shared sequence as needed."""
        C = self.C
        while len(self._P) <= a:
            M = self._M[len(self._P)]
            L, P = measurement_update(M, C, self.V)                   # Joseph form
            self._P.append(P)
            self._L.append(L)
            self._M.append(self.Phi @ P @ self.Phi.T + self.Qd)       # M⁺ = Φ P Φᵀ + Q_d
        return self._M[a], self._P[a], self._L[a]

    def covariances(self, a: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(M_a, P_a, L_a)`` of age ``a`` (the closed-form theory follows the gains)."""
        return self._covariances(a)

    def error_covariances(self, received: np.ndarray) -> np.ndarray | None:
        """The filter's own ``P_a`` at each age: its gain schedule is its covariance recursion
        from ``M0`` (a lost sample keeps the schedule, as the filter does)."""
        return np.array([self._covariances(a)[1] for a in range(len(received))])

    def reset(self, x_hat0: np.ndarray, rows: np.ndarray | None = None) -> None:
        super().reset(x_hat0, rows)
        if rows is None:
            self._age = np.zeros(self.x_hat.shape[0], dtype=np.int64)
        else:
            self._age[rows] = 0

    def estimate(self, y: np.ndarray) -> np.ndarray:
        C = self.C
        self.x_prior = self._prior
        self.innovation = y - matvec(C, self.x_prior)
        ages = np.unique(self._age)
        if ages.size <= 1:                                  # the whole batch at one age
            self.M, self.P, self.gain = self._covariances(int(ages[0]) if ages.size else 0)
            self.x_hat = self.x_prior + matvec(self.gain, self.innovation)
            self.x_hat = predict_only(lost_rows(y), self.x_prior, self.x_hat)
            return self.x_hat
        n = self._age.size
        self.M, self.P = np.empty((n, *self.M0.shape)), np.empty((n, *self.M0.shape))
        self.gain = np.empty((n, self.n_state, C.shape[0]))
        self.x_hat = np.empty_like(self.x_prior)
        for a in ages.tolist():                             # each age group with its own gain
            rows = np.nonzero(self._age == a)[0]
            M, P, L = self._covariances(a)
            self.M[rows], self.P[rows], self.gain[rows] = M, P, L
            self.x_hat[rows] = self.x_prior[rows] + matvec(L, self.innovation[rows])
        self.x_hat = predict_only(lost_rows(y), self.x_prior, self.x_hat)
        return self.x_hat

    def update(self, u: np.ndarray) -> None:
        self._prior = matvec(self.Phi, self.x_hat) + matvec(self.Gamma, u)
        self._age += 1

    def select(self, rows: np.ndarray) -> None:
        super().select(rows)
        self._age = self._age[rows]


class ReducedOrderEstimator(Estimator):
    r"""Reduced-order (minimal-order) observer: only the unmeasured part is estimated.

    With the design of :func:`~pendulum_lqg.design.dreduced_order_observer` (``[y; w] = T x``):

    .. math:: \hat x_n = T^{-1}\begin{bmatrix} y_n \\ z_n + G y_n\end{bmatrix},\qquad
              z_{n+1} = F z_n + H_y y_n + H_u u_n

    The measured part of ``x̂`` is the newest measurement itself (noise included); ``x_prior`` is
    the estimate reconstructed from the predicted ``z`` and ``innovation`` is 0 (there is no
    output correction term to log).
    """

    form = "current"

    def __init__(self, obs: object, C: np.ndarray) -> None:
        T = obs.T                                            # type: ignore[attr-defined]
        super().__init__(T.shape[0])
        self.C, self.gain = C, obs.G                         # type: ignore[attr-defined]
        self.F, self.H_y, self.H_u = obs.F, obs.H_y, obs.H_u  # type: ignore[attr-defined]
        self.T, self.T_inv = T, obs.T_inv                    # type: ignore[attr-defined]
        self.P = None
        p = C.shape[0]
        self._p = p
        self._z = np.zeros((0, T.shape[0] - p))
        self._y = np.zeros((0, p))

    def reset(self, x_hat0: np.ndarray, rows: np.ndarray | None = None) -> None:
        super().reset(x_hat0, rows)
        tx = matvec(self.T, np.asarray(x_hat0, dtype=float))     # [ŷ₀; ŵ₀]
        z0 = tx[:, self._p:] - matvec(self.gain, tx[:, :self._p])
        if rows is None:
            self._z = z0
            self._y = tx[:, :self._p].copy()
        else:
            self._z[rows] = z0
            self._y[rows] = tx[:, :self._p]

    def _reconstruct(self, y: np.ndarray) -> np.ndarray:
        w = self._z + matvec(self.gain, y)
        return matvec(self.T_inv, np.hstack([y, w]))

    def estimate(self, y: np.ndarray) -> np.ndarray:
        self.x_prior = self._reconstruct(self._y)
        lost = lost_rows(y)
        if lost is not None:            # a lost sample: hold the row's last measurement
            y = np.where(lost[:, None], self._y, y)
        self._y = y
        self.x_hat = self._reconstruct(y)
        self.innovation = np.zeros_like(y)
        return self.x_hat

    def update(self, u: np.ndarray) -> None:
        self._z = matvec(self.F, self._z) + matvec(self.H_y, self._y) + matvec(self.H_u, u)

    def select(self, rows: np.ndarray) -> None:
        super().select(rows)
        self._z, self._y = self._z[rows], self._y[rows]


class DelayKalman(Estimator):
    r"""Steady-state Kalman filter (current form) of the delay-augmented state, and the prediction
    over the actuator delay (:func:`pendulum_lqg.design.augment_delays`).

    .. math::
        \hat z_n = \bar z_n + L_a(y_n - C_a\bar z_n), \qquad
        \bar z_{n+1} = \Phi_a\hat z_n + \Gamma_a u_n, \qquad
        \hat x_{n+d_a|n} = \Pi\,\hat z_n

    :meth:`estimate` returns :math:`\hat x_{n+d_a|n}` — the state at which the force requested now
    will act — for the controller; ``x_hat`` / ``x_prior`` are the estimates of the *current*
    state :math:`x_n` (the first block of :math:`\hat z_n, \bar z_n`, what the estimation-error
    metrics compare with), ``x_control`` the prediction, ``z_hat`` the augmented estimate; ``P``
    and ``M`` the covariances of :math:`x_n` (``P_augmented``, ``M_augmented`` the whole ones).
    A row starts with the delay lines at 0: no output has arrived and no force is on its way.
    """

    form = "current"

    def __init__(self, Phi_a: np.ndarray, Gamma_a: np.ndarray, C_a: np.ndarray, L_a: np.ndarray,
                 predict: np.ndarray, *, P: np.ndarray, M: np.ndarray) -> None:
        super().__init__(predict.shape[0])
        self.Phi, self.Gamma, self.C, self.gain, self.predict = Phi_a, Gamma_a, C_a, L_a, predict
        self.P_augmented, self.M_augmented = P, M
        n = self.n_state
        self.P, self.M = P[:n, :n], M[:n, :n]
        self._z_prior = np.zeros((0, Phi_a.shape[0]))
        self.z_hat = np.zeros((0, Phi_a.shape[0]))
        self.x_control = np.zeros((0, n))

    def reset(self, x_hat0: np.ndarray, rows: np.ndarray | None = None) -> None:
        super().reset(x_hat0, rows)
        x_hat0 = np.asarray(x_hat0, dtype=float)
        z0 = np.zeros((x_hat0.shape[0], self.Phi.shape[0]))
        z0[:, :self.n_state] = x_hat0
        if rows is None:
            self._z_prior, self.z_hat = z0, z0.copy()
            self.x_control = matvec(self.predict, z0)
        else:
            self._z_prior[rows], self.z_hat[rows] = z0, z0
            self.x_control[rows] = matvec(self.predict, z0)

    def estimate(self, y: np.ndarray) -> np.ndarray:
        n = self.n_state
        z_prior = self._z_prior
        self.innovation = y - matvec(self.C, z_prior)                          # y − C_a z̄
        z_hat = z_prior + matvec(self.gain, self.innovation)                   # ẑ = z̄ + L_a(…)
        self.z_hat = predict_only(lost_rows(y), z_prior, z_hat)
        self.x_prior, self.x_hat = z_prior[:, :n], self.z_hat[:, :n]
        self.x_control = matvec(self.predict, self.z_hat)                      # x̂_{n+d_a|n} = Π ẑ
        return self.x_control

    def update(self, u: np.ndarray) -> None:
        self._z_prior = matvec(self.Phi, self.z_hat) + matvec(self.Gamma, u)       # z̄⁺ = Φ_a ẑ + Γ_a u

    def select(self, rows: np.ndarray) -> None:
        super().select(rows)
        self._z_prior, self.z_hat = self._z_prior[rows], self.z_hat[rows]
        self.x_control = self.x_control[rows]
