"""Plugins for tests/policies/test_loading_plugins.py: the built-in designs behind the plugin
protocol, and broken plugins (each breaks one rule of the protocol)."""

from __future__ import annotations

import numpy as np

from pendulum_lqg.policies.lqg import DesignSpec, design_policy


class _Builtin:
    """A built-in policy reached only through the plugin protocol (reset(n) / act / select)."""

    def __init__(self, ctx, observer: str, with_select: bool = True) -> None:
        self._p = design_policy(ctx.plant, ctx.dt, ctx.noise, DesignSpec(observer=observer))
        self.needs_state = self._p.needs_state
        if with_select:
            self.select = self._p.select

    def reset(self, n):
        self._p.reset(n)

    def act(self, y):
        return self._p.act(y)

    @property
    def x_hat(self):
        return self._p.x_hat


def builtin_kalman(ctx):
    return _Builtin(ctx, "kalman")


def builtin_luenberger(ctx):
    return _Builtin(ctx, "luenberger")


def builtin_luenberger_no_select(ctx):
    return _Builtin(ctx, "luenberger", with_select=False)


def builtin_full_state(ctx):
    return _Builtin(ctx, "none")


class _Broken(_Builtin):
    def __init__(self, ctx, how):
        super().__init__(ctx, "kalman")
        self.how, self.calls = how, 0

    def act(self, y):
        u = super().act(y)
        self.calls += 1
        if self.how == "raise" and self.calls == 3:
            raise RuntimeError("controller exploded\non purpose")
        if self.how == "shape":
            return np.zeros((y.shape[0], 2))
        if self.how == "nan" and self.calls == 5:
            u = u.copy()
            u[1] = np.nan                       # episode in row 1 blows up in its 5th period
        if self.how == "text":
            return "push left"
        return u


def raises(ctx):
    return _Broken(ctx, "raise")


def wrong_shape(ctx):
    return _Broken(ctx, "shape")


def nan_force(ctx):
    return _Broken(ctx, "nan")


def text_force(ctx):
    return _Broken(ctx, "text")


def no_act(ctx):
    return object()


def factory_raises(ctx):
    raise KeyError("missing gain")


NOT_CALLABLE = 3
