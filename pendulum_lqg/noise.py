"""noise at its 0.3 import path (the module is :mod:`pendulum_lqg.core.noise`)."""

from pendulum_lqg.core.noise import (
    CHUNK_PERIODS,
    DRAW_LOCK,
    FIRST_PERIODS,
    LECTURE_PERIOD,
    LECTURE_V,
    LECTURE_W_STEP,
    NoiseModel,
    NoiseStream,
    UniformStream,
)

__all__ = ["CHUNK_PERIODS", "DRAW_LOCK", "FIRST_PERIODS", "LECTURE_PERIOD", "LECTURE_V",
           "LECTURE_W_STEP", "NoiseModel", "NoiseStream", "UniformStream"]
