r"""Loop gains, stability margins and loop transfer recovery — pure functions of matrices.

Every loop here is broken at the **plant input** (the cart force), the point where the LQ guarantees
hold. With the sign convention ``u = −K x̂`` the loop gain is what a unit signal injected at the
input comes back as, negated, so the closed loop is ``1 / (1 + L)``:

* LQ (state feedback, continuous): :math:`L(s) = K(sI - A)^{-1}B`;
* LQ sampled (state feedback at period T): :math:`L(z) = K(zI - \Phi)^{-1}\Gamma`;
* LQG (observer-based compensator :math:`C_K` from ``y`` to ``−u``, plant :math:`P = C(sI-A)^{-1}B`):
  :math:`L = C_K P` with :math:`C_K(s) = K(sI - A + BK + LC)^{-1}L` (continuous), and the discrete
  predictor / current-estimator compensators of :func:`predictor_compensator` /
  :func:`current_compensator`.

Kalman inequality (Kalman 1964; Anderson & Moore, *Optimal Control*, §5.4): for an LQR with
``R > 0`` the return difference satisfies

.. math::
    (1 + L(-j\omega))^T R\, (1 + L(j\omega))
      = R + B^T(-j\omega I - A^T)^{-1} Q (j\omega I - A)^{-1} B \;\ge\; R
    \;\Rightarrow\; |1 + L(j\omega)| \ge 1 \quad\text{(single input)},

so the Nyquist curve of the LQ loop stays outside the unit disc centred on −1: gain margin
``[1/2, ∞)`` and phase margin ≥ 60°. An observer-based (LQG) loop has no such guarantee (Doyle 1978).
Loop transfer recovery (Doyle & Stein 1979): designing the Kalman filter with ``W = q² B Bᵀ`` (noise
entering like the input) and ``V`` fixed makes the LQG loop tend to the LQ loop as ``q → ∞`` — if the
plant ``C(sI − A)⁻¹B`` has no transmission zeros in the right half plane.

No MuJoCo here; python-control evaluates frequency responses and disk margins.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass

import control
import numpy as np
from numpy.typing import ArrayLike

from pendulum_lqg.design import kalman
from pendulum_lqg.design.checks import as_loop, as_matrix
from pendulum_lqg.errors import ConfigError


# ---- loops ---------------------------------------------------------------------------------------
def lq_loop(A: ArrayLike, B: ArrayLike, K: ArrayLike, *, dt: float | None = None,
            ) -> control.StateSpace:
    r"""State-feedback loop broken at the plant input, :math:`L = K(sI - A)^{-1}B`.

    Parameters
    ----------
    A : (n, n), B : (n, m), K : (m, n) — continuous ``(A, B)`` or discrete ``(Φ, Γ)``
    dt : sample period of a discrete loop (``None``: continuous)

    Returns
    -------
    (m × m) state-space loop gain.
    """
    A = as_matrix("A", A)
    n = A.shape[0]
    B = as_matrix("B", B, (n, None))
    K = as_matrix("K", K, (B.shape[1], n))
    return control.ss(A, B, K, np.zeros((K.shape[0], B.shape[1])), dt=0 if dt is None else dt)


def plant(A: ArrayLike, B: ArrayLike, C: ArrayLike, *, dt: float | None = None,
          ) -> control.StateSpace:
    """The plant ``P = C(sI − A)⁻¹B`` (no feedthrough): (p × m) state space."""
    A = as_matrix("A", A)
    n = A.shape[0]
    B = as_matrix("B", B, (n, None))
    C = as_matrix("C", C, (None, n))
    return control.ss(A, B, C, np.zeros((C.shape[0], B.shape[1])), dt=0 if dt is None else dt)


def lqg_compensator(A: ArrayLike, B: ArrayLike, C: ArrayLike, K: ArrayLike, L: ArrayLike,
                    ) -> control.StateSpace:
    r"""Continuous observer-based compensator from ``y`` to ``−u``.

    .. math::
        \dot{\hat x} = (A - BK - LC)\hat x + Ly, \qquad -u = K\hat x

    Parameters
    ----------
    A : (n, n), B : (n, m), C : (p, n), K : (m, n), L : (n, p)
    """
    A, B, C, K, L = as_loop(A, B, C, K, L)
    return control.ss(A - B @ K - L @ C, L, K, np.zeros((K.shape[0], C.shape[0])))


def predictor_compensator(F: ArrayLike, G_u: ArrayLike, G_y: ArrayLike, K: ArrayLike, *,
                          dt: float) -> control.StateSpace:
    r"""Discrete compensator of a predictor-type estimator, from ``y`` to ``−u``.

    The estimator :math:`\hat x[n+1] = F\hat x[n] + G_u u[n] + G_y y[n]` with
    :math:`u[n] = -K\hat x[n]` gives

    .. math::
        \hat x[n+1] = (F - G_uK)\hat x[n] + G_y y[n], \qquad -u[n] = K\hat x[n].

    (The textbook predictor has ``F = Φ − L_pC``, ``G_u = Γ``, ``G_y = L_p``.)
    """
    F = as_matrix("F", F)
    n = F.shape[0]
    G_u = as_matrix("G_u", G_u, (n, None))
    G_y = as_matrix("G_y", G_y, (n, None))
    K = as_matrix("K", K, (G_u.shape[1], n))
    return control.ss(F - G_u @ K, G_y, K, np.zeros((K.shape[0], G_y.shape[1])), dt=dt)


def current_compensator(Phi: ArrayLike, Gamma: ArrayLike, C: ArrayLike, K: ArrayLike,
                        L: ArrayLike, *, dt: float) -> control.StateSpace:
    r"""Discrete compensator of the current estimator (filter form), from ``y`` to ``−u``.

    With :math:`\hat x = (I - LC)\bar x + Ly`, :math:`\bar x^+ = \Phi\hat x + \Gamma u` and
    :math:`u = -K\hat x`:

    .. math::
        \bar x[n+1] = (\Phi - \Gamma K)(I - LC)\bar x[n] + (\Phi - \Gamma K)Ly[n], \qquad
        -u[n] = K(I - LC)\bar x[n] + KLy[n]

    — a compensator with direct feedthrough ``KL`` (it uses the newest measurement).
    """
    Phi, Gamma, C, K, L = as_loop(Phi, Gamma, C, K, L, names=("Phi", "Gamma"))
    n = Phi.shape[0]
    I_LC = np.eye(n) - L @ C
    Acl = Phi - Gamma @ K
    return control.ss(Acl @ I_LC, Acl @ L, K @ I_LC, K @ L, dt=dt)


def reduced_order_compensator(F: ArrayLike, H_y: ArrayLike, H_u: ArrayLike, G: ArrayLike,
                              T_inv: ArrayLike, K: ArrayLike, *, dt: float) -> control.StateSpace:
    r"""Discrete compensator of the reduced-order observer, from ``y`` to ``−u``.

    With :math:`\hat x = T^{-1}[y;\ z + Gy]` and :math:`KT^{-1} = [K_a\ K_b]`,
    :math:`-u = K_b z + (K_a + K_bG)\,y`, and :math:`z^+ = Fz + H_y y + H_u u`:

    .. math::
        z[n+1] = (F - H_uK_b)z[n] + (H_y - H_u D)y[n],\qquad -u[n] = K_b z[n] + D y[n],
        \quad D = K_a + K_bG.
    """
    F = as_matrix("F", F)
    K = as_matrix("K", K)
    KT = K @ as_matrix("T_inv", T_inv)
    p = as_matrix("G", G).shape[1]
    Ka, Kb = KT[:, :p], KT[:, p:]
    D = Ka + Kb @ np.asarray(G)
    H_u = np.asarray(H_u)
    return control.ss(F - H_u @ Kb, np.asarray(H_y) - H_u @ D, Kb, D, dt=dt)


def loop_through(compensator: control.StateSpace, P: control.StateSpace) -> control.StateSpace:
    """Loop gain at the plant input, ``L = C_K · P`` (input → plant → compensator → −input)."""
    return control.series(P, compensator)


# ---- frequency grid and margins ------------------------------------------------------------------
def frequency_grid(*, lo: float = 1e-3, hi: float = 1e3, n: int = 4000,
                   dt: float | None = None) -> np.ndarray:
    """Log-spaced frequencies [rad/s]; a discrete loop's grid stops just below Nyquist ``π/T``."""
    if not (0 < lo < hi) or n < 2:
        raise ConfigError(f"frequency grid: expected 0 < lo < hi and n ≥ 2, got {lo}, {hi}, {n}")
    if dt is not None:
        hi = min(hi, np.pi / dt * (1 - 1e-6))
    return np.logspace(np.log10(lo), np.log10(hi), n)


