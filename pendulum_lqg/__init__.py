"""pendulum_lqg: LQG control of a MuJoCo cart-pole under noise — design, simulation, benchmark.

The names a program needs are imported from the package itself; each loads its module on first
use, so ``import pendulum_lqg`` loads neither Gymnasium, numpy nor MuJoCo::

    from pendulum_lqg import Scenario, run_episodes, load_plant, build_policy

    plant, scenario = load_plant(), Scenario()
    policy = build_policy("dlqr+kalman", plant=plant, scenario=scenario)
    rows = run_episodes(plant, scenario, policy, seed=0, episodes=range(8)).rows

The Gymnasium environment :data:`ENV_ID` is registered when Gymnasium is already imported at the
package's import, when :data:`ENV_ID` is read from the package, or by :func:`register_envs`::

    import gymnasium as gym
    import pendulum_lqg

    env = gym.make(pendulum_lqg.ENV_ID)   # or gym.make("pendulum_lqg:pendulum_lqg/CartPoleLQG-v0")

Public API (a change gets a version bump and a CHANGELOG.md entry): the names in :data:`__all__`,
the policy-plugin protocol (:mod:`pendulum_lqg.policies.loading`), the CLI flags and the results
schema (:data:`SCHEMA_VERSION`). Every other name is reached through its module's real path
(docs/architecture.md has the map).
"""

from __future__ import annotations

import importlib
import os
import sys
from typing import TYPE_CHECKING, Any

from pendulum_lqg.envs.registration import register_envs
from pendulum_lqg.errors import ConfigError, DesignError, PendulumLQGError, PluginError, ShapeError
from pendulum_lqg.version import SCHEMA_VERSION, __version__

if TYPE_CHECKING:
    from pendulum_lqg.core.noise import NoiseModel
    from pendulum_lqg.core.runner import BatchResult, run_episodes
    from pendulum_lqg.core.scenario import Scenario
    from pendulum_lqg.core.seeding import episode_seed
    from pendulum_lqg.core.trajectory import Trajectory
    from pendulum_lqg.envs.agent import LQGAgent
    from pendulum_lqg.envs.config import EnvConfig
    from pendulum_lqg.envs.registration import ENV_ID
    from pendulum_lqg.envs.single import CartPoleLQGEnv
    from pendulum_lqg.envs.vector import CartPoleLQGVectorEnv
    from pendulum_lqg.model.plant import Plant, load_plant
    from pendulum_lqg.policies.loading import PolicyContext, build_policy
    from pendulum_lqg.policies.lqg import DesignSpec, design_policy

#: Each name of the public API that loads on first use, and the module that defines it.
LAZY: dict[str, str] = {
    "Scenario": "pendulum_lqg.core.scenario",
    "NoiseModel": "pendulum_lqg.core.noise",
    "run_episodes": "pendulum_lqg.core.runner",
    "BatchResult": "pendulum_lqg.core.runner",
    "Trajectory": "pendulum_lqg.core.trajectory",
    "episode_seed": "pendulum_lqg.core.seeding",
    "Plant": "pendulum_lqg.model.plant",
    "load_plant": "pendulum_lqg.model.plant",
    "DesignSpec": "pendulum_lqg.policies.lqg",
    "design_policy": "pendulum_lqg.policies.lqg",
    "build_policy": "pendulum_lqg.policies.loading",
    "PolicyContext": "pendulum_lqg.policies.loading",
    "LQGAgent": "pendulum_lqg.envs.agent",
    "EnvConfig": "pendulum_lqg.envs.config",
    "CartPoleLQGEnv": "pendulum_lqg.envs.single",
    "CartPoleLQGVectorEnv": "pendulum_lqg.envs.vector",
}

__all__ = [
    "ENV_ID",
    "SCHEMA_VERSION",
    "BatchResult",
    "CartPoleLQGEnv",
    "CartPoleLQGVectorEnv",
    "ConfigError",
    "DesignError",
    "DesignSpec",
    "EnvConfig",
    "LQGAgent",
    "NoiseModel",
    "PendulumLQGError",
    "Plant",
    "PluginError",
    "PolicyContext",
    "Scenario",
    "ShapeError",
    "Trajectory",
    "__version__",
    "build_policy",
    "design_policy",
    "episode_seed",
    "load_plant",
    "register_envs",
    "run_episodes",
]


def __getattr__(name: str) -> Any:
    if name == "ENV_ID":                 # reading the id registers it: gym.make(pendulum_lqg.ENV_ID)
        from pendulum_lqg.envs.registration import ENV_ID

        register_envs()
        return ENV_ID
    if name in LAZY:
        return getattr(importlib.import_module(LAZY[name]), name)
    raise AttributeError(f"module 'pendulum_lqg' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})


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

# A program that imported Gymnasium first (``gym.make("pendulum_lqg:…")`` does) finds the id
# registered, as with any Gymnasium environment package; registering then costs nothing more.
if "gymnasium" in sys.modules:
    register_envs()
