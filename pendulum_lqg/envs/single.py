"""The single Gymnasium environment: one cart-pole episode over a one-row simulator."""

from __future__ import annotations

from typing import Any, SupportsFloat, Unpack

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.wrappers import TimeLimit

from pendulum_lqg.core.rules import FAIL_NONE, FAIL_REASONS
from pendulum_lqg.envs.config import Actions, EnvConfig, step_reward, true_outputs
from pendulum_lqg.envs.keywords import EnvKeywords
from pendulum_lqg.envs.render import Frames, check_renderable, image_size
from pendulum_lqg.errors import ConfigError, PendulumLQGError


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
    `gymnasium.make("pendulum_lqg/CartPoleLQG-v0", **kwargs)`, all keywords optional. The complete
    list, generated from the declarations in `pendulum_lqg.problem`, is the typed `EnvKeywords`
    (`pendulum_lqg.envs.keywords`) and the table of docs/gymnasium.md; this one adds notes:

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
    | `theta_max`            | float (rad)          | `0.5`         | failure angle (`inf`: none)       |
    | `track_limit`          | float (m) or None    | `None`        | track end (None: the MJCF's) [8]  |
    | `force_limit`          | float (N) or None    | `None`        | saturation (None: `ctrlrange`) [8] |
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
    benchmark's episode (see `pendulum_lqg.core.scenario.Scenario`).
    [7] the MJCF model's linearisation stepped instead of MuJoCo: exact ZOH, or the lecture's
    forward Euler at the control period (`pendulum_lqg.core.scenario.Scenario.plant`).
    [8] `inf` switches the limit off (the lecture's unbounded linear loop); on MuJoCo at most the
    model's slider `range` and `ctrlrange` (`pendulum_lqg.core.rules.limits`).

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
                 width: int = 640, height: int = 480, **config: Unpack[EnvKeywords]) -> None:
        self.config = EnvConfig.build(**config)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ConfigError(f"render_mode: expected None or 'rgb_array', got {render_mode!r}")
        self.render_mode = render_mode
        self.scenario = self.config.scenario
        self.observation_mode = self.config.observation_mode
        self.plant, self._sim = self.config.make_simulator(nthread=0)
        check_renderable(self.plant, render_mode)
        self.width, self.height = image_size(self.plant, width, height)
        self._actions = Actions(self._sim.u_max, normalize_action)
        self._frames = Frames(self.plant, self.width, self.height)
        #: control period T [s] and physics steps per env step
        self.dt, self.frame_skip = self._sim.dt, self._sim.k
        self.max_episode_steps = self._sim.n_periods
        self._scale_dt = self.config.reward_scale * self.dt
        self.metadata = {**type(self).metadata, "render_fps": round(1.0 / self.dt)}
        self.action_space = self._actions.space
        dim = self._sim.layout.p if self.observation_mode == "measurement" else self._sim.nx
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
        cost, reason, force = sim.step_one(u)
        failed = reason != FAIL_NONE
        reward = step_reward(cost, failed, self._scale_dt)
        self._running_cost += cost
        if failed:
            self._ended = True
            obs = self._noise_free_observation()
        else:
            obs = self._observe()
        truncated = sim.period.item(0) >= sim.n_periods         # TimeLimit's rule
        return obs, reward, failed, truncated, self._info(cost, reason, force)

    def _observe(self) -> np.ndarray:
        y = self._sim.measure_one()   # always: it draws this period's process noise too
        return y if self.observation_mode == "measurement" else self._sim.x[0].copy()

    def _noise_free_observation(self) -> np.ndarray:
        x = self._sim.x[0]
        return true_outputs(self._sim, x) if self.observation_mode == "measurement" \
            else x.copy()

    def _info(self, cost: float, reason: int, force: float) -> dict[str, Any]:
        state = self._sim.x[0].copy()
        return {"cost": cost, "running_cost": self._running_cost, "state": state,
                "y_true": true_outputs(self._sim, state), "failure_reason": FAIL_REASONS[reason],
                "time": self._sim.t.item(0), "force": force}

    @property
    def action_map(self) -> Actions:
        """The map between actions and newtons (the identity unless ``normalize_action``)."""
        return self._actions

    @property
    def normalize_action(self) -> bool:
        """Actions are in ``[−1, 1]`` (mapped onto the force range), not newtons."""
        return self._actions.normalize

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
        x = self._sim.x[0] if hasattr(self._sim, "x") else np.zeros(self._sim.nx)
        return self._frames.frame(x)

    def close(self) -> None:
        self._frames.close()
        self._sim.close()


def make_env(**kwargs: Any) -> gym.Env[np.ndarray, np.ndarray]:
    """The entry point of ``pendulum_lqg/CartPoleLQG-v0``: a :class:`CartPoleLQGEnv` (keywords as
    its own) inside a ``TimeLimit`` of its episode length, ``round(duration / control_period)``
    steps — ``max_episode_steps`` derived from the keywords, not fixed at registration."""
    env = CartPoleLQGEnv(**kwargs)
    return TimeLimit(env, max_episode_steps=env.max_episode_steps)
