"""Exceptions raised by pendulum_lqg.

All of them subclass :class:`ValueError` (as python-control's ``ControlArgument`` family does), so a
caller that already catches ``ValueError`` for bad input keeps working. Messages are one line and
start with the name of the offending parameter.
"""

from __future__ import annotations


class PendulumLQGError(ValueError):
    """Base class: bad input to pendulum_lqg (the message names the parameter)."""


class ShapeError(PendulumLQGError):
    """A matrix or vector argument has the wrong shape."""


class DesignError(PendulumLQGError):
    """A design is impossible for the given data (e.g. not stabilisable, indefinite weight)."""


class ConfigError(PendulumLQGError):
    """A configuration value (CLI option, TOML key, env keyword, model override) is invalid."""


class PluginError(PendulumLQGError):
    """A user's policy plugin cannot be loaded or broke the policy protocol (names the plugin)."""


class NotApplicable(ConfigError):
    """A policy or agent cannot play a scoreboard suite as it is posed (it observes something else:
    the true state where the suite gives only ``y``, or the reverse); its score row says so."""
