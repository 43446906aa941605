"""The native vector environment: ``num_envs`` episodes stepped together on one batched simulator."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Unpack

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from pendulum_lqg.core.loop import StepResult
from pendulum_lqg.core.rules import FAIL_NONE, FAIL_REASONS
from pendulum_lqg.envs.config import Actions, EnvConfig, positive_int, step_reward, true_outputs
from pendulum_lqg.envs.keywords import EnvKeywords
from pendulum_lqg.envs.render import Frames, check_renderable, image_size
from pendulum_lqg.errors import ConfigError, PendulumLQGError
from pendulum_lqg.util.limits import MAX_NUM_ENVS, check_at_most

#: the vector env's info keys, each with its mask's key (Gymnasium's ``_key``), in order
_INFO_KEYS = tuple((key, "_" + key) for key in ("cost", "running_cost", "state", "y_true",
                                                 "failure_reason", "time", "force"))
#: ``FAIL_REASONS`` indexed by code, for the vector infos.
_REASON_NAMES = np.array([FAIL_REASONS[c] for c in range(len(FAIL_REASONS))], dtype=object)


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
                 width: int = 640, height: int = 480, **config: Unpack[EnvKeywords]) -> None:
        self.num_envs = check_at_most("num_envs", positive_int("num_envs", num_envs),
                                      MAX_NUM_ENVS, "each sub-env is a row of every array of "
                                      "the batched simulation core")
        self.autoreset_mode = _autoreset_mode(autoreset_mode)
        if render_mode is not None and render_mode != "rgb_array":
            raise ConfigError(f"render_mode: expected None or 'rgb_array', got {render_mode!r}")
        self.render_mode = render_mode
        self.config = EnvConfig.build(**config)
        self.scenario = self.config.scenario
        self.observation_mode = self.config.observation_mode
        self.plant, self._sim = self.config.make_simulator(nthread=nthread)
        check_renderable(self.plant, render_mode)
        width, height = image_size(self.plant, width, height)
        self._frames = Frames(self.plant, width, height)
        self.dt, self.frame_skip = self._sim.dt, self._sim.k
        #: physics threads of the batched core
        self.nthread = self._sim.nthread
        limit = self._sim.n_periods
        if max_episode_steps is not None:
            limit = min(limit, positive_int("max_episode_steps", max_episode_steps))
        self.max_episode_steps = limit
        self._scale_dt = self.config.reward_scale * self.dt
        self.metadata = {**type(self).metadata, "render_fps": round(1.0 / self.dt),
                         "autoreset_mode": self.autoreset_mode}
        self._actions = Actions(self._sim.u_max, normalize_action)
        self.single_action_space = self._actions.space
        dim = self._sim.layout.p if self.observation_mode == "measurement" else self._sim.nx
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

    @property
    def action_map(self) -> Actions:
        """The map between actions and newtons (the identity unless ``normalize_action``)."""
        return self._actions

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
        self._obs[failed] = (true_outputs(self._sim, x[failed])
                             if self.observation_mode == "measurement" else x[failed])
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
                      "y_true": true_outputs(self._sim, state), "failure_reason": _REASON_NAMES[reason],
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
                "state": state, "y_true": true_outputs(self._sim, state),
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
        x = self._sim.x if self._started else np.zeros((self.num_envs, self._sim.nx))
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
