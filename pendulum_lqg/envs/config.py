"""The Gymnasium environments' configuration: keywords, spaces, actions and the reward.

Both environments (:mod:`~pendulum_lqg.envs.single`, :mod:`~pendulum_lqg.envs.vector`) take the
same keywords through :class:`EnvConfig`, map actions to forces with :class:`Actions` and reward a
step with :func:`step_reward`, so a sub-env of the vector env and a single env give the same
floats. The plant, the noise, the saturation, the failure rule and the cost are the core's
(:mod:`pendulum_lqg.core`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cache
from typing import Any, Literal, Unpack, overload

import numpy as np
from gymnasium import spaces

from pendulum_lqg.core.loop import Simulator
from pendulum_lqg.core.noise import NoiseModel
from pendulum_lqg.core.scenario import Scenario
from pendulum_lqg.envs.keywords import EnvKeywords
from pendulum_lqg.errors import ConfigError, PendulumLQGError, ShapeError
from pendulum_lqg.model.overrides import ModelOverrides, Randomization
from pendulum_lqg.model.plant import Plant, load_plant
from pendulum_lqg.problem import defaults
from pendulum_lqg.problem.declare import PositiveInt, check, coerce, declared
from pendulum_lqg.problem.env import EnvSettings, env_keywords

ObservationMode = Literal["measurement", "state"]


#: Default reward scale [J/s] (:data:`pendulum_lqg.problem.defaults.REWARD_SCALE`).
DEFAULT_REWARD_SCALE = defaults.REWARD_SCALE

#: The smallest reward of a step that survives: the smallest normal float, where ``exp`` of a
#: very large cost would underflow to the failure reward 0.
REWARD_FLOOR = float(np.finfo(np.float64).smallest_normal)


@cache
def _keywords() -> tuple[str, ...]:
    """The environments' keywords, in their declared order."""
    return tuple(d.name for d in env_keywords())


def _overrides(value: object) -> ModelOverrides:
    """The ``model_overrides`` keyword: a mapping, a :class:`ModelOverrides` or ``None``."""
    if value is None:
        return ModelOverrides()
    if isinstance(value, ModelOverrides):
        return value
    if isinstance(value, Mapping):
        return ModelOverrides.from_mapping(dict(value))
    raise ConfigError(f"model_overrides: expected a mapping or a ModelOverrides, got {value!r}")


def positive_int(name: str, value: object) -> int:
    return int(check(name, value, PositiveInt))



