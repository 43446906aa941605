"""pendulum_lqg: LQG control of a MuJoCo cart-pole under noise — design, simulation, benchmark.

Importing the package registers the Gymnasium environment :data:`ENV_ID` (``gymnasium.make``,
``gymnasium.make_vec``), as Gymnasium 1.x environment packages do::

    import gymnasium as gym
    import pendulum_lqg

    gym.register_envs(pendulum_lqg)       # optional: marks the import as used
    env = gym.make(pendulum_lqg.ENV_ID)   # or gym.make("pendulum_lqg:pendulum_lqg/CartPoleLQG-v0")

Registering imports Gymnasium (and numpy) but none of MuJoCo, python-control or the simulation
core: those load when an environment is made. The one process that skips it is the
``pendulum-lqg`` command itself, which never makes a Gymnasium env and whose ``--help`` must not wait
for numpy (it can still call :func:`register_envs`).

Public API (stable from 0.2.0; a change gets a version bump and a CHANGELOG.md entry): :data:`ENV_ID`,
:class:`PolicyContext` and the policy-plugin protocol (:mod:`pendulum_lqg.plugins`), the CLI flags,
and the results schema (:data:`SCHEMA_VERSION`).
"""

from __future__ import annotations

import os
import sys
from pathlib import PurePath
from typing import TYPE_CHECKING, Any

__version__ = "0.5.0"
__all__ = ["ENV_ID", "SCHEMA_VERSION", "PolicyContext", "__version__", "register_envs"]

#: The Gymnasium id of the cart-pole LQG environment (:class:`pendulum_lqg.envs.single.CartPoleLQGEnv`).
ENV_ID = "pendulum_lqg/CartPoleLQG-v0"

#: Version of the results schema (``summary.json``, ``episodes.csv``); see docs/results.md.
SCHEMA_VERSION = 1

# The registered defaults of the episode (``tests/test_env.py`` checks they are the env's own).
_DEFAULT_DURATION = 10.0
_DEFAULT_CONTROL_PERIOD = 0.01

if TYPE_CHECKING:
    from pendulum_lqg.plugins import PolicyContext


def register_envs() -> None:
    """Register :data:`ENV_ID` (single and vector entry points) with Gymnasium, once.

    Called when the package is imported. A behaviour change of the environment gets a new version
    here (``-v1``), never an edit of v0.

    The entry point :func:`pendulum_lqg.envs.single.make_env` wraps the env in its own ``TimeLimit`` of
    ``duration / control_period`` steps, so ``max_episode_steps`` follows those keywords (a fixed
    registered value would cut a longer episode short); hence no ``max_episode_steps`` here.
    """
    import gymnasium

    if ENV_ID in gymnasium.registry:
        return
    gymnasium.register(
        id=ENV_ID,
        entry_point="pendulum_lqg.envs.single:make_env",
        vector_entry_point="pendulum_lqg.envs.vector:CartPoleLQGVectorEnv",
        kwargs={"duration": _DEFAULT_DURATION, "control_period": _DEFAULT_CONTROL_PERIOD},
    )


def __getattr__(name: str) -> Any:
    if name == "PolicyContext":          # the plugin API, loaded on first use
        from pendulum_lqg.plugins import PolicyContext

        return PolicyContext
    raise AttributeError(f"module 'pendulum_lqg' has no attribute {name!r}")


def _headless_gl_default() -> None:
    """Choose MuJoCo's EGL backend on a Linux machine without a display, if nothing was chosen.

    MuJoCo reads ``MUJOCO_GL`` once, when it is imported, and its default (GLFW) needs a display:
    without this, rendering (and Gymnasium's ``check_env``) fail on a headless machine. Nothing
    changes when ``MUJOCO_GL`` is set, a display exists, or MuJoCo is already imported (then the
    env's ``render`` says in one line what to set).
    """
    if ("MUJOCO_GL" in os.environ or "mujoco" in sys.modules
            or not sys.platform.startswith("linux")
            or os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        return
    os.environ["MUJOCO_GL"] = "egl"


_headless_gl_default()

#: The ``pendulum-lqg`` console script: its process needs no Gymnasium registration.
_CLI_PROCESS = PurePath(sys.argv[0]).name == "pendulum-lqg" if sys.argv else False

if not _CLI_PROCESS:
    register_envs()
