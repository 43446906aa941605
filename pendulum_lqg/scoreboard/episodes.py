"""Playing a suite's episodes: a policy through the batch, or a Gymnasium agent through the env.

Both paths give one row per episode — ``episode``, ``seed``, ``success``, ``failure_reason`` and
``cost`` (J, the integral of ``xᵀQx + R u²`` until the end or the failure) — for episodes
``0 … episodes−1`` seeded
``episode_seed(suite.seed, k)``. A controller wrapped both ways (a plug-in, and the same plug-in
as a Gymnasium agent: :class:`PluginAgent`) gives identical rows: the env is the core's one-row
simulator, with the same noise streams, saturation, failure rule and cost.

A **Gymnasium agent** is what a factory ``f(env)`` returns: an object with ``reset()`` (a new
episode starts) and ``act(observation) -> action``. References: ``MODULE:ATTR`` or
``path/to/file.py:ATTR`` (loaded like a plug-in), ``sb3:PATH.zip`` (a stable-baselines3 model:
:mod:`pendulum_lqg.scoreboard.sb3`) or ``linear:FILE.json`` (a linear controller of a y/u history:
:mod:`pendulum_lqg.scoreboard.linear`).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any, Protocol, cast

import gymnasium as gym
import numpy as np

from pendulum_lqg.core.protocol import optional_members
from pendulum_lqg.core.runner import run_episodes
from pendulum_lqg.core.seeding import episode_seeds
from pendulum_lqg.envs.registration import ENV_ID, register_envs
from pendulum_lqg.errors import ConfigError, NotApplicable, PluginError
from pendulum_lqg.policies.loading import build_policy, guard, is_plugin_ref, load_factory
from pendulum_lqg.scoreboard.suites import Suite, design_plant

#: The fields of a scored episode row.
ROW_FIELDS = ("episode", "seed", "success", "failure_reason", "cost")


class Agent(Protocol):
    """A Gymnasium agent: one episode at a time, observations in, actions out."""

    def reset(self) -> None: ...

    def act(self, observation: np.ndarray) -> np.ndarray: ...


AgentFactory = Callable[[gym.Env], Agent]


# ---- the batch path ---------------------------------------------------------------------------------
def policy_rows(suite: Suite, policy: str, *, base_dir: Path | None = None,
                nthread: int | None = None) -> list[dict[str, Any]]:
    """The rows of a built-in (``"dlqr+kalman"``) or plug-in (``MODULE:ATTR``) policy on the
    suite, through :func:`~pendulum_lqg.core.runner.run_episodes` (the batch), designed on (or, a
    plug-in, given the context of) the suite's design plant
    (:func:`~pendulum_lqg.scoreboard.suites.design_plant`).

    What the policy observes is the suite's: in a ``full-state`` suite it must declare
    ``needs_state = True`` (a built-in ``controller+none``), elsewhere it must not (it would see
    the true state the suite hides). On a plant's suite
    (:class:`~pendulum_lqg.scoreboard.lti_suite.LTISuite`) a built-in designed on its plant
    (:meth:`~pendulum_lqg.scoreboard.lti_suite.LTISuite.rows`)."""
    if _plant_suite(suite):
        return cast(Any, suite).rows(policy)
    return _batch_rows(suite, policy, base_dir=base_dir, nthread=nthread, check=True)


def _plant_suite(suite: Any) -> bool:
    """``suite`` is a plant's suite (an :class:`~pendulum_lqg.scoreboard.lti_suite.LTISuite`, which
    names its plant file; not imported here: that module imports this one through the score)."""
    return getattr(suite, "lti_file", None) is not None


def full_state_rows(suite: Suite, *, nthread: int | None = None) -> list[dict[str, Any]]:
    """The rows of the full-state LQR (``dlqr+none``: the true state, no estimator) in the suite's
    scenario — the bound of what observation costs, also where the suite observes only ``y``."""
    if _plant_suite(suite):
        return cast(Any, suite).rows("dlqr+none")
    return _batch_rows(suite, "dlqr+none", base_dir=None, nthread=nthread, check=False)


def _batch_rows(suite: Suite, policy: str, *, base_dir: Path | None, nthread: int | None,
                check: bool) -> list[dict[str, Any]]:
    simulated, design = suite.plants()
    scenario = suite.config.scenario
    built = build_policy(policy, plant=design, scenario=scenario, base_dir=base_dir)
    if check:
        _check_observation(suite, policy, optional_members(built).needs_state)
    res = run_episodes(simulated, scenario, built, seed=suite.seed, episodes=range(suite.episodes),
                       nthread=nthread)
    return [{"episode": r["episode"], "seed": r["seed"], "success": r["success"],
             "failure_reason": r["failure_reason"], "cost": r["cost"]} for r in res.rows]


def _check_observation(suite: Suite, name: str, needs_state: bool) -> None:
    if suite.observes_state and not needs_state:
        raise NotApplicable(f"policy {name!r} takes y = [p, θ]; suite {suite.name!r} gives the "
                            "true state (a full-state policy: controller+none, or a plug-in with "
                            "needs_state = True)")
    if needs_state and not suite.observes_state:
        raise NotApplicable(f"policy {name!r} needs the true state, which suite {suite.name!r} "
                            "does not give (it observes y = [p, θ])")


# ---- the Gymnasium path ---------------------------------------------------------------------------
def make_env(suite: Suite, *, normalize_action: bool = False) -> gym.Env:
    """The suite's Gymnasium env (``gymnasium.make`` with the suite's keywords)."""
    register_envs()          # the package registers the id only when Gymnasium is loaded
    return gym.make(ENV_ID, normalize_action=normalize_action, **suite.env)


def agent_rows(suite: Suite, factory: AgentFactory, *, name: str = "agent",
               normalize_action: bool = False) -> list[dict[str, Any]]:
    """The rows of a Gymnasium agent on the suite: ``env.reset(seed=episode_seed(seed, k))``,
    ``agent.reset()``, then ``env.step(agent.act(obs))`` until the episode ends."""
    env = make_env(suite, normalize_action=normalize_action)
    label = f"agent {name!r}"
    agent = guard(label, "the factory", factory, env, passing=(NotApplicable,))
    for member in ("reset", "act"):
        if not callable(guard(label, f"reading {member}", getattr, agent, member, None)):
            raise PluginError(f"{label}: the factory returned {type(agent).__name__}, "
                              f"which has no {member}() method (expected reset() and act(obs))")
    def act(observation: np.ndarray) -> np.ndarray:      # the action converted: __array__ is theirs
        return np.asarray(agent.act(observation))

    rows = []
    for k, seed in enumerate(episode_seeds(suite.seed, range(suite.episodes))):
        obs, info = env.reset(seed=seed)
        guard(label, "reset", agent.reset)
        terminated = truncated = False
        while not (terminated or truncated):
            action = guard(label, "act", act, obs)
            obs, _, terminated, truncated, info = env.step(action)
        rows.append({"episode": k, "seed": seed, "success": not terminated,
                     "failure_reason": info["failure_reason"],
                     "cost": float(info["running_cost"])})
    env.close()
    return rows


class PluginAgent:
    """A batched plug-in policy as a Gymnasium agent of one env (its twin on the Gymnasium path).

    ``reset()`` starts one row (``policy.reset(1)``); ``act(obs)`` is ``policy.act(obs[None])``.
    The plug-in is built on the env's design plant (:func:`~pendulum_lqg.scoreboard.suites.design_plant`),
    as on the batch path, and the env saturates the force as the core does, so the rows equal
    the plug-in's batch rows.
    """

    def __init__(self, env: gym.Env, ref: str, *, base_dir: Path | None = None) -> None:
        base: Any = env.unwrapped
        self.policy = build_policy(ref, plant=design_plant(base.config), scenario=base.scenario,
                                   base_dir=base_dir)
        if base.normalize_action:
            raise ConfigError(f"agent {ref!r}: a plug-in acts in newtons; score it on an env "
                              "without normalize_action")
        _check_observation_mode(ref, base.observation_mode,
                                optional_members(self.policy).needs_state)

    def reset(self) -> None:
        self.policy.reset(1)

    def act(self, observation: np.ndarray) -> np.ndarray:
        return np.asarray(self.policy.act(np.asarray(observation, dtype=float)[None, :]),
                          dtype=float).reshape(1)


def _check_observation_mode(name: str, mode: str, needs_state: bool) -> None:
    if (mode == "state") != needs_state:
        raise NotApplicable(f"policy {name!r} observes {'x' if needs_state else 'y = [p, θ]'}; "
                            f"this env gives {'x' if mode == 'state' else 'y = [p, θ]'}")


def plugin_agent(ref: str, *, base_dir: Path | None = None) -> AgentFactory:
    """The factory of :class:`PluginAgent` for the plug-in ``ref``."""
    return lambda env: PluginAgent(env, ref, base_dir=base_dir)


def load_agent(ref: str, *, base_dir: Path | None = None) -> AgentFactory:
    """The agent factory a reference names: ``sb3:PATH.zip``, ``linear:FILE.json``, ``MODULE:ATTR``
    or ``file.py:ATTR``."""
    if not isinstance(ref, str) or not ref:
        raise ConfigError(f"agent: expected MODULE:ATTR, path/to/file.py:ATTR, sb3:PATH.zip or "
                          f"linear:FILE.json, got {ref!r}")
    if ref.startswith("sb3:"):
        from pendulum_lqg.scoreboard.sb3 import sb3_agent

        return sb3_agent(ref.removeprefix("sb3:"))
    if ref.startswith("linear:"):
        from pendulum_lqg.scoreboard.linear import linear_agent

        return linear_agent(ref.removeprefix("linear:"))
    if not is_plugin_ref(ref):
        raise ConfigError(f"agent: expected MODULE:ATTR, path/to/file.py:ATTR, sb3:PATH.zip or "
                          f"linear:FILE.json, got {ref!r}")
    return load_factory(ref, base_dir=base_dir)       # type: ignore[return-value]


def reference_agent(env: gym.Env) -> Agent:
    """:class:`~pendulum_lqg.envs.agent.LQGAgent` with the design a suite's reference uses for this
    env: full-state feedback (``none``) when the env observes the state, the delay-aware Kalman
    filter (``kalman-delay``) when it has a measurement or actuator delay, else the steady-state
    Kalman filter (:func:`reference_design`), designed as the suites' reference is: on the env's
    plant with its ``model_overrides`` and without its ``randomize`` draws
    (:func:`~pendulum_lqg.scoreboard.suites.design_plant`, which the env's plant is)."""
    from pendulum_lqg.envs.agent import LQGAgent

    base: Any = env.unwrapped
    controller, observer = reference_design(base.observation_mode, base.scenario).split("+")
    return LQGAgent(env, controller=controller, observer=observer, design_model="simulated")


def reference_design(observation_mode: str, scenario: Any) -> str:
    """The best built-in LQG design for a scenario: the rule the suites' references follow."""
    if observation_mode == "state":
        return "dlqr+none"
    if scenario.measurement_delay > 0 or scenario.actuator_delay > 0:
        return "dlqr+kalman-delay"
    return "dlqr+kalman"


__all__ = [
    "ROW_FIELDS",
    "Agent",
    "AgentFactory",
    "PluginAgent",
    "agent_rows",
    "full_state_rows",
    "load_agent",
    "make_env",
    "plugin_agent",
    "policy_rows",
    "reference_agent",
    "reference_design",
]
