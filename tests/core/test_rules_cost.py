"""The period cost (``rules.period_cost``) and its form chosen once for given weights
(``rules.period_cost_of``, what the single env's ``step_one`` calls): diagonal weights and a
weight matrix, the same floats either way (step_one against step, bit for bit:
tests/core/test_loop.py)."""

from __future__ import annotations

import numpy as np

from pendulum_lqg.core import rules


def test_the_form_chosen_once_gives_period_costs_floats_for_both_kinds_of_weights():
    rng = np.random.default_rng(0)
    z = rng.standard_normal((3, 10, 5))
    diagonal = rules.cost_weights((1.0, 2.0, 3.0, 4.0), 0.5, 1e-3)
    full = rng.standard_normal((5, 5))
    matrix = rules.cost_weights((), 0.0, 1e-3, matrix=full @ full.T)
    for weights in (diagonal, matrix):
        cost = rules.period_cost(z, weights)
        assert np.array_equal(rules.period_cost_of(weights)(z, weights), cost)
        dense = np.diag(weights) if weights.ndim == 1 else weights
        expected = [sum(row @ dense @ row for row in z[i]) for i in range(len(z))]
        assert np.allclose(cost, expected, rtol=1e-12, atol=0)