def frequency_response(loop: control.StateSpace, omega: ArrayLike) -> np.ndarray:
    """SISO ``L(jω)`` (or ``L(e^{jωT})``) on ``omega``: (len(omega),) complex."""
    _require_siso(loop)
    resp = control.frequency_response(loop, np.asarray(omega, dtype=float))
    return np.asarray(resp.complex).reshape(-1)


def return_difference(loop: control.StateSpace, omega: ArrayLike) -> np.ndarray:
    """``|1 + L(jω)|`` on ``omega`` — the distance of the Nyquist curve from −1."""
    return np.abs(1.0 + frequency_response(loop, omega))


def _require_siso(loop: control.StateSpace) -> None:
    if loop.ninputs != 1 or loop.noutputs != 1:
        raise ConfigError(f"loop: expected a single-input single-output loop gain, got "
                          f"{loop.noutputs}×{loop.ninputs}")


@dataclass(frozen=True)
class MarginReport:
    """Stability margins of a SISO loop gain ``L`` (negative feedback ``1/(1+L)``).

    Attributes
    ----------
    closed_loop_stable : all poles of the closed loop in the open left half plane (unit disc)
    min_return_difference : ``min_ω |1 + L(jω)|`` on the grid (the Kalman inequality says ≥ 1 for LQ)
    omega_min_return_difference : the frequency where it occurs [rad/s]
    gain_margin_upper : smallest gain factor > 1 that destabilises (∞ if none)
    gain_margin_lower : largest gain factor < 1 that destabilises (0 if none; an open-loop
        unstable plant always has one)
    phase_margin_deg : smallest |phase margin| over all gain crossovers [deg] (nan: no crossover)
    omega_crossover : the gain crossover of that phase margin [rad/s]
    disk_margin : balanced (skew 0) disk margin α
    disk_gain_margin : the gain interval it guarantees, ``[(2 − α)/(2 + α), (2 + α)/(2 − α)]``,
        given by its upper end (a factor; ∞ when α ≥ 2)
    disk_phase_margin_deg : the phase it guarantees simultaneously [deg]
    """

    closed_loop_stable: bool
    min_return_difference: float
    omega_min_return_difference: float
    gain_margin_upper: float
    gain_margin_lower: float
    phase_margin_deg: float
    omega_crossover: float
    disk_margin: float
    disk_gain_margin: float
    disk_phase_margin_deg: float

    def to_dict(self) -> dict[str, object]:
        return asdict(self)


