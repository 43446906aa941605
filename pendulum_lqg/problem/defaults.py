"""The defaults of an episode, written once: :class:`~pendulum_lqg.core.scenario.Scenario`'s fields
take them, and the environments' keywords, the CLI's options and the experiment files' ``[scenario]``
tables take theirs from here (this module imports nothing, so the CLI builds its parser without
numpy). ``tests/problem/test_defaults.py`` holds them equal to the
declarations."""

from __future__ import annotations

#: The control period T [s].
CONTROL_PERIOD = 0.01
#: The episode length [s].
DURATION = 10.0
#: The mean initial state ``[p, θ, ṗ, θ̇]`` [m, rad, m/s, rad/s]: the pole 0.1 rad off upright.
X0: tuple[float, ...] = (0.0, 0.1, 0.0, 0.0)
#: The standard deviation of the initial state around :data:`X0`.
X0_STD: tuple[float, ...] = (0.0, 0.0, 0.0, 0.0)
#: The failure angle |θ| [rad].
THETA_MAX = 0.5
#: The cost weights of ``∫ xᵀQx + R u² dt``.
COST_Q: tuple[float, ...] = (1.0, 1.0, 1.0, 1.0)
COST_R = 1.0
#: The noise scale: multiplies both noises' standard deviations (1 is the nominal model).
NOISE_SCALE = 1.0
#: The settling band |θ| [rad] of the settling time.
SETTLE_BAND = 0.02
#: The measurement variance V of p and θ [m², rad²] (the lecture's).
MEASUREMENT_VARIANCE = 0.01
#: The environments' reward scale [J/s]: the cost rate at which a step's reward is e⁻¹ (the
#: lecture LQG policy runs at ≈ 3.4 J/s, the full-state LQR at ≈ 0.18 J/s).
REWARD_SCALE = 10.0
