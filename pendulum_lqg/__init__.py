"""pendulum_lqg: LQG control of a MuJoCo cart-pole under noise — design, simulation, benchmark.

Importing the package registers the Gymnasium environment :data:`ENV_ID` (``gymnasium.make``,
``gymnasium.make_vec``) without importing Gymnasium or MuJoCo itself: if Gymnasium is already
imported the ids are registered now, otherwise when Gymnasium is first imported. The
``"pendulum_lqg:pendulum_lqg/CartPoleLQG-v0"`` form of ``gymnasium.make`` needs no prior import.
"""

from __future__ import annotations

import importlib.abc
import importlib.machinery
import importlib.util
import sys
from types import ModuleType

__all__ = ["ENV_ID", "register_envs"]

#: The Gymnasium id of the cart-pole LQG environment (:class:`pendulum_lqg.env.CartPoleLQGEnv`).
ENV_ID = "pendulum_lqg/CartPoleLQG-v0"

# The registered defaults of the episode (``tests/test_env.py`` checks they are the env's own).
_DEFAULT_DURATION = 10.0
_DEFAULT_CONTROL_PERIOD = 0.01


def register_envs() -> None:
    """Register :data:`ENV_ID` (single and vector entry points) with Gymnasium, once.

    A behaviour change of the environment gets a new version here (``-v1``), never an edit of v0.

    The entry point :func:`pendulum_lqg.env.make_env` wraps the env in its own ``TimeLimit`` of
    ``duration / control_period`` steps, so ``max_episode_steps`` follows those keywords (a fixed
    registered value would cut a longer episode short); hence no ``max_episode_steps`` here.
    """
    import gymnasium

    if ENV_ID in gymnasium.registry:
        return
    gymnasium.register(
        id=ENV_ID,
        entry_point="pendulum_lqg.env:make_env",
        vector_entry_point="pendulum_lqg.env:CartPoleLQGVectorEnv",
        kwargs={"duration": _DEFAULT_DURATION, "control_period": _DEFAULT_CONTROL_PERIOD},
    )


class _RegisteringLoader(importlib.abc.Loader):
    """Gymnasium's own loader, followed by :func:`register_envs` once the module has run."""

    def __init__(self, inner: importlib.abc.Loader) -> None:
        self._inner = inner

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType | None:
        return self._inner.create_module(spec)

    def exec_module(self, module: ModuleType) -> None:
        self._inner.exec_module(module)
        register_envs()

    def __getattr__(self, name: str) -> object:   # resource readers etc. of the real loader
        return getattr(self._inner, name)


class _RegisterOnGymnasiumImport(importlib.abc.MetaPathFinder):
    """One-shot import hook: registers our ids right after ``import gymnasium``."""

    def find_spec(self, fullname: str, path: object = None, target: object = None,
                  ) -> importlib.machinery.ModuleSpec | None:
        if fullname != "gymnasium":
            return None
        if self in sys.meta_path:
            sys.meta_path.remove(self)
        spec = importlib.util.find_spec(fullname)
        if spec is not None and spec.loader is not None:
            spec.loader = _RegisteringLoader(spec.loader)
        return spec


if "gymnasium" in sys.modules:
    register_envs()
elif not any(isinstance(f, _RegisterOnGymnasiumImport) for f in sys.meta_path):
    sys.meta_path.insert(0, _RegisterOnGymnasiumImport())
