"""stable-baselines3's ``VecEnv`` over the native vector env: training on one batched simulator.

:class:`~pendulum_lqg.envs.vector.CartPoleLQGVectorEnv` steps ``num_envs`` episodes in one batched
MuJoCo call; stable-baselines3 (SB3) expects its own ``VecEnv`` contract instead of Gymnasium's
vector API. :func:`native_vec_env` gives that contract over the native env:

* **autoreset as SB3's**: the native env runs in ``SAME_STEP`` mode, so the step in which a
  sub-env ends returns the *new* episode's observation, ``done = terminated or truncated``, the
  ended episode's last observation in ``infos[i]["terminal_observation"]`` and
  ``infos[i]["TimeLimit.truncated"] = truncated and not terminated`` (as SB3's ``DummyVecEnv``);
  ``infos[i]`` is the ended episode's last info, the new episode's reset info goes to
  ``reset_infos[i]``;
* **seeding**: ``seed(s)`` (SB3: sub-env ``i`` gets ``s + i`` at the next ``reset()``) is passed to
  the native env's ``reset(seed=[…])``, which seeds sub-env ``i`` exactly as a single env reset with
  ``s + i``; seeds are used once, as SB3's;
* ``get_attr``, ``set_attr``, ``env_method``, ``env_is_wrapped``: the sub-envs are rows of one
  batched env, so an attribute is the vector env's (the same for every index), ``set_attr`` and
  ``env_method`` act on the whole vector env and refuse a subset of indices (one line), and no row
  is wrapped by a Gymnasium wrapper.

SB3 is imported when the env is made (the ``rl`` extra), never when this module is imported; a
``base`` class standing in for SB3's ``VecEnv`` may be given (the tests run the adapter's logic
without torch that way).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

from pendulum_lqg.errors import ConfigError

__all__ = ["NativeVecEnvLogic", "native_vec_env", "row_infos"]


def row_infos(infos: dict[str, Any], n: int) -> list[dict[str, Any]]:
    """Gymnasium vector infos (arrays with ``_key`` masks) as SB3's list of ``n`` per-env dicts;
    a key appears in row ``i``'s dict where its mask is true."""
    out: list[dict[str, Any]] = [{} for _ in range(n)]
    for key, values in infos.items():
        if key.startswith("_") or key in ("final_obs", "final_info"):
            continue
        mask = infos.get("_" + key, np.ones(n, dtype=bool))
        for i in np.nonzero(mask)[0]:
            value = values[i]
            out[i][key] = value.copy() if isinstance(value, np.ndarray) else value
    return out


