"""The names of the built-in choices, in one light module (the CLI imports it without numpy)."""

from __future__ import annotations

CONTROLLERS: tuple[str, ...] = ("lqr", "dlqr")
#: Observers: ``none`` (true state) and the estimators of :mod:`pendulum_lqg.policies.lqg`.
OBSERVERS: tuple[str, ...] = ("none", "luenberger", "kalman", "kalman-predictor", "kalman-tv",
                              "kalman-bucy", "reduced-order", "ackermann", "lmi", "h2", "hinf",
                              "kalman-delay", "luenberger-euler", "kalman-bucy-euler")
#: How the plant is simulated: MuJoCo, or the linearisation discretised exactly (ZOH) or by
#: forward Euler at the control period (the lecture's own linear simulation).
PLANTS: tuple[str, ...] = ("mujoco", "linear-zoh", "linear-euler")
#: The built-in linear policies of the lecture study (``experiments/lecture.toml``), the default of
#: ``pendulum-lqg theory``.
LECTURE_POLICIES: tuple[str, ...] = ("dlqr+none", "dlqr+luenberger", "dlqr+kalman",
                                     "dlqr+kalman-tv", "lqr+kalman-bucy")
#: What an environment observes: the measurement ``y`` (the benchmark) or the true state.
OBSERVATION_MODES: tuple[str, ...] = ("measurement", "state")
