"""Issue 55's small thing in the RL figures: twelve learning curves on a ten-colour cycle."""

from __future__ import annotations

import numpy as np

from pendulum_lqg.learn.figures import curves_figure, method_styles


def _run(k):
    steps = np.linspace(0.0, 1e5, 5)
    return {"env_steps": steps, "wall_seconds": steps / 1e3,
            "success_rate": np.full(5, k / 12), "score_mean": np.full(5, k / 12)}


def test_twelve_learning_curves_have_twelve_styles():
    """The eleventh and twelfth methods had the first and second's colour and line: the curves
    of 12 methods are now 12 distinct (colour, line style) pairs in every panel."""
    curves = {f"m{k:02d}": [_run(k)] for k in range(12)}
    fig = curves_figure(curves)
    for ax in fig.axes:
        looks = {(line.get_color(), line.get_linestyle()) for line in ax.get_lines()}
        assert len(ax.get_lines()) == 12
        assert len(looks) == 12
    styles = method_styles(list(curves))
    assert styles["m00"] == {"color": "C0", "ls": "-"}
    assert styles["m10"] == {"color": "C0", "ls": "--"}
    assert styles["m11"] == {"color": "C1", "ls": "--"}