def _crossings(loop: control.StateSpace, omega: np.ndarray, Lw: np.ndarray,
               ) -> tuple[float, float, float, float]:
    """(upper GM, lower GM, PM [deg], ω of that PM) from sign changes on the grid."""
    gms: list[float] = []
    im = Lw.imag
    for k in np.nonzero(np.sign(im[:-1]) * np.sign(im[1:]) < 0)[0]:
        t = im[k] / (im[k] - im[k + 1])
        re = Lw[k].real + t * (Lw[k + 1].real - Lw[k].real)
        if re < 0:
            gms.append(-1.0 / re)
    ends = (1.0, -1.0) if loop.isdtime(strict=True) else (0.0,)   # ω = 0 (and π/T): L is real
    A = np.asarray(loop.A, dtype=float)
    for s in ends:
        if A.size and np.min(np.abs(np.linalg.eigvals(A) - s)) < 1e-9:
            continue                                                # a pole there: L infinite
        z = complex(np.asarray(control.evalfr(loop, s)).reshape(-1)[0])
        if z.real < 0:
            gms.append(-1.0 / z.real)
    g = np.asarray(gms)
    upper = float(np.min(g[g > 1])) if np.any(g > 1) else float("inf")
    lower = float(np.max(g[g < 1])) if np.any(g < 1) else 0.0
    mag = np.abs(Lw) - 1.0
    best, w_best = float("nan"), float("nan")
    for k in np.nonzero(np.sign(mag[:-1]) * np.sign(mag[1:]) < 0)[0]:
        t = mag[k] / (mag[k] - mag[k + 1])
        Lc = Lw[k] + t * (Lw[k + 1] - Lw[k])
        pm = float(abs(np.degrees(np.angle(-Lc))))
        if not pm >= best:
            best, w_best = pm, float(omega[k] + t * (omega[k + 1] - omega[k]))
    return upper, lower, best, w_best