class NativeVecEnvLogic:
    """SB3's ``VecEnv`` methods over :class:`~pendulum_lqg.envs.vector.CartPoleLQGVectorEnv`
    (module docstring); mixed with SB3's ``VecEnv`` (or a stand-in) by :func:`native_vec_env`.

    Parameters
    ----------
    num_envs : sub-envs (rows of the batched simulator)
    env_kwargs : the keywords of ``CartPoleLQGVectorEnv`` (the suite's ``[env]``,
        ``normalize_action``, ``nthread``…) except ``autoreset_mode``, which is ``SAME_STEP``
    """

    # the attributes SB3's VecEnv sets in its __init__ (declared for the type checker)
    num_envs: int
    reset_infos: list[dict[str, Any]]
    _seeds: list[int | None]
    _options: list[dict[str, Any]]

    def __init__(self, num_envs: int, **env_kwargs: Any) -> None:
        from gymnasium.vector import AutoresetMode

        from pendulum_lqg.envs.vector import CartPoleLQGVectorEnv

        if "autoreset_mode" in env_kwargs:
            raise ConfigError("autoreset_mode: SB3's VecEnv resets in the same step; it is not a "
                              "keyword of the SB3 adapter")
        self.venv = CartPoleLQGVectorEnv(num_envs, autoreset_mode=AutoresetMode.SAME_STEP,
                                         **env_kwargs)
        self._actions: np.ndarray | None = None
        super().__init__(self.venv.num_envs, self.venv.single_observation_space,  # type: ignore[call-arg]
                         self.venv.single_action_space)

    # -- the VecEnv contract ---------------------------------------------------------------------
    def reset(self) -> np.ndarray:
        """Reset every sub-env with the seeds of :meth:`seed` (used once), as ``DummyVecEnv``."""
        if any(self._options):
            raise ConfigError(f"options: the native vector env takes no reset options, got "
                              f"{self._options!r}")
        # the native reset takes a list with None entries (those sub-envs continue) as SB3 may hold
        seeds: Any = None if all(s is None for s in self._seeds) else list(self._seeds)
        obs, infos = self.venv.reset(seed=seeds)
        self.reset_infos = row_infos(infos, self.num_envs)
        self._seeds = [None] * self.num_envs
        self._options = [{} for _ in range(self.num_envs)]
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions)

    def step_wait(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        if self._actions is None:
            raise ConfigError("step_wait: call step_async(actions) first")
        obs, reward, terminated, truncated, infos = self.venv.step(self._actions)
        self._actions = None
        n = self.num_envs
        dones = terminated | truncated
        out = row_infos(infos, n)
        if "final_obs" in infos:
            finals = row_infos(infos["final_info"], n)
            for row in np.nonzero(infos["_final_obs"])[0]:
                self.reset_infos[row] = out[row]          # the new episode's first info
                out[row] = finals[row]                    # the ended episode's last info
                out[row]["terminal_observation"] = np.asarray(infos["final_obs"][row]).copy()
        for i in range(n):
            out[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
        return obs, np.asarray(reward, dtype=np.float32), dones, out

    def close(self) -> None:
        self.venv.close()

    def get_images(self) -> Sequence[np.ndarray | None]:
        frames = self.venv.render()
        return [None] * self.num_envs if frames is None else list(frames)

    # -- attributes and methods: one batched env, the same for every row --------------------------
    def _rows(self, indices: int | Iterable[int] | None) -> list[int]:
        rows = (list(range(self.num_envs)) if indices is None
                else [indices] if isinstance(indices, int) else list(indices))
        bad = [i for i in rows if not 0 <= int(i) < self.num_envs]
        if bad:
            raise ConfigError(f"indices: expected sub-envs 0 … {self.num_envs - 1}, got {bad[0]}")
        return rows

    def _whole(self, what: str, indices: int | Iterable[int] | None) -> list[int]:
        rows = self._rows(indices)
        if sorted(set(rows)) != list(range(self.num_envs)):
            raise ConfigError(f"indices: {what} acts on the whole batched env (its sub-envs are "
                              f"rows of one simulator); expected all {self.num_envs}, got {rows}")
        return rows

    def get_attr(self, attr_name: str, indices: int | Iterable[int] | None = None) -> list[Any]:
        value = getattr(self.venv, attr_name)
        return [value for _ in self._rows(indices)]

    def set_attr(self, attr_name: str, value: Any,
                 indices: int | Iterable[int] | None = None) -> None:
        self._whole(f"set_attr({attr_name!r})", indices)
        setattr(self.venv, attr_name, value)

    def env_method(self, method_name: str, *method_args: Any,
                   indices: int | Iterable[int] | None = None, **method_kwargs: Any) -> list[Any]:
        rows = self._whole(f"env_method({method_name!r})", indices)
        result = getattr(self.venv, method_name)(*method_args, **method_kwargs)
        return [result for _ in rows]

    def env_is_wrapped(self, wrapper_class: type, indices: int | Iterable[int] | None = None,
                       ) -> list[bool]:
        return [False for _ in self._rows(indices)]



def sb3_vec_env_class(name: str, who: str) -> type:
    """stable-baselines3's ``stable_baselines3.common.vec_env.NAME`` (``VecEnv``,
    ``VecEnvWrapper``), imported when first needed; without the ``rl`` extra one line naming
    ``who`` needs it."""
    try:
        from stable_baselines3.common import vec_env
    except ImportError as exc:
        raise ConfigError(f"{who} needs stable-baselines3 (install the rl extra: "
                          "pip install 'pendulum_lqg-…whl[rl]')") from exc
    cls: type = getattr(vec_env, name)
    return cls


def native_vec_env(num_envs: int, *, base: type | None = None, seed: int | None = None,
                   **env_kwargs: Any) -> Any:
    """An SB3 ``VecEnv`` over the native vector env (see the module docstring); ``seed`` is
    passed to its ``seed()`` (used at the first ``reset()``). ``base``: the ``VecEnv`` class to
    mix in (default: stable-baselines3's, which needs the ``rl`` extra)."""
    base = sb3_vec_env_class("VecEnv", "native_vec_env") if base is None else base
    cls = type("NativeSB3VecEnv", (NativeVecEnvLogic, base), {"__module__": __name__})
    env = cls(num_envs, **env_kwargs)
    if seed is not None:
        env.seed(seed)
    return env
