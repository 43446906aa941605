"""The one validation helper for matrix arguments of the design layer.

Errors name the argument, say what was expected and what was found (python-control's
``_check_shape`` style), and subclass :class:`ValueError`.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from typing import Any, TypeVar

import msgspec
import numpy as np
from numpy.typing import ArrayLike

from pendulum_lqg.errors import DesignError, PendulumLQGError, ShapeError
from pendulum_lqg.problem.declare import positive_number

#: Relative tolerance for symmetry / definiteness / rank decisions.
RTOL = 1e-9
#: Longest solver message kept in a wrapped error (the message stays one readable line).
MAX_DETAIL = 200

F = TypeVar("F", bound=Callable[..., Any])


def _one_line(exc: BaseException) -> str:
    detail = " ".join(str(exc).split()) or "no message"
    if len(detail) > MAX_DETAIL:
        detail = detail[:MAX_DETAIL - 1] + "…"
    return f"{type(exc).__name__}: {detail}"


def _non_finite(value: object, seen: int = 0) -> bool:
    """Whether a result (array, number, tuple/list, record of them) holds a nan or inf."""
    if seen > 4:                                   # results are shallow; stop on odd nesting
        return False
    if isinstance(value, np.ndarray):
        return value.dtype.kind in "fc" and not bool(np.all(np.isfinite(value)))
    if isinstance(value, float | complex | np.floating | np.complexfloating):
        return not bool(np.isfinite(value))
    if isinstance(value, tuple | list):
        return any(_non_finite(v, seen + 1) for v in value)
    if isinstance(value, msgspec.Struct):         # a design's result record
        return any(_non_finite(v, seen + 1) for v in msgspec.structs.astuple(value))
    return False


def design_function(hint: str | None = None) -> Callable[[F], F]:
    """Decorator of every public design function: the layer's one error contract.

    * pendulum_lqg errors (:class:`ShapeError`, :class:`DesignError`, …) pass unchanged;
    * any other exception of the numerics underneath (``numpy.linalg.LinAlgError``, scipy's and
      python-control's ``ValueError``/``TypeError`` family, cvxpy's ``SolverError``, overflow) becomes
      a one-line :class:`DesignError` naming the function, e.g. ``lqr: no solution for these data
      (LinAlgError: Failed to find a finite solution.); check the scaling of Q and R``;
    * a result holding nan or inf (an overflow inside a solver that did not notice) is refused with
      a :class:`DesignError` instead of being returned.

    ``hint`` names the arguments to check (appended to the wrapped messages).
    """
    advice = f"; check the scaling of {hint}" if hint else ""

    def wrap(func: F) -> F:
        name = func.__name__

        @functools.wraps(func)
        def checked(*args: Any, **kwargs: Any) -> Any:
            try:
                with np.errstate(all="ignore"):    # overflow is judged on the result below
                    result = func(*args, **kwargs)
            except PendulumLQGError:
                raise
            except Exception as exc:   # whatever the numerics underneath raise: one DesignError
                raise DesignError(f"{name}: no solution for these data ({_one_line(exc)})"
                                  f"{advice}") from exc
            if _non_finite(result):
                raise DesignError(f"{name}: the result is not finite (nan or inf: the data "
                                  f"overflow double precision){advice}")
            return result

        return checked  # type: ignore[return-value]

    return wrap


def _real_array(name: str, value: ArrayLike) -> np.ndarray:
    """``value`` as a float array; complex entries (even with a zero imaginary part) and
    non-numbers are refused rather than cut to their real part."""
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError) as exc:       # ragged nested sequences
        raise ShapeError(f"{name}: expected a real matrix, got {type(value).__name__}") from exc
    if np.iscomplexobj(raw):
        raise ShapeError(f"{name}: expected a real matrix, got complex entries")
    if raw.dtype.kind not in "biuf":
        if raw.dtype.kind == "O" and raw.size and any(isinstance(v, complex | np.complexfloating)
                                                      for v in raw.ravel()):
            raise ShapeError(f"{name}: expected a real matrix, got complex entries")
        try:
            raw = raw.astype(float)
        except (TypeError, ValueError) as exc:
            raise ShapeError(f"{name}: expected a real matrix, got {type(value).__name__}") from exc
    return np.array(raw, dtype=float)


def as_matrix(name: str, value: ArrayLike, shape: tuple[int | None, int | None] | None = None,
              ) -> np.ndarray:
    """Return ``value`` as a finite 2-D float array, checking its shape.

    Scalars become 1×1 and 1-D arrays become columns. ``None`` in ``shape`` accepts any size.
    Complex entries are refused (not cut to their real part).
    """
    arr = _real_array(name, value)
    if arr.ndim == 0:
        arr = arr.reshape(1, 1)
    elif arr.ndim == 1:
        arr = arr.reshape(-1, 1)
    elif arr.ndim != 2:
        raise ShapeError(f"{name}: expected a 2-D matrix, found {arr.ndim} dimensions")
    if shape is not None:
        expected = tuple(arr.shape[i] if s is None else s for i, s in enumerate(shape))
        if arr.shape != expected:
            raise ShapeError(f"Incompatible dimensions of {name}; expected {expected} "
                             f"but found {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise DesignError(f"{name}: contains non-finite entries (nan or inf)")
    return arr


def as_square(name: str, value: ArrayLike, n: int | None = None) -> np.ndarray:
    """A square matrix (of size ``n`` if given)."""
    arr = as_matrix(name, value)
    if arr.shape[0] != arr.shape[1] or (n is not None and arr.shape[0] != n):
        size = n if n is not None else arr.shape[0]
        raise ShapeError(f"Incompatible dimensions of {name}; expected ({size}, {size}) "
                         f"but found {arr.shape}")
    return arr


def as_loop(A: ArrayLike, B: ArrayLike, C: ArrayLike, K: ArrayLike, L: ArrayLike,
            names: tuple[str, str] = ("A", "B")) -> tuple[np.ndarray, ...]:
    """Plant ``(A, B, C)`` with state feedback ``K`` (m, n) and observer gain ``L`` (n, p)."""
    A = as_square(names[0], A)
    n = A.shape[0]
    B = as_matrix(names[1], B, (n, None))
    C = as_matrix("C", C, (None, n))
    K = as_matrix("K", K, (B.shape[1], n))
    L = as_matrix("L", L, (n, C.shape[0]))
    return A, B, C, K, L


def as_weight(name: str, value: ArrayLike, n: int, *, definite: bool) -> np.ndarray:
    """A symmetric weight/covariance of size n×n; positive definite if ``definite`` else PSD.

    Scalars and 1-D arrays of length n are accepted as ``s·I`` / ``diag(v)``.
    """
    arr = _real_array(name, value)
    if not np.all(np.isfinite(arr)):
        raise DesignError(f"{name}: contains non-finite entries (nan or inf)")
    if arr.ndim == 0:
        arr = arr * np.eye(n)
    elif arr.ndim == 1 and arr.shape[0] == n and n > 1:
        arr = np.diag(arr)
    arr = as_square(name, arr, n)
    scale = max(1.0, float(np.max(np.abs(arr))))
    asym = float(np.max(np.abs(arr - arr.T)))
    if asym > RTOL * scale:
        raise DesignError(f"{name}: must be symmetric; max |{name} - {name}ᵀ| = {asym:.3g}")
    arr = 0.5 * (arr + arr.T)
    eig_min = float(np.min(np.linalg.eigvalsh(arr)))
    if definite and eig_min <= 0:
        raise DesignError(f"{name}: must be positive definite; smallest eigenvalue {eig_min:.3g}")
    if definite and eig_min <= RTOL * scale:
        raise DesignError(f"{name}: must be positive definite and well conditioned; smallest "
                          f"eigenvalue {eig_min:.3g} is below {RTOL:g} × its largest entry "
                          f"{scale:.3g}")
    if not definite and eig_min < -RTOL * scale:
        raise DesignError(f"{name}: must be positive semi-definite; "
                          f"smallest eigenvalue {eig_min:.3g}")
    return arr


def as_poles(name: str, poles: ArrayLike | Sequence[complex], n: int) -> np.ndarray:
    """A set of ``n`` poles closed under complex conjugation."""
    try:
        arr = np.atleast_1d(np.asarray(poles, dtype=complex)).ravel()
    except (TypeError, ValueError) as exc:
        raise ShapeError(f"{name}: expected a sequence of numbers, got {poles!r}") from exc
    if arr.shape[0] != n:
        raise ShapeError(f"{name}: expected {n} poles, found {arr.shape[0]}")
    if not np.all(np.isfinite(arr)):
        raise DesignError(f"{name}: contains non-finite poles")
    scale = max(1.0, float(np.max(np.abs(arr))))
    remaining = list(arr)
    while remaining:
        p = remaining.pop(0)
        if abs(p.imag) <= RTOL * scale:
            continue
        dist = [abs(q - np.conj(p)) for q in remaining]
        j = int(np.argmin(dist)) if dist else -1
        if j < 0 or dist[j] > 1e-8 * scale:
            raise DesignError(f"{name}: pole {p:.6g} has no complex-conjugate partner")
        remaining.pop(j)
    return arr


def as_positive(name: str, value: float) -> float:
    """A finite positive real number (:class:`DesignError` naming ``name`` otherwise)."""
    return positive_number(name, value, error=DesignError)


def unstable_modes(A: np.ndarray, B: np.ndarray, *, discrete: bool) -> list[complex]:
    """Eigenvalues of A that fail the PBH test ``rank [A − λI, B] = n`` and are not stable.

    These are the modes that make ``(A, B)`` not stabilisable. Used
    with ``(Aᵀ, Cᵀ)`` for detectability.
    """
    scale = max(1.0, float(np.linalg.norm(A, 2)), float(np.linalg.norm(B, 2)) if B.size else 0.0)

    def unstable(lam: complex) -> bool:
        return abs(lam) >= 1 - 1e-12 if discrete else lam.real >= -1e-12 * scale

    return pbh_failures(A, B, select=unstable, tol=1e-9 * scale)


def pbh_failures(A: np.ndarray, B: np.ndarray, *, select: Callable[[complex], bool],
                 tol: float) -> list[complex]:
    """The package's one PBH test: the eigenvalues λ of ``A`` that ``select`` keeps and for which
    ``rank [A − λI, B] < n`` (smallest singular value ≤ ``tol``) — uncontrollable modes of
    ``(A, B)``, or unobservable modes of ``(A, C)`` given ``(Aᵀ, Cᵀ)``."""
    n = A.shape[0]
    return [complex(lam) for lam in np.linalg.eigvals(A) if select(lam)
            and np.linalg.svd(np.hstack([A - lam * np.eye(n), B]), compute_uv=False)[-1] <= tol]


def require_stabilizable(A: np.ndarray, B: np.ndarray, *, discrete: bool, names: str) -> None:
    bad = unstable_modes(A, B, discrete=discrete)
    if bad:
        modes = ", ".join(f"{lam:.4g}" for lam in bad)
        raise DesignError(f"{names}: pair is not stabilisable (uncontrollable "
                          f"{'non-decaying' if discrete else 'unstable'} mode(s) {modes})")


def require_detectable(A: np.ndarray, C: np.ndarray, *, discrete: bool, names: str) -> None:
    bad = unstable_modes(A.T, C.T, discrete=discrete)
    if bad:
        modes = ", ".join(f"{lam:.4g}" for lam in bad)
        raise DesignError(f"{names}: pair is not detectable (unobservable "
                          f"{'non-decaying' if discrete else 'unstable'} mode(s) {modes})")


def require_stable(poles: np.ndarray, *, discrete: bool, what: str) -> None:
    """Guard against a Riccati solution that is not stabilising (e.g. an undetectable Q)."""
    bad = np.abs(poles) >= 1 if discrete else poles.real >= 0
    if np.any(bad):
        raise DesignError(f"{what}: the design is not stabilising (closed-loop poles "
                          + ", ".join(f"{p:.4g}" for p in poles[bad]) + "); check that the "
                          "weights make every unstable mode visible in the cost")


#: Relative distance from the stability boundary (imaginary axis / unit circle) within which a mode
#: counts as marginal, and the PBH threshold of "not seen" for such modes. Loose on purpose: a
#: repeated eigenvalue (the cart's double integrator) is only computed to about √eps.
MARGINAL_RTOL = 1e-6


def psd_root(M: np.ndarray) -> np.ndarray:
    """The symmetric square root of a positive semi-definite matrix (negative rounding clipped)."""
    evals, evecs = np.linalg.eigh(0.5 * (M + M.T))
    return evecs @ np.diag(np.sqrt(np.clip(evals, 0.0, None))) @ evecs.T


def hidden_marginal_modes(A: np.ndarray, C: np.ndarray, *, discrete: bool) -> list[complex]:
    """Eigenvalues of A on the stability boundary that ``C`` does not see (PBH:
    ``rank [A − λI; C] < n``). A Riccati equation with such a mode in its weight has no
    stabilising solution (the LQR cost or the Kalman noise must reach every marginal mode)."""
    scale = max(1.0, float(np.linalg.norm(A, 2)))
    weight = max(float(np.linalg.norm(C, 2)), 1e-300) if C.size else 1e-300

    def marginal(lam: complex) -> bool:
        return (abs(abs(lam) - 1.0) if discrete else abs(lam.real)) <= MARGINAL_RTOL * scale

    # [A − λI; C] has the singular values of its transpose [Aᵀ − λI, Cᵀ]
    return pbh_failures(A.T, C.T, select=marginal, tol=MARGINAL_RTOL * max(scale, weight))


def _modes(modes: list[complex]) -> str:
    return ", ".join(f"{lam:.4g}" for lam in modes)


def require_cost_sees_marginal_modes(A: np.ndarray, B: np.ndarray, Q: np.ndarray, R: np.ndarray,
                                     N: np.ndarray, *, discrete: bool, names: str) -> None:
    """LQR: every mode of ``A − B R⁻¹ Nᵀ`` on the stability boundary must appear in the
    cost ``Q − N R⁻¹ Nᵀ`` (else no stabilising Riccati solution exists)."""
    RiNt = np.linalg.solve(R, N.T)
    bad = hidden_marginal_modes(A - B @ RiNt, psd_root(Q - N @ RiNt), discrete=discrete)
    if bad:
        where = "on the unit circle" if discrete else "on the imaginary axis"
        raise DesignError(f"Q: the cost does not weight the mode(s) {_modes(bad)} of {names} "
                          f"{where}, so no stabilising LQR exists; give them a positive weight")


def require_noise_reaches_marginal_modes(A: np.ndarray, GWG: np.ndarray, *, discrete: bool,
                                         names: str) -> None:
    """Kalman (dual of :func:`require_cost_sees_marginal_modes`): the process noise ``G W Gᵀ``
    must reach every mode of A on the stability boundary."""
    bad = hidden_marginal_modes(A.T, psd_root(GWG), discrete=discrete)
    if bad:
        where = "on the unit circle" if discrete else "on the imaginary axis"
        raise DesignError(f"W: the process noise does not reach the mode(s) {_modes(bad)} of "
                          f"{names} {where}, so no stabilising Kalman filter exists; add noise "
                          "on them")