def closed_loop_stable(loop: control.StateSpace) -> bool:
    """Whether ``1/(1 + L)`` is stable (poles of ``A − B(1 + D)⁻¹C`` of the loop realisation)."""
    _require_siso(loop)
    A, B, C, D = (np.asarray(m, dtype=float) for m in (loop.A, loop.B, loop.C, loop.D))
    if A.size == 0:
        return True
    Acl = A - B @ np.linalg.solve(np.eye(1) + D, C)
    poles = np.linalg.eigvals(Acl)
    if loop.isdtime(strict=True):
        return bool(np.all(np.abs(poles) < 1))
    return bool(np.all(poles.real < 0))


def loop_margins(loop: control.StateSpace, omega: ArrayLike) -> MarginReport:
    r"""Classical and disk margins of a SISO loop gain on the frequency grid ``omega``.

    Gain and phase margins come from the crossings of the Nyquist curve on the grid (linear
    interpolation between neighbouring points; ``ω = 0`` and, for a discrete loop, the Nyquist
    frequency ``π/T``, where ``L`` is real, are checked too); the return difference
    :math:`\min_\omega |1 + L(j\omega)|` and the balanced disk margin
    (Seiler, Packard & Gahinet 2020, python-control ``disk_margins``) are evaluated on ``omega``.

    Parameters
    ----------
    loop : SISO loop gain (continuous or discrete)
    omega : (k,) frequencies [rad/s]; for a discrete loop they must stay below ``π/T``
    """
    _require_siso(loop)
    omega = np.asarray(omega, dtype=float)
    Lw = frequency_response(loop, omega)
    rd = np.abs(1.0 + Lw)
    i = int(np.argmin(rd))
    upper, lower, phase, w_c = _crossings(loop, omega, Lw)
    disk, dgm, dpm = control.disk_margins(loop, omega, skew=0.0)
    disk = float(np.min(disk))
    dgm_factor = float(10 ** (float(np.min(dgm)) / 20)) if np.isfinite(np.min(dgm)) else float("inf")
    return MarginReport(
        closed_loop_stable=closed_loop_stable(loop), min_return_difference=float(rd[i]),
        omega_min_return_difference=float(omega[i]), gain_margin_upper=upper,
        gain_margin_lower=lower, phase_margin_deg=phase, omega_crossover=w_c,
        disk_margin=disk, disk_gain_margin=dgm_factor, disk_phase_margin_deg=float(np.min(dpm)))


# ---- zeros ---------------------------------------------------------------------------------------
def channel_zeros(A: ArrayLike, B: ArrayLike, C: ArrayLike) -> list[np.ndarray]:
    r"""Finite zeros of each single-input single-output channel :math:`C_i(sI - A)^{-1}B`.

    Zeros of the SISO channel are the finite generalised eigenvalues of the Rosenbrock pencil
    :math:`\begin{bmatrix} A - sI & B \\ C_i & 0\end{bmatrix}`.

    Parameters
    ----------
    A : (n, n), B : (n, 1), C : (p, n)

    Returns
    -------
    list of p arrays of zeros (sorted by real part).
    """
    from scipy.linalg import eig

    A = as_matrix("A", A)
    n = A.shape[0]
    B = as_matrix("B", B, (n, 1))
    C = as_matrix("C", C, (None, n))
    out = []
    for i in range(C.shape[0]):
        M = np.block([[A, B], [C[i:i + 1], np.zeros((1, 1))]])
        N = np.zeros_like(M)
        N[:n, :n] = np.eye(n)
        vals = eig(M, N, right=False)
        z = vals[np.isfinite(vals) & (np.abs(vals) < 1e8)]
        out.append(np.sort_complex(z))
    return out


