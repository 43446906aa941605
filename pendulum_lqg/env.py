"""Gymnasium environments on the one simulation core: a single env and a native batched vector env.

Both are thin adapters over :class:`~pendulum_lqg.sim.Simulator`: the plant, the noise models, the
saturation, the failure rule and the cost are the sim core's; nothing here steps MuJoCo, draws
noise or integrates a cost. The ids are registered in ``pendulum_lqg/__init__.py``
(:data:`pendulum_lqg.ENV_ID`).

One env step is one control period ``T``: the core's measure → act → step order of
:func:`~pendulum_lqg.sim.run_episodes`, so ``env.reset(seed=episode_seed(s, k))`` replays episode
``k`` of a ``pendulum-lqg`` run seeded ``s`` bit for bit.
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Literal, SupportsFloat, overload

import gymnasium as gym
import mujoco
import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space
from gymnasium.wrappers import TimeLimit

from pendulum_lqg._config import positive_number
from pendulum_lqg.errors import ConfigError, PendulumLQGError, ShapeError
from pendulum_lqg.metrics import FAIL_NONE, FAIL_REASONS
from pendulum_lqg.noise import LECTURE_V, NoiseModel
from pendulum_lqg.plant import CART_BODY, ModelOverrides, Plant, load_plant
from pendulum_lqg.sim import Scenario, Simulator, StepResult

ObservationMode = Literal["measurement", "state"]
OBSERVATION_MODES: tuple[str, ...] = ("measurement", "state")

#: Rendering camera: tracks the cart from the side (the view of the XML's ``side`` camera, but
#: close enough to frame cart and pole), at this many pole lengths away.
CAMERA_DISTANCE_POLE_LENGTHS = 3.0

#: Default reward scale: the cost rate [J/s] at which a step's reward is e⁻¹ (the lecture LQG
#: policy runs at ≈ 3.4 J/s, the full-state LQR at ≈ 0.18 J/s).
DEFAULT_REWARD_SCALE = 10.0

#: The smallest reward of a step that survives: the smallest normal float, where ``exp`` of a
#: very large cost would underflow to the failure reward 0.
REWARD_FLOOR = float(np.finfo(np.float64).smallest_normal)


def _positive_int(name: str, value: object) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 1:
        raise ConfigError(f"{name}: expected a positive integer, got {value!r}")
    return int(value)


@dataclass(frozen=True)
class EnvConfig:
    """The validated keywords of :class:`CartPoleLQGEnv` (see its docstring for each).

    ``scenario`` is the :class:`~pendulum_lqg.sim.Scenario` the sim core runs; the rest is the
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
    def build(cls, *, control_period: float = 0.01, duration: float = 10.0,
              observation_mode: ObservationMode = "measurement", noise_scale: float = 1.0,
              process_noise: Literal["state", "force"] = "state",
              process_density: float | Sequence[float] | None = None,
              measurement_variance: float | Sequence[float] = LECTURE_V,
              x0: Sequence[float] = (0.0, 0.1, 0.0, 0.0),
              x0_std: Sequence[float] = (0.0, 0.0, 0.0, 0.0), theta_max: float = 0.5,
              cost_Q: Sequence[float] = (1.0, 1.0, 1.0, 1.0), cost_R: float = 1.0,
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
    return 0.0 if failed else max(float(r), REWARD_FLOOR)


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
        u = np.asarray(action, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ShapeError(f"action: expected {n} force(s) in newtons, got {action!r}") from exc
    if u.shape not in ((n,), (n, 1)) and not (n == 1 and u.shape == ()):
        want = "(1,)" if n == 1 else f"({n}, 1)"
        raise ShapeError(f"action: expected shape {want}, found {u.shape}")
    u = u.reshape(n)
    if not np.all(np.isfinite(u)):
        raise PendulumLQGError(f"action: expected finite forces, got {u!r}")
    return u


class _Actions:
    """The action space and the map from actions to requested forces [N].

    ``normalize_action=False``: the action is the force, ``Box(lo, hi)`` from the actuator's
    ``ctrlrange``; ``True``: an action in ``[−1, 1]`` maps linearly onto ``[lo, hi]``. Either
    way the core saturates the force to ``[lo, hi]``.
    """

    def __init__(self, plant: Plant, normalize: object) -> None:
        if not isinstance(normalize, bool):
            raise ConfigError(f"normalize_action: expected True or False, got {normalize!r}")
        self.normalize = normalize
        self.lo, self.hi = plant.force_limit
        bound = (-1.0, 1.0) if normalize else (self.lo, self.hi)
        self.space = spaces.Box(np.float32(bound[0]), np.float32(bound[1]), shape=(1,),
                                dtype=np.float32)

    def force(self, action: object) -> float:
        """The requested force [N] of a single env's action (shape (1,))."""
        if type(action) is np.ndarray and action.shape == (1,) and action.dtype.kind == "f":
            u = float(action[0])                               # the common case, kept cheap
            if not math.isfinite(u):
                raise PendulumLQGError(f"action: expected finite forces, got {action!r}")
        else:
            u = float(_action_force(action, 1)[0])
        return self._to_newtons(u)

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

    def applied(self, u: float) -> float:
        """The force the actuator applies to a single env's requested force ``u`` (saturated, as
        the core saturates it; the vector env takes it from the core's
        :attr:`~pendulum_lqg.sim.StepResult.requested`)."""
        return min(max(u, self.lo), self.hi)


class _Frames:
    """Offscreen frames of the cart-pole at given states: a side view tracking the cart."""

    def __init__(self, plant: Plant, width: int, height: int) -> None:
        self.plant, self.width, self.height = plant, width, height
        self._renderer: mujoco.Renderer | None = None
        self._data: mujoco.MjData | None = None
        self._camera: mujoco.MjvCamera | None = None

    def frame(self, x: np.ndarray) -> np.ndarray:
        """An RGB image (height, width, 3) uint8 of the state ``x = [p, θ, ṗ, θ̇]``."""
        model = self.plant.model
        if self._renderer is None:
            self._renderer = _make_renderer(model, self.height, self.width)
            self._data = mujoco.MjData(model)
            cam = mujoco.MjvCamera()
            cam.type = mujoco.mjtCamera.mjCAMERA_TRACKING
            cam.trackbodyid = model.body(CART_BODY).id
            cam.distance = CAMERA_DISTANCE_POLE_LENGTHS * self.plant.pole_length
            cam.azimuth, cam.elevation = 90.0, -10.0      # from −y, x to the right: a side view
            self._camera = cam
        assert self._data is not None
        self.plant.set_state(self._data, x)
        self._renderer.update_scene(self._data, camera=self._camera)
        return self._renderer.render()

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
        self._renderer = self._data = self._camera = None

    def __getstate__(self) -> dict[str, Any]:
        # GL resources (and the camera, which does not pickle) are made again on demand
        return {**self.__dict__, "_renderer": None, "_data": None, "_camera": None}


class CartPoleLQGEnv(gym.Env[np.ndarray, np.ndarray]):
    """
    ## Description
    The MuJoCo cart-pole of `models/cartpole.xml` (a 1 kg cart on a ±2.4 m rail carrying a
    uniform 1 m, 0.1 kg pole; a ±10 N motor) balanced upright under process and measurement noise:
    the stochastic LQG problem of the lecture, as a Gymnasium environment. It runs on the same
    simulation core as `pendulum-lqg run` / `bench` — same plant, noise models, saturation,
    failure rule and cost — so an agent is scored exactly as the benchmark scores its policies.
    One step is one control period `T` (default 10 ms = 10 physics steps of 1 ms): the agent's
    force is held (zero-order hold) over the period.

    ## Action Space
    A `Box(-10, 10, (1,), float32)` (bounds read from the actuator `ctrlrange` × `gear`):

    | Num | Action                   | Min | Max | Name (in XML) | Joint | Type (Unit) |
    |-----|--------------------------|-----|-----|---------------|-------|-------------|
    | 0   | horizontal force on cart | -10 | 10  | force         | slide | force (N)   |

    Units: newtons. Forces outside the range are saturated (clipped to ±10 N, as in the
    benchmark); `info["force"]` is the force actually applied. With `normalize_action=True` the
    action space is `Box(-1, 1, (1,), float32)` and an action `a` requests the force
    `lo + (a + 1)/2 · (hi − lo)` (±1 ↔ ±10 N). Actions are applied at float64 precision: a
    float64 action is used as given (the LQG agent returns float64, so its forces — and J — equal
    the benchmark's bit for bit); a float32 one is widened. A non-finite action is an error.

    ## Observation Space
    `observation_mode="measurement"` (default, the LQG problem): the noisy measurement
    `y = [p, θ] + v`, `v ~ N(0, V)` per sample, a `Box(-inf, inf, (2,), float64)`:

    | Num | Observation                  | Min  | Max | Name (in XML)                   | Joint | Unit |
    |-----|------------------------------|------|-----|---------------------------------|-------|------|
    | 0   | cart position p (+ noise)    | -Inf | Inf | slider (sensor `cart_position`) | slide | m    |
    | 1   | pole angle θ (+ noise)       | -Inf | Inf | hinge (sensor `pole_angle`)     | hinge | rad  |

    `observation_mode="state"`: the true state `x = [p, θ, ṗ, θ̇]`, a `Box(-inf, inf, (4,), float64)`
    (rows 0–1 as above without noise; 2: cart velocity ṗ (m/s), slider; 3: pole rate θ̇ (rad/s),
    hinge). θ = 0 is upright, θ > 0 tips the pole towards +x.

    The observation after the step in which the episode failed is noise-free (that period's
    noise is never drawn, as in the benchmark).

    ## Rewards
    With `c` the quadratic cost of the step, `c = ∫ xᵀ diag(cost_Q) x + cost_R u² dt` over the
    period (the benchmark's J, integrated at the physics step):

    - a step that does not fail: `r = exp(−c / (reward_scale · T))` ∈ (0, 1] — 1 at rest upright with
      no force, e⁻¹ at a mean cost rate of `reward_scale` J/s; never below the smallest normal
      float (2.2e-308), where the exponential would underflow to 0;
    - the step in which the episode fails: `r = 0`, and the episode ends.

    Failing therefore never pays: from any state, failing now returns 0 while any continuation
    that does not fail returns more than 0. `info` carries the exact cost, so agents are compared
    on J and success exactly as `bench` compares policies:

    | key            | value                                                            |
    |----------------|------------------------------------------------------------------|
    | `cost`         | `c`, the LQ cost of this step (0 after reset)                    |
    | `running_cost` | J so far in the episode (the benchmark's `cost` at the end)      |
    | `state`        | the true state `[p, θ, ṗ, θ̇]` (4,) at the new sample            |
    | `y_true`       | the noise-free measurement `[p, θ]` (2,)                         |
    | `failure_reason` | `""`, `"pole_fell"`, `"track_limit"` or `"diverged"`           |
    | `time`         | time of the new sample [s]                                       |
    | `force`        | the force applied over the step [N] (saturated; 0 after reset)   |

    ## Starting State
    `x₀ ~ N(x0, diag(x0_std²))`, default `x0 = [0, 0.1, 0, 0]` (the pole tilted 0.1 rad), `x0_std = 0`:
    the lecture's initial condition. Drawn from `self.np_random` (seeded by `reset(seed=...)`),
    which then draws all of the episode's noise.

    ## Episode End
    - Termination (failure, the benchmark's rule): `|θ| > theta_max` (default 0.5 rad), the cart at
      the end of the track (`|p| ≥ 2.4 m`, the slider `range`), or a non-finite / runaway state —
      checked at every physics step.
    - Truncation: after `duration` seconds, `round(duration / control_period)` steps (default
      10 s = 1000 steps): the benchmark's horizon. `gymnasium.make` wraps the env in a `TimeLimit`
      of exactly that many steps, so `env.spec.max_episode_steps` follows `duration` and
      `control_period`; the env also truncates itself there when built directly. As with
      `TimeLimit`, a step that fails on the last step is both terminated and truncated.

    ## Arguments
    `gymnasium.make("pendulum_lqg/CartPoleLQG-v0", **kwargs)`, all keywords optional:

    | Parameter              | Type                 | Default       | Description                       |
    |------------------------|----------------------|---------------|-----------------------------------|
    | `control_period`       | float (s)            | `0.01`        | T, a multiple of the XML timestep |
    | `duration`             | float (s)            | `10.0`        | episode length (truncation)       |
    | `observation_mode`     | str                  | "measurement" | or "state"; see Observation Space |
    | `noise_scale`          | float ≥ 0            | `1.0`         | multiplies both noise std devs    |
    | `process_noise`        | str                  | "state"       | F = I₄ (lecture), or "force" [1]  |
    | `process_density`      | float or list        | `4e-4` (×4)   | spectral density W (units²·s) [2] |
    | `measurement_variance` | float or list of 2   | `0.01`        | per-sample V of `[p, θ]` (m², rad²) |
    | `x0`, `x0_std`         | 4 floats each        | see above     | initial-state mean / std dev      |
    | `theta_max`            | float (rad)          | `0.5`         | failure angle                     |
    | `cost_Q`, `cost_R`     | 4 floats, float      | `1`, `1`      | weights of the cost J             |
    | `reward_scale`         | float (J/s)          | `10.0`        | see Rewards                       |
    | `model_overrides`      | mapping              | `None`        | simulated-plant changes [3]       |
    | `model_path`           | str                  | bundled XML   | another MJCF cart-pole            |
    | `normalize_action`     | bool                 | `False`       | actions in [−1, 1] (see Action Space) |
    | `plant`                | str                  | "mujoco"      | or "linear-zoh" / "linear-euler" [7] |
    | `measurement_delay`    | float (s)            | `0.0`         | age of `y`, whole periods [5]     |
    | `actuator_delay`       | float (s)            | `0.0`         | delay of the force, whole periods |
    | `dropout`              | float in [0, 1)      | `0.0`         | P(a sample is lost → `nan`) [5]   |
    | `actuator_tau`         | float (s)            | `0.0`         | first-order force lag (0: none)   |
    | `randomize`            | mapping              | `None`        | per-episode scales [6]            |
    | `render_mode`          | str or None          | `None`        | "rgb_array": `mujoco.Renderer` [4] |
    | `width`, `height`      | int (px)             | `640`, `480`  | image size (≤ offscreen buffer)   |

    [1] generalised forces on slider and hinge through `qfrc_applied`, redrawn every physics step.
    [2] 4 entries for "state" (default: the lecture's `0.04·T·I₄` at T = 0.01 s); required, with
    2 entries (N²·s, N²m²·s), for "force". [3] model mismatch: a mapping (or a `ModelOverrides`)
    of `pole_mass`, `pole_length`, `cart_mass`, their `*_scale`, `force_limit`, `timestep`.
    [4] a side view (the XML's `side` camera direction) that tracks the cart at 3 pole lengths.
    [5] the observation is `[nan, nan]` for a lost sample and for the first `measurement_delay / T`
    steps of an episode (nothing has arrived yet); the `state` observation is never delayed.
    [6] `{"pole_mass_scale": (lo, hi), "pole_length_scale": …, "cart_mass_scale": …}`, uniform
    draws from a child of the episode's generator, so `reset(seed=s)` gives the same plant as the
    benchmark's episode (see `pendulum_lqg.sim.Scenario`).
    [7] the MJCF model's linearisation stepped instead of MuJoCo: exact ZOH, or the lecture's
    forward Euler at the control period (`pendulum_lqg.sim.Scenario.plant`).

    Invalid values raise `pendulum_lqg.errors.ConfigError` naming the parameter.

    Initial-state randomisation: `x0_std` (default 0: the lecture's fixed start) draws each
    episode's `x₀ ~ N(x0, diag(x0_std²))`, e.g. `x0_std=(0.5, 0.2, 0.5, 0.5)` for a spread of
    starts; `x0` sets the mean (default `[0, 0.1, 0, 0]`).

    ## Version History
    * v0: Initial version (the lecture scenario; reward `exp(−c/(s·T))`, 0 on failure).
      pendulum-lqg 0.2.0 added `normalize_action` and `info["force"]` (defaults unchanged).
    """

    metadata: dict[str, Any] = {"render_modes": ["rgb_array"], "render_fps": 100}  # noqa: RUF012

    def __init__(self, *, normalize_action: bool = False, render_mode: str | None = None,
                 width: int = 640, height: int = 480, **config: Any) -> None:
        self.config = EnvConfig.from_keywords(config)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ConfigError(f"render_mode: expected None or 'rgb_array', got {render_mode!r}")
        self.render_mode = render_mode
        self.scenario = self.config.scenario
        self.observation_mode = self.config.observation_mode
        self.plant, self._sim = self.config.make_simulator(nthread=0)
        self.width, self.height = _image_size(self.plant, width, height)
        self._actions = _Actions(self.plant, normalize_action)
        self._frames = _Frames(self.plant, self.width, self.height)
        #: control period T [s] and physics steps per env step
        self.dt, self.frame_skip = self._sim.dt, self._sim.k
        self.max_episode_steps = self._sim.n_periods
        self._scale_dt = self.config.reward_scale * self.dt
        self.metadata = {**type(self).metadata, "render_fps": round(1.0 / self.dt)}
        self.action_space = self._actions.space
        dim = 2 if self.observation_mode == "measurement" else 4
        self.observation_space = spaces.Box(-np.inf, np.inf, shape=(dim,), dtype=np.float64)
        self._running_cost = 0.0
        self._ended = False
        self._started = False

    # ---- episode -----------------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None,
              ) -> tuple[np.ndarray, dict[str, Any]]:
        """Start an episode: draw x₀, then the first measurement, from ``self.np_random``.

        ``options`` takes no keys (an unknown key is an error).
        """
        super().reset(seed=seed)
        if options:
            raise ConfigError(f"options: unknown key {sorted(options)[0]!r}; reset takes none")
        self._sim.reset([self.np_random])
        self._running_cost = 0.0
        self._ended = False
        self._started = True
        return self._observe(), self._info(0.0, FAIL_NONE, 0.0)

    def step(self, action: np.ndarray) -> tuple[np.ndarray, SupportsFloat, bool, bool,
                                                 dict[str, Any]]:
        """One control period with the force ``action[0]`` [N] held."""
        if not self._started:
            raise PendulumLQGError("step: call reset() before the first step")
        if self._ended:
            raise PendulumLQGError("step: the episode has failed; call reset() first")
        sim = self._sim
        u = self._actions.force(action)
        cost, reason = sim.step_one(u)
        failed = reason != FAIL_NONE
        reward = step_reward(cost, failed, self._scale_dt)
        self._running_cost += cost
        if failed:
            self._ended = True
            obs = self._noise_free_observation()
        else:
            obs = self._observe()
        truncated = int(sim.period[0]) >= sim.n_periods         # TimeLimit's rule
        return obs, reward, failed, truncated, self._info(cost, reason, self._actions.applied(u))

    def _observe(self) -> np.ndarray:
        y = self._sim.measure_one()   # always: it draws this period's process noise too
        return y if self.observation_mode == "measurement" else self._sim.x[0].copy()

    def _noise_free_observation(self) -> np.ndarray:
        x = self._sim.x[0]
        return (x[:2] if self.observation_mode == "measurement" else x).copy()

    def _info(self, cost: float, reason: int, force: float) -> dict[str, Any]:
        state = self._sim.x[0].copy()
        return {"cost": cost, "running_cost": self._running_cost, "state": state,
                "y_true": state[:2], "failure_reason": FAIL_REASONS[reason],
                "time": float(self._sim.t[0]), "force": force}

    @property
    def running_cost(self) -> float:
        """J so far in the current episode."""
        return self._running_cost

    # ---- rendering ---------------------------------------------------------------------------
    def render(self) -> np.ndarray | None:
        """An RGB image (height, width, 3) uint8 of the current state (``render_mode="rgb_array"``)."""
        if self.render_mode is None:
            gym.logger.warn("render: called without a render_mode; make the env with "
                            "render_mode='rgb_array'")
            return None
        x = self._sim.x[0] if hasattr(self._sim, "x") else np.zeros(4)
        return self._frames.frame(x)

    def close(self) -> None:
        self._frames.close()
        self._sim.close()


#: the vector env's info keys, each with its mask's key (Gymnasium's ``_key``), in order
_INFO_KEYS = tuple((key, "_" + key) for key in ("cost", "running_cost", "state", "y_true",
                                                 "failure_reason", "time", "force"))
#: ``FAIL_REASONS`` indexed by code, for the vector infos.
_REASON_NAMES = np.array([FAIL_REASONS[c] for c in range(len(FAIL_REASONS))], dtype=object)


def _make_renderer(model: mujoco.MjModel, height: int, width: int) -> mujoco.Renderer:
    """``mujoco.Renderer``, or a one-line error that says which OpenGL backend to choose."""
    try:
        return mujoco.Renderer(model, height, width)
    except Exception as exc:
        import os

        backend = os.environ.get("MUJOCO_GL", "glfw (the default)")
        detail = " ".join(str(exc).split())[:160]
        raise PendulumLQGError(
            f"render: MuJoCo could not create an OpenGL context with MUJOCO_GL={backend} "
            f"({type(exc).__name__}: {detail}); on a machine without a display set MUJOCO_GL=egl "
            "(or osmesa) before mujoco is first imported (pendulum_lqg does this itself when it "
            "is imported first)") from exc


def _image_size(plant: Plant, width: int, height: int) -> tuple[int, int]:
    width, height = _positive_int("width", width), _positive_int("height", height)
    vis = plant.model.vis.global_
    if width > vis.offwidth or height > vis.offheight:
        raise ConfigError(f"width: {width}×{height} exceeds the model's offscreen buffer "
                          f"{vis.offwidth}×{vis.offheight} (<visual><global offwidth/offheight>)")
    return width, height


def make_env(**kwargs: Any) -> gym.Env[np.ndarray, np.ndarray]:
    """The entry point of ``pendulum_lqg/CartPoleLQG-v0``: a :class:`CartPoleLQGEnv` (keywords as
    its own) inside a ``TimeLimit`` of its episode length, ``round(duration / control_period)``
    steps — ``max_episode_steps`` derived from the keywords, not fixed at registration."""
    env = CartPoleLQGEnv(**kwargs)
    return TimeLimit(env, max_episode_steps=env.max_episode_steps)


class CartPoleLQGVectorEnv(VectorEnv):
    """``num_envs`` :class:`CartPoleLQGEnv` episodes stepped together on one batched sim core.

    The vector entry point of ``pendulum_lqg/CartPoleLQG-v0``
    (``gymnasium.make_vec(id, num_envs=N)``): one batched MuJoCo call (``mujoco.batch``) per step
    for the whole batch. Each sub-env owns its generator, seeded as :class:`~gymnasium.vector.SyncVectorEnv`
    seeds its sub-envs (``reset(seed=s)`` → ``s, s+1, …``; or a list of seeds; ``None`` → fresh
    entropy), so sub-env ``i`` gives exactly the episodes of a single env reset with the same seed
    — after an autoreset too (the generator continues, as a single env's ``reset()`` without a seed).

    Autoreset follows Gymnasium's conventions and ``SyncVectorEnv`` step for step
    (``metadata["autoreset_mode"]``):

    * ``NEXT_STEP`` (default, as ``SyncVectorEnv``): the step in which a sub-env ends returns its
      last observation; the next step ignores that sub-env's action and returns its reset
      observation and ``info``, with reward 0 and ``terminated = truncated = False``;
    * ``SAME_STEP``: the ended sub-env is reset within the same step; the returned observation and
      ``info`` are the new episode's, ``info["final_obs"]`` / ``info["final_info"]`` (masks
      ``_final_obs`` / ``_final_info``) the last ones;
    * ``DISABLED``: ended sub-envs wait for ``reset(options={"reset_mask": mask})``.

    ``reset(options={"reset_mask": mask})`` resets only the masked sub-envs in every mode.
    ``render_mode="rgb_array"``: ``render()`` returns one frame per sub-env (a tuple, as
    ``SyncVectorEnv``). Per-sub-env ``wrappers=`` cannot be given to ``gymnasium.make_vec`` with
    any vector entry point (Gymnasium refuses them); use ``vectorization_mode="sync"`` for those
    (same episodes, slower), or wrap this env in ``gymnasium.wrappers.vector`` wrappers.

    Parameters
    ----------
    num_envs : number of sub-envs
    autoreset_mode : an ``AutoresetMode`` or its name (default ``NEXT_STEP``)
    max_episode_steps : truncate after this many steps (``gym.make_vec(id, N,
        max_episode_steps=M)`` passes it); the env's own ``duration`` also truncates, whichever
        comes first (``TimeLimit``'s rule: a sub-env that fails on its last step is both
        terminated and truncated)
    nthread : physics threads (default: the CPU cores, at most 8); results do not depend on it
    the other keywords : as :class:`CartPoleLQGEnv`
    """

    metadata: dict[str, Any] = {"render_modes": ["rgb_array"],  # noqa: RUF012
                                "autoreset_mode": AutoresetMode.NEXT_STEP}

    def __init__(self, num_envs: int, *, autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
                 max_episode_steps: int | None = None, nthread: int | None = None,
                 normalize_action: bool = False, render_mode: str | None = None,
                 width: int = 640, height: int = 480, **config: Any) -> None:
        self.num_envs = _positive_int("num_envs", num_envs)
        self.autoreset_mode = _autoreset_mode(autoreset_mode)
        if render_mode is not None and render_mode != "rgb_array":
            raise ConfigError(f"render_mode: expected None or 'rgb_array', got {render_mode!r}")
        self.render_mode = render_mode
        self.config = EnvConfig.from_keywords(config)
        self.scenario = self.config.scenario
        self.observation_mode = self.config.observation_mode
        self.plant, self._sim = self.config.make_simulator(nthread=nthread)
        width, height = _image_size(self.plant, width, height)
        self._frames = _Frames(self.plant, width, height)
        self.dt, self.frame_skip = self._sim.dt, self._sim.k
        #: physics threads of the batched core
        self.nthread = self._sim.nthread
        limit = self._sim.n_periods
        if max_episode_steps is not None:
            limit = min(limit, _positive_int("max_episode_steps", max_episode_steps))
        self.max_episode_steps = limit
        self._scale_dt = self.config.reward_scale * self.dt
        self.metadata = {**type(self).metadata, "render_fps": round(1.0 / self.dt),
                         "autoreset_mode": self.autoreset_mode}
        self._actions = _Actions(self.plant, normalize_action)
        self.single_action_space = self._actions.space
        dim = 2 if self.observation_mode == "measurement" else 4
        self.single_observation_space = spaces.Box(-np.inf, np.inf, shape=(dim,),
                                                   dtype=np.float64)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self._gens: list[np.random.Generator] = []
        self._running_cost = np.zeros(self.num_envs)
        self._all = np.arange(self.num_envs)
        self._waiting = np.zeros(self.num_envs, dtype=bool)   # ended, not yet reset
        self._obs = np.zeros((self.num_envs, dim))
        self._started = False

    def reset(self, *, seed: int | Sequence[int] | None = None,
              options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset every sub-env (or those of ``options["reset_mask"]``), as ``SyncVectorEnv``.

        ``seed``: an int ``s`` (sub-env i gets ``s + i``), a list of ``num_envs`` seeds (``None``
        entries allowed), or ``None``. A sub-env without a seed continues its generator (fresh
        entropy the first time), as a single env's ``reset()`` does.
        """
        n = self.num_envs
        options = dict(options or {})
        mask = options.pop("reset_mask", None)
        if options:
            raise ConfigError(f"options: unknown key {sorted(options)[0]!r}; reset takes only "
                              "'reset_mask'")
        seeds: list[int | None]
        if seed is None or isinstance(seed, int | np.integer):
            super().reset(seed=None if seed is None else int(seed))
            seeds = [None] * n if seed is None else [int(seed) + i for i in range(n)]
        else:
            seeds = list(seed)
            if len(seeds) != n or not all(s is None or (isinstance(s, int | np.integer)
                                                        and not isinstance(s, bool))
                                          for s in seeds):
                raise ConfigError(f"seed: expected {n} integer seeds (or None), got {seed!r}")
        if mask is not None:
            if not self._started:
                raise ConfigError("options: reset_mask needs a first reset() of every sub-env")
            mask = np.asarray(mask)
            if mask.shape != (n,) or mask.dtype != np.bool_ or not mask.any():
                raise ConfigError(f"options: reset_mask must be a bool array of shape ({n},) "
                                  f"with at least one True, got {mask!r}")
            rows = np.nonzero(mask)[0]
        else:
            rows = self._all
        gens: list[np.random.Generator | None] = list(self._gens) if self._gens else [None] * n
        chosen = set(rows.tolist())
        for i, s in enumerate(seeds):
            if i in chosen and (s is not None or gens[i] is None):
                gens[i] = seeding.np_random(None if s is None else int(s))[0]
        # every entry is a Generator now: a first reset covers every sub-env
        self._gens = [g for g in gens if g is not None]
        assert len(self._gens) == n
        if rows.size == n:
            self._sim.reset(self._gens, ids=self._all)
            self._running_cost[:] = 0.0
            self._obs = self._observe(self._all)
        else:
            self._restart(rows)
        self._waiting[rows] = False
        self._started = True
        zeros = np.zeros(rows.size)
        return self._obs.copy(), self._infos(rows, zeros, np.full(rows.size, FAIL_NONE), zeros)

    def _observe(self, rows: np.ndarray) -> np.ndarray:
        """Measure ``rows`` (draws their noise for the coming period) → their observations."""
        sim = self._sim
        y = sim.measure() if rows.size == self.num_envs else sim.measure(rows)
        return y if self.observation_mode == "measurement" else sim.x[rows].copy()

    def _restart(self, rows: np.ndarray) -> None:
        """New episodes in ``rows`` (their generators continue), observed."""
        self._sim.reset([self._gens[r] for r in rows], ids=rows, rows=rows)
        self._running_cost[rows] = 0.0
        self._obs[rows] = self._observe(rows)

    def step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                                 dict[str, Any]]:
        if not self._started:
            raise PendulumLQGError("step: call reset() before the first step")
        sim, n = self._sim, self.num_envs
        u = self._actions.forces(actions, n)
        if np.count_nonzero(self._waiting) == 0:   # the common case: every sub-env is running
            res = sim.step(u)
            self._running_cost += res.cost
            terminated = res.failed.copy()
            truncated = sim.period >= self.max_episode_steps          # TimeLimit's rule
            if np.count_nonzero(terminated) == 0 and np.count_nonzero(truncated) == 0:
                reward = step_reward(res.cost, terminated, self._scale_dt)   # ... still running
                self._obs = self._observe(self._all)
                infos = self._infos(self._all, res.cost, res.reason, res.requested)
                return self._obs.copy(), reward, terminated, truncated, infos
            return self._step_end(res, np.zeros(0, dtype=np.int64), truncated)
        waiting = np.nonzero(self._waiting)[0]
        if self.autoreset_mode == AutoresetMode.DISABLED:
            raise PendulumLQGError(f"step: sub-env(s) {waiting.tolist()} ended; reset them with "
                                   "reset(options={'reset_mask': mask}) first")
        sim.park(waiting)                      # NEXT_STEP: their actions are ignored
        u[waiting] = 0.0
        res = sim.step(u)
        self._running_cost += res.cost
        return self._step_end(res, waiting, sim.period >= self.max_episode_steps)

    def _step_end(self, res: StepResult, waiting: np.ndarray, truncated: np.ndarray,
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """The rest of :meth:`step` when some sub-env ends, or waited for its reset."""
        sim, n = self._sim, self.num_envs
        terminated = res.failed.copy()
        reward = step_reward(res.cost, terminated, self._scale_dt)
        force = res.requested.copy()
        cost, reason = res.cost.copy(), res.reason.copy()
        if waiting.size:                       # NEXT_STEP: this step is their reset
            terminated[waiting] = truncated[waiting] = False
            reward[waiting] = force[waiting] = cost[waiting] = 0.0
            reason[waiting] = FAIL_NONE
        ended = np.nonzero(terminated | truncated)[0]
        failed = np.nonzero(terminated)[0]
        measured = np.nonzero(~terminated & ~self._waiting)[0]
        if measured.size:
            self._obs[measured] = self._observe(measured)
        x = sim.x
        self._obs[failed] = x[failed, :2] if self.observation_mode == "measurement" else x[failed]
        if waiting.size:
            self._restart(waiting)
            self._waiting[waiting] = False
        infos: dict[str, Any]
        if self.autoreset_mode == AutoresetMode.SAME_STEP and ended.size:
            final_info = self._infos(ended, cost[ended], reason[ended], force[ended])
            final_obs = np.full(n, None, dtype=object)
            for r in ended:
                final_obs[r] = self._obs[r].copy()
            self._restart(ended)
            cost[ended], reason[ended], force[ended] = 0.0, FAIL_NONE, 0.0
            infos = self._infos(self._all, cost, reason, force)
            mask = np.zeros(n, dtype=bool)
            mask[ended] = True
            infos.update({"final_obs": final_obs, "_final_obs": mask, "final_info": final_info,
                          "_final_info": mask.copy()})
        else:
            infos = self._infos(self._all, cost, reason, force)
            self._waiting[ended] = True
        return self._obs.copy(), reward, terminated, truncated, infos

    def _infos(self, rows: np.ndarray, cost: np.ndarray, reason: np.ndarray,
               force: np.ndarray) -> dict[str, Any]:
        """Vector infos (arrays with ``_key`` masks) of ``rows``, as ``SyncVectorEnv`` builds."""
        n, sim = self.num_envs, self._sim
        values: dict[str, np.ndarray]
        if rows.size == n:          # the common step: whole arrays, each the info's own copy
            masks = np.ones((len(_INFO_KEYS), n), dtype=bool)
            state = sim.x.copy()
            values = {"cost": np.array(cost, dtype=float),
                      "running_cost": self._running_cost.copy(), "state": state,
                      "y_true": state[:, :2].copy(), "failure_reason": _REASON_NAMES[reason],
                      "time": sim.t.copy(), "force": np.array(force, dtype=float)}
        else:
            def spread(values: np.ndarray, fill: object = 0.0, dtype: Any = float) -> np.ndarray:
                out = np.full((n, *np.shape(values)[1:]), fill, dtype=dtype)
                out[rows] = values
                return out

            masks = np.zeros((len(_INFO_KEYS), n), dtype=bool)
            masks[:, rows] = True
            state = spread(sim.x[rows])
            values = {
                "cost": spread(cost), "running_cost": spread(self._running_cost[rows]),
                "state": state, "y_true": state[:, :2].copy(),
                "failure_reason": spread(_REASON_NAMES[reason], None, object),
                "time": spread(sim.t[rows]), "force": spread(force)}
        out: dict[str, Any] = {}
        for (key, mask_key), mask in zip(_INFO_KEYS, masks, strict=True):
            out[key] = values[key]
            out[mask_key] = mask        # one row of one block each: the masks share no memory
        return out

    def render(self) -> tuple[np.ndarray, ...] | None:
        """One RGB frame (height, width, 3) per sub-env (``render_mode="rgb_array"``)."""
        if self.render_mode is None:
            gym.logger.warn("render: called without a render_mode; make the env with "
                            "render_mode='rgb_array'")
            return None
        x = self._sim.x if self._started else np.zeros((self.num_envs, 4))
        return tuple(self._frames.frame(x[i]) for i in range(self.num_envs))

    def close_extras(self, **kwargs: Any) -> None:
        self._frames.close()
        self._sim.close()


def _autoreset_mode(mode: object) -> AutoresetMode:
    if isinstance(mode, AutoresetMode):
        return mode
    names = {m.name.lower(): m for m in AutoresetMode} | {m.value.lower(): m for m in AutoresetMode}
    if isinstance(mode, str) and mode.lower() in names:
        return names[mode.lower()]
    raise ConfigError(f"autoreset_mode: expected one of "
                      f"{', '.join(m.name for m in AutoresetMode)}, got {mode!r}")


__all__ = ["CAMERA_DISTANCE_POLE_LENGTHS", "DEFAULT_REWARD_SCALE", "REWARD_FLOOR", "CartPoleLQGEnv",
           "CartPoleLQGVectorEnv", "EnvConfig", "make_env", "step_reward"]
