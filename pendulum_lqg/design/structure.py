"""Structural properties: controllability, observability, PBH tests."""

from __future__ import annotations

import msgspec
import numpy as np
from numpy.typing import ArrayLike

from pendulum_lqg.design.checks import (
    as_matrix,
    as_square,
    design_function,
    pbh_failures,
    unstable_modes,
)


@design_function()
def controllability_matrix(A: ArrayLike, B: ArrayLike) -> np.ndarray:
    """``[B, AB, …, Aⁿ⁻¹B]`` (n, n·m)."""
    A = as_square("A", A)
    B = as_matrix("B", B, (A.shape[0], None))
    blocks, blk = [], B
    for _ in range(A.shape[0]):
        blocks.append(blk)
        blk = A @ blk
    return np.hstack(blocks)


@design_function()
def observability_matrix(A: ArrayLike, C: ArrayLike) -> np.ndarray:
    """``[C; CA; …; CAⁿ⁻¹]`` (n·p, n)."""
    A = as_square("A", A)
    C = as_matrix("C", C, (None, A.shape[0]))
    return controllability_matrix(A.T, C.T).T


@design_function()
def pbh_rank_deficient(A: ArrayLike, B: ArrayLike, *, tol: float = 1e-9) -> list[complex]:
    """Eigenvalues λ of A with ``rank [A − λI, B] < n`` (uncontrollable modes, PBH test)."""
    A = as_square("A", A)
    B = as_matrix("B", B, (A.shape[0], None))
    scale = max(1.0, float(np.linalg.norm(A, 2)), float(np.linalg.norm(B, 2)))
    return pbh_failures(A, B, select=lambda lam: True, tol=tol * scale)


class StructureReport(msgspec.Struct, frozen=True):
    """Controllability / observability facts of ``(A, B, C)``.

    Attributes
    ----------
    n : state dimension
    controllability_rank, observability_rank : ranks of the Kalman matrices
    uncontrollable_modes, unobservable_modes : eigenvalues failing the PBH test
    stabilizable, detectable : no non-decaying mode fails the PBH test
    discrete : whether stability means |λ| < 1 (else Re λ < 0)
    """

    n: int
    controllability_rank: int
    observability_rank: int
    uncontrollable_modes: tuple[complex, ...]
    unobservable_modes: tuple[complex, ...]
    stabilizable: bool
    detectable: bool
    discrete: bool

    @property
    def controllable(self) -> bool:
        return self.controllability_rank == self.n

    @property
    def observable(self) -> bool:
        return self.observability_rank == self.n


@design_function()
def structure(A: ArrayLike, B: ArrayLike, C: ArrayLike, *, discrete: bool = False,
              ) -> StructureReport:
    """Rank and PBH tests of controllability, observability, stabilisability, detectability."""
    A = as_square("A", A)
    n = A.shape[0]
    B = as_matrix("B", B, (n, None))
    C = as_matrix("C", C, (None, n))
    return StructureReport(
        n=n,
        controllability_rank=int(np.linalg.matrix_rank(controllability_matrix(A, B))),
        observability_rank=int(np.linalg.matrix_rank(observability_matrix(A, C))),
        uncontrollable_modes=tuple(pbh_rank_deficient(A, B)),
        unobservable_modes=tuple(pbh_rank_deficient(A.T, C.T)),
        stabilizable=not unstable_modes(A, B, discrete=discrete),
        detectable=not unstable_modes(A.T, C.T, discrete=discrete),
        discrete=discrete,
    )
