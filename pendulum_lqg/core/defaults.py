"""The defaults of an episode: re-exported from :mod:`pendulum_lqg.problem.defaults`, where they are
written once (the declarations of the problem take theirs from there)."""

from pendulum_lqg.problem.defaults import (
    CONTROL_PERIOD,
    COST_Q,
    COST_R,
    DURATION,
    NOISE_SCALE,
    SETTLE_BAND,
    THETA_MAX,
    X0,
    X0_STD,
)

__all__ = ["CONTROL_PERIOD", "COST_Q", "COST_R", "DURATION", "NOISE_SCALE", "SETTLE_BAND",
           "THETA_MAX", "X0", "X0_STD"]
