"""Numbers of the lecture documents that the conventions page (docs/conventions-lecture.md)
corrects, recomputed from the documents' own data."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pendulum_lqg import design

A_DI = np.array([[0.0, 1.0], [0.0, 0.0]])
B_DI = np.array([[0.0], [1.0]])
C_DI = np.array([[1.0, 0.0]])


def test_double_integrator_lqg_compensator_zero_is_0_318():
    """The exercise prints 3.14(s + 0.31)/(s + 1.57 ± j1.4); with K = [1, √2] and L = [√3, 1]ᵀ
    the compensator K(sI − A + BK + LC)⁻¹L is (√2+√3)(s + 1/(√2+√3)) / (s² + (√2+√3)s + …):
    gain 3.146, zero −0.3178 (cut to 0.31 in the document), poles −1.573 ± 1.405j."""
    K = design.lqr(A_DI, B_DI, C_DI.T @ C_DI, 1.0).K
    L = design.kalman(A_DI, np.eye(2), C_DI, np.eye(2), np.array([[1.0]])).L
    Ac = A_DI - B_DI @ K - L @ C_DI
    gain = float((K @ L)[0, 0])                        # leading coefficient of the numerator
    assert gain == pytest.approx(math.sqrt(2) + math.sqrt(3), rel=1e-9)
    # a 2×2 matrix X has adj X = tr(X)·I − X, so adj(sI − Ac) = (s − tr Ac)·I + Ac and the
    # numerator K adj(sI − Ac) L = gain·s + K(Ac − tr(Ac)·I)L
    zero = -float((K @ (Ac - np.trace(Ac) * np.eye(2)) @ L)[0, 0]) / gain
    assert zero == pytest.approx(-0.3178, abs=5e-5)
    assert round(-zero, 2) == 0.32                     # rounded; the document prints 0.31
    poles = np.linalg.eigvals(Ac)
    assert sorted(poles.imag) == pytest.approx([-1.405, 1.405], abs=5e-4)
    assert poles.real == pytest.approx([-1.573, -1.573], abs=5e-4)