def transmission_zeros(A: ArrayLike, B: ArrayLike, C: ArrayLike, *, tol: float = 1e-6,
                       ) -> np.ndarray:
    r"""Transmission zeros of a single-input plant with one or more outputs.

    For one input the transfer matrix :math:`C(sI - A)^{-1}B` is a column; its rank drops at ``s``
    only if every output channel vanishes there, so the transmission zeros are the zeros shared
    by all channels (within ``tol``, relative). A plant with two outputs that have no zero in
    common has **no** transmission zeros, whatever zeros each channel has on its own.
    """
    chans = channel_zeros(A, B, C)
    common = list(chans[0])
    for z in chans[1:]:
        keep = []
        pool = list(z)
        for c in common:
            d = [abs(c - q) for q in pool]
            if d and min(d) <= tol * max(1.0, abs(c)):
                keep.append(c)
                pool.pop(int(np.argmin(d)))
        common = keep
    return np.sort_complex(np.asarray(common, dtype=complex))


# ---- loop transfer recovery ----------------------------------------------------------------------
@dataclass(frozen=True)
class LTRPoint:
    """One point of an LTR sweep: the Kalman gain for ``W = q² BBᵀ`` and the LQG loop's margins.

    ``recovery_error`` is :math:`\\max_\\omega |L_{LQG}(j\\omega) - L_{LQ}(j\\omega)| /
    |1 + L_{LQ}(j\\omega)|` — below 1 the LQG loop keeps the LQ loop's stability robustness
    direction by direction on the grid.
    """

    q: float
    margins: MarginReport
    recovery_error: float
    observer_poles: np.ndarray


def ltr_sweep(A: ArrayLike, B: ArrayLike, C: ArrayLike, K: ArrayLike, V: ArrayLike,
              qs: Sequence[float], *, omega: ArrayLike, W0: ArrayLike | None = None,
              ) -> list[LTRPoint]:
    r"""Loop transfer recovery at the plant input (Doyle & Stein 1979).

    For each ``q`` design the Kalman–Bucy filter with process noise entering like the input,

    .. math::
        W = W_0 + q^2 B B^T, \qquad V \text{ fixed},

    and compare the LQG loop :math:`K(sI - A + BK + LC)^{-1}L\,C(sI - A)^{-1}B` with the LQ loop
    :math:`K(sI - A)^{-1}B`. As ``q → ∞`` they coincide pointwise in ω if the plant has no
    right-half-plane transmission zeros (and at least as many outputs as inputs).

    Parameters
    ----------
    A : (n, n), B : (n, 1), C : (p, n), K : (1, n) the LQR gain, V : (p, p) measurement-noise
    density; qs : the recovery parameters; omega : frequency grid; W0 : (n, n) PSD base density
    (default 0)

    Returns
    -------
    list of :class:`LTRPoint`, one per ``q``.
    """
    A = as_matrix("A", A)
    n = A.shape[0]
    B = as_matrix("B", B, (n, None))
    C = as_matrix("C", C, (None, n))
    K = as_matrix("K", K, (B.shape[1], n))
    W0 = np.zeros((n, n)) if W0 is None else as_matrix("W0", W0, (n, n))
    omega = np.asarray(omega, dtype=float)
    lq = frequency_response(lq_loop(A, B, K), omega)
    P = plant(A, B, C)
    out = []
    for q in qs:
        if not np.isfinite(q) or q <= 0:
            raise ConfigError(f"qs: expected positive numbers, got {q!r}")
        kf = kalman(A, np.eye(n), C, W0 + q * q * (B @ B.T), V)
        loop = loop_through(lqg_compensator(A, B, C, K, kf.L), P)
        lqg = frequency_response(loop, omega)
        err = float(np.max(np.abs(lqg - lq) / np.abs(1 + lq)))
        out.append(LTRPoint(q=float(q), margins=loop_margins(loop, omega), recovery_error=err,
                            observer_poles=kf.poles))
    return out
