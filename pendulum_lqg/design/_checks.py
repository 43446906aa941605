"""The one validation helper for matrix arguments of the design layer.

Errors name the argument, say what was expected and what was found (python-control's
``_check_shape`` style), and subclass :class:`ValueError`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from pendulum_lqg.errors import DesignError, ShapeError

#: Relative tolerance for symmetry / definiteness / rank decisions.
RTOL = 1e-9


def as_matrix(name: str, value: ArrayLike, shape: tuple[int | None, int | None] | None = None,
              ) -> np.ndarray:
    """Return ``value`` as a finite 2-D float array, checking its shape.

    Scalars become 1×1 and 1-D arrays become columns. ``None`` in ``shape`` accepts any size.
    """
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ShapeError(f"{name}: expected a real matrix, got {type(value).__name__}") from exc
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
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ShapeError(f"{name}: expected a real matrix, got {type(value).__name__}") from exc
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
    if definite and eig_min <= RTOL * scale:
        raise DesignError(f"{name}: must be positive definite; smallest eigenvalue {eig_min:.3g}")
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
    """A finite positive real number."""
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise DesignError(f"{name}: expected a positive number, got {value!r}") from exc
    if not np.isfinite(v) or v <= 0:
        raise DesignError(f"{name}: expected a finite positive number, got {value!r}")
    return v


def unstable_modes(A: np.ndarray, B: np.ndarray, *, discrete: bool, uncontrollable: bool = True,
                   ) -> list[complex]:
    """Eigenvalues of A that fail the PBH test ``rank [A − λI, B] = n`` and are not stable.

    With ``uncontrollable=True`` these are the modes that make ``(A, B)`` not stabilisable. Used
    with ``(Aᵀ, Cᵀ)`` for detectability.
    """
    n = A.shape[0]
    bad: list[complex] = []
    scale = max(1.0, float(np.linalg.norm(A, 2)), float(np.linalg.norm(B, 2)) if B.size else 0.0)
    for lam in np.linalg.eigvals(A):
        stable = abs(lam) < 1 - 1e-12 if discrete else lam.real < -1e-12 * scale
        if stable:
            continue
        pbh = np.hstack([A - lam * np.eye(n), B])
        sv = np.linalg.svd(pbh, compute_uv=False)
        if sv[-1] <= 1e-9 * scale:
            bad.append(complex(lam))
    return bad


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
