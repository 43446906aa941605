"""The Gymnasium environments' configuration: keywords, spaces, actions and the reward.

Both environments (:mod:`~pendulum_lqg.envs.single`, :mod:`~pendulum_lqg.envs.vector`) take the
same keywords through :class:`EnvConfig`, map actions to forces with :class:`Actions` and reward a
step with :func:`step_reward`, so a sub-env of the vector env and a single env give the same
floats. The plant, the noise, the saturation, the failure rule and the cost are the core's
(:mod:`pendulum_lqg.core`).
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Literal, overload

import numpy as np
from gymnasium import spaces

from pendulum_lqg.core import defaults
from pendulum_lqg.core.loop import Simulator
from pendulum_lqg.core.noise import LECTURE_V, NoiseModel
from pendulum_lqg.core.scenario import Scenario
from pendulum_lqg.errors import ConfigError, PendulumLQGError, ShapeError
from pendulum_lqg.model.plant import ModelOverrides, Plant, load_plant
from pendulum_lqg.names import OBSERVATION_MODES
from pendulum_lqg.problem.declare import positive_number

ObservationMode = Literal["measurement", "state"]


#: Default reward scale: the cost rate [J/s] at which a step's reward is e⁻¹ (the lecture LQG
#: policy runs at ≈ 3.4 J/s, the full-state LQR at ≈ 0.18 J/s).
DEFAULT_REWARD_SCALE = 10.0

#: The smallest reward of a step that survives: the smallest normal float, where ``exp`` of a
#: very large cost would underflow to the failure reward 0.
REWARD_FLOOR = float(np.finfo(np.float64).smallest_normal)


def positive_int(name: str, value: object) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
        raise ConfigError(f"{name}: expected a positive integer, got {value!r}")
    return int(value)



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

    @classmethod
    def from_keywords(cls, keywords: dict[str, Any]) -> EnvConfig:
        """:meth:`build` from an env's ``**keywords`` (an unknown keyword is a one-line error)."""
        unknown = sorted(set(keywords) - set(inspect.signature(cls.build).parameters))
        if unknown:
            known = ", ".join(p for p in inspect.signature(cls.build).parameters if p != "cls")
            raise ConfigError(f"{unknown[0]}: not a keyword of the environment; known: {known}, "
                              "and normalize_action, render_mode, width, height")
        return cls.build(**keywords)

    @classmethod
    def build(cls, *, control_period: float = defaults.CONTROL_PERIOD,
              duration: float = defaults.DURATION,
              observation_mode: ObservationMode = "measurement", noise_scale: float = 1.0,
              process_noise: Literal["state", "force"] = "state",
              process_density: float | Sequence[float] | None = None,
              measurement_variance: float | Sequence[float] = LECTURE_V,
              x0: Sequence[float] = defaults.X0, x0_std: Sequence[float] = defaults.X0_STD,
              theta_max: float = defaults.THETA_MAX,
              track_limit: float | None = None, force_limit: float | None = None,
              cost_Q: Sequence[float] = defaults.COST_Q, cost_R: float = defaults.COST_R,
              reward_scale: float = DEFAULT_REWARD_SCALE,
              model_overrides: Mapping[str, float] | ModelOverrides | None = None,
              model_path: str | None = None, plant: str = "mujoco",
              measurement_delay: float = 0.0, actuator_delay: float = 0.0, dropout: float = 0.0,
              actuator_tau: float = 0.0, randomize: Mapping[str, Sequence[float]] | None = None,
              ) -> EnvConfig:
        """The one list of the environments' scenario keywords and their defaults (documented in
        :class:`CartPoleLQGEnv`); both env classes pass their ``**config`` here."""
        if observation_mode not in OBSERVATION_MODES:
            raise ConfigError(f"observation_mode: expected 'measurement' or 'state', got "
                              f"{observation_mode!r}")
        if process_noise not in ("state", "force"):
            raise ConfigError(f"process_noise: expected 'state' or 'force', got {process_noise!r}")
        if process_density is None:
            if process_noise == "force":
                raise ConfigError("process_density: required with process_noise='force' "
                                  "(2 densities, [N²·s, N²m²·s])")
            noise = NoiseModel(measurement_variance=measurement_variance,  # type: ignore[arg-type]
                               scale=noise_scale)
        else:
            noise = NoiseModel(process=process_noise,
                               process_density=process_density,  # type: ignore[arg-type]
                               measurement_variance=measurement_variance,  # type: ignore[arg-type]
                               scale=noise_scale)
        if model_overrides is None:
            overrides = ModelOverrides()
        elif isinstance(model_overrides, ModelOverrides):
            overrides = model_overrides
        elif isinstance(model_overrides, Mapping):
            overrides = ModelOverrides.from_mapping(dict(model_overrides))
        else:
            raise ConfigError(f"model_overrides: expected a mapping or a ModelOverrides, got "
                              f"{model_overrides!r}")
        if model_path is not None and not isinstance(model_path, str):
            raise ConfigError(f"model_path: expected a path string, got {model_path!r}")
        scenario = Scenario(control_period=control_period, duration=duration, noise=noise,
                            x0=x0, x0_std=x0_std, theta_max=theta_max,  # type: ignore[arg-type]
                            track_limit=track_limit, force_limit=force_limit,
                            cost_Q=cost_Q, cost_R=cost_R, overrides=overrides,  # type: ignore[arg-type]
                            plant=plant,
                            measurement_delay=measurement_delay, actuator_delay=actuator_delay,
                            dropout=dropout, actuator_tau=actuator_tau,
                            randomize=dict(randomize) if isinstance(randomize, Mapping)
                            else randomize)  # type: ignore[arg-type]
        return cls(scenario=scenario, observation_mode=observation_mode,
                   reward_scale=positive_number("reward_scale", reward_scale), model_path=model_path)

    def make_simulator(self, *, nthread: int | None) -> tuple[Plant, Simulator]:
        plant = load_plant(self.model_path, overrides=self.scenario.overrides)
        sim = Simulator(plant, self.scenario, backend="rollout", nthread=nthread,
                        streamed_metrics=False)
        return plant, sim


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
        if not isinstance(normalize, bool):
            raise ConfigError(f"normalize_action: expected True or False, got {normalize!r}")
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