@dataclass(frozen=True)
class EnvConfig:
    """The validated keywords of :class:`CartPoleLQGEnv` (see its docstring for each).

    ``scenario`` is the :class:`~pendulum_lqg.core.scenario.Scenario` the sim core runs; the rest is the
    environment's own (observation mode, reward scale, model file).
    """

    scenario: Scenario
    observation_mode: ObservationMode
    reward_scale: float
    model_path: str | None
    #: the plant of a plant file (``plant`` keyword), ``None`` for the cart-pole
    plant_file: Any = None

    @classmethod
    def from_keywords(cls, keywords: Mapping[str, Any]) -> EnvConfig:
        """:meth:`build` from a mapping of keywords (an env's ``**config``, a suite's ``[env]``)."""
        return cls.build(**keywords)

    @classmethod
    def build(cls, **keywords: Unpack[EnvKeywords]) -> EnvConfig:
        """The validated configuration of the environments' keywords (declared once in
        :mod:`pendulum_lqg.problem.env`, typed by :class:`~pendulum_lqg.envs.keywords.EnvKeywords`);
        an unknown keyword or an invalid value is a one-line :class:`ConfigError` naming it."""
        given: dict[str, Any] = dict(keywords)
        known = _keywords()
        unknown = sorted(set(given) - set(known))
        if unknown:
            raise ConfigError(f"{unknown[0]}: not a keyword of the environment; known: "
                              f"{', '.join(known)}, and normalize_action, render_mode, width, "
                              "height")
        explicit = set(given)
        own = {d.name: coerce(d, given.pop(d.name, d.default))
               if d.name not in ("model_overrides", "plant") else given.pop(d.name, None)
               for d in declared(EnvSettings)}
        simulator, plant_ref = _plant_keywords(own["plant"], own["simulator"])
        if plant_ref is not None:
            return cls._of_plant_file(plant_ref, simulator, given, own, explicit)
        if simulator is not None:
            given["plant"] = simulator
        if own["process_density"] is None and own["process_noise"] == "force":
            raise ConfigError("process_density: required with process_noise='force' "
                              "(2 densities, [N²·s, N²m²·s])")
        noise_keywords = {"process_density": own["process_density"]} \
            if own["process_density"] is not None else {}
        noise = NoiseModel(process=own["process_noise"], scale=own["noise_scale"],
                           measurement_variance=own["measurement_variance"], **noise_keywords)
        scenario = Scenario(**given, noise=noise, overrides=_overrides(own["model_overrides"]),
                            randomize=Randomization.from_mapping(own["randomize"]))
        return cls(scenario=scenario, observation_mode=own["observation_mode"],
                   reward_scale=own["reward_scale"], model_path=own["model_path"])

    @classmethod
    def _of_plant_file(cls, ref: str, simulator: str | None, given: dict[str, Any],
                       own: dict[str, Any], explicit: set[str]) -> EnvConfig:
        """The configuration on a plant file's plant: the file holds the period, x0, the noise,
        the cost and the limits; a keyword for any of them is refused, one line naming it."""
        from pendulum_lqg.model.catalog import load_named_plant
        from pendulum_lqg.policies.lti import lti_scenario

        for key in (*_PLANT_FILE_HOLDS, *given):
            if key in explicit and key not in _PLANT_FILE_TAKES:
                raise ConfigError(f"{key}: not with plant={ref!r} (its plant file holds it); "
                                  f"the env takes " + ", ".join(_PLANT_FILE_TAKES)
                                  + ", observation_mode, reward_scale, noise_scale, simulator")
        plant = load_named_plant(ref, what="plant")
        if len(plant.input_names) != 1:
            raise ConfigError(f"plant: the environments take one input, the plant {ref!r} has "
                              f"{len(plant.input_names)}")
        if simulator is not None and simulator not in plant.simulators:
            raise ConfigError(f"simulator: the plant {ref!r} is simulated by "
                              f"{' or '.join(plant.simulators)}, got {simulator!r}")
        scenario = lti_scenario(plant, noise_scale=own["noise_scale"], simulator=simulator,
                                **{k: v for k, v in given.items() if k in _PLANT_FILE_TAKES})
        return cls(scenario=scenario, observation_mode=own["observation_mode"],
                   reward_scale=own["reward_scale"], model_path=None, plant_file=plant)

    def make_simulator(self, *, nthread: int | None) -> tuple[Plant, Simulator]:
        if self.plant_file is not None:
            sim = Simulator(self.plant_file, self.scenario, backend="rollout", nthread=nthread,
                            streamed_metrics=False)
            return self.plant_file, sim
        plant = load_plant(self.model_path, overrides=self.scenario.overrides)
        sim = Simulator(plant, self.scenario, backend="rollout", nthread=nthread,
                        streamed_metrics=False)
        return plant, sim


#: What an env on a plant file may set (the scenario's choices beside the file).
_PLANT_FILE_TAKES = ("duration", "force_limit", "measurement_delay", "actuator_delay", "dropout",
                     "actuator_tau")
#: The env's own keywords a plant file holds (refused with it).
_PLANT_FILE_HOLDS = ("process_noise", "process_density", "measurement_variance",
                     "model_overrides", "model_path", "randomize")
#: The words the ``plant`` keyword took before it named plants: the simulator (one release).
_SIMULATOR_WORDS = ("mujoco", "linear-zoh", "linear-euler")


def _plant_keywords(plant: object, simulator: str | None) -> tuple[str | None, str | None]:
    """``(simulator, plant reference)`` of the ``plant`` and ``simulator`` keywords: ``plant``
    names a shipped plant or a plant file (``None``: the cart-pole), or, kept one release, the
    simulator."""
    from pendulum_lqg.model.catalog import is_cartpole

    if plant is None or (isinstance(plant, str) and is_cartpole(plant)):
        return simulator, None
    if not isinstance(plant, str) or not plant.strip():
        raise ConfigError(f"plant: expected a plant name or a plant file (.toml, .npz), got "
                          f"{plant!r}")
    if plant in _SIMULATOR_WORDS:
        if simulator is not None and simulator != plant:
            raise ConfigError(f"plant: {plant!r} names the simulator, as simulator={simulator!r} "
                              f"does; give one")
        return plant, None
    return simulator, plant


@overload
def step_reward(cost: np.ndarray, failed: np.ndarray, scale_dt: float) -> np.ndarray: ...
@overload
def step_reward(cost: np.float64 | float, failed: bool, scale_dt: float) -> float: ...
def step_reward(cost: np.ndarray | np.float64 | float, failed: np.ndarray | bool, scale_dt: float,
                ) -> np.ndarray | float:
    """``r = exp(−c / (s·T))`` for a period that survived (at least :data:`REWARD_FLOOR`, so it is
    always worth more than failing), ``0`` for the period that failed.

    One function for the single env (a scalar cost) and the vector env (arrays), so both give the
    same floats.
    """
    r = np.exp(cost / -scale_dt)
    if isinstance(r, np.ndarray):
        np.maximum(r, REWARD_FLOOR, out=r)
        if np.count_nonzero(failed):
            r[failed] = 0.0
        return r
    if failed:
        return 0.0
    r = float(r)
    return REWARD_FLOOR if REWARD_FLOOR > r else r       # max(r, floor) without the call


def _action_force(action: object, n: int) -> np.ndarray:
    """Forces (n,) float64 from an action of shape (1,) (single env) or (n, 1) / (n,) (vector)."""
    if type(action) is np.ndarray and action.shape in ((n,), (n, 1)) \
            and action.dtype.kind == "f":                      # the common case, kept cheap
        u = action.astype(np.float64).reshape(n)
        # one sum is the fast check (a finite sum has finite terms; an overflowing one is
        # checked term by term)
        if (math.isfinite(u[0]) if n == 1 else
                math.isfinite(u.sum()) or bool(np.isfinite(u).all())):
            return u
        raise PendulumLQGError(f"action: expected finite forces, got {u!r}")
    try:
        u = np.asarray(action)
        complex_action = u.dtype.kind == "c"        # a cast would drop the imaginary part
        if not complex_action:
            u = np.asarray(u, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ShapeError(f"action: expected {n} force(s) in newtons, got {_short(action)}") \
            from exc
    if complex_action:
        raise PendulumLQGError(f"action: expected real forces in newtons, got complex "
                               f"{_short(action)}")
    if u.shape not in ((n,), (n, 1)) and not (n == 1 and u.shape == ()):
        want = "(1,)" if n == 1 else f"({n}, 1)"
        raise ShapeError(f"action: expected shape {want}, found {u.shape}")
    u = u.reshape(n)
    if not np.all(np.isfinite(u)):
        raise PendulumLQGError(f"action: expected finite forces, got {u!r}")
    return u


def true_outputs(sim: Simulator, x: np.ndarray) -> np.ndarray:
    """The noise-free outputs ``y = C x`` of states ``x`` (one or a batch), a new array: the
    cart-pole's measured states ``[p, θ]`` themselves (its layout has no C), else ``x Cᵀ``."""
    C = sim.layout.C
    return x[..., :sim.layout.p].copy() if C is None else x @ C.T


def _short(value: object) -> str:
    """``repr(value)`` on one line, cut to a readable length."""
    text = " ".join(repr(value).split())
    return text if len(text) <= 120 else text[:117] + "..."


class Actions:
    """The action space and the map from actions to requested forces [N].

    ``normalize_action=False``: the action is the force, ``Box(lo, hi)`` from the force limit in
    force (the scenario's ``force_limit``, else the actuator's ``ctrlrange``; unbounded for
    ``inf``), ``u_max`` [N]; ``True``: an action in ``[−1, 1]`` maps linearly onto ``[lo, hi]``. Either
    way the core saturates the force to ``[lo, hi]``.
    """

    def __init__(self, u_max: float, normalize: object) -> None:
        normalize = bool(check("normalize_action", normalize, bool))
        if normalize and not math.isfinite(u_max):
            raise ConfigError("normalize_action: needs a finite force_limit (an action in [−1, 1] "
                              "maps onto [−force_limit, force_limit])")
        self.normalize = normalize
        self.lo, self.hi = -u_max, u_max
        bound = (-1.0, 1.0) if normalize else (self.lo, self.hi)
        self.space = spaces.Box(np.float32(bound[0]), np.float32(bound[1]), shape=(1,),
                                dtype=np.float32)

    def force(self, action: object) -> float:
        """The requested force [N] of a single env's action (shape (1,))."""
        if type(action) is np.ndarray and action.shape == (1,) and action.dtype.kind == "f":
            u = action.item()                                  # the common case, kept cheap
            if not math.isfinite(u):
                raise PendulumLQGError(f"action: expected finite forces, got {action!r}")
        else:
            u = float(_action_force(action, 1)[0])
        return self._to_newtons(u) if self.normalize else u

    def forces(self, action: object, n: int) -> np.ndarray:
        return self._to_newtons(_action_force(action, n))

    @overload
    def _to_newtons(self, u: float) -> float: ...
    @overload
    def _to_newtons(self, u: np.ndarray) -> np.ndarray: ...
    def _to_newtons(self, u: np.ndarray | float) -> np.ndarray | float:
        """Actions → requested forces: ``[−1, 1]`` onto ``[lo, hi]`` when normalized."""
        if self.normalize:
            return self.lo + (u + 1.0) * (0.5 * (self.hi - self.lo))
        return u

    def from_newtons(self, u: np.ndarray) -> np.ndarray:
        """Requested forces [N] → the actions that request them: the inverse of the map above.

        Normalized, the round trip agrees to a few ulps of the force limit, not bit for bit: the
        map rounds ``a + 1``, which keeps a small force to about 1e-16 of the limit only."""
        if self.normalize:
            return (u - self.lo) / (0.5 * (self.hi - self.lo)) - 1.0
        return u
