"""stable-baselines3 models as Gymnasium agents: ``--agent sb3:PATH.zip`` (the ``rl`` extra).

A model is a zip saved by stable-baselines3 with a JSON file beside it, ``PATH.json``, that says how
it was trained (the training script writes it)::

    {"algo": "PPO",                  # PPO, SAC, TD3, A2C (stable-baselines3), RecurrentPPO (sb3-contrib)
     "method": "ppo-history", "seed": 3,   # the run: a method and its training seed (optional)
     "frame_stack": 8,               # frames of the history (1: none)
     "past_actions": true,           # each frame is [y, previous action] (default false)
     "estimator": "kalman",          # frames of the reference Kalman filter's x̂ instead of y (optional)
     "obs_norm": {"mean": [...], "var": [...], "clip": 10.0, "epsilon": 1e-8},  # of the stack, or null
     "normalize_action": false,      # trained on actions in [−1, 1]
     "env": {...},                   # the env keywords it was trained on
     "budget": {...}}                # steps, seeds, wall time

:class:`SB3Agent` rebuilds the observation design of the record for one env
(:mod:`pendulum_lqg.scoreboard.obs_design`: the history of frames, newest last, zeros before the
first, each frame the observation and, with ``past_actions``, the previous action; then the
normalisation of the stack with the frozen statistics), the same code the training wrapper runs,
and asks the model's ``predict`` for a deterministic action, carrying a recurrent policy's state
across the episode. A sample that is lost or not yet delivered (``nan``, under ``dropout`` or a
measurement delay) is replaced by the last one received (zeros before the first): the networks
never saw a nan.
Nothing here imports torch until a model is loaded.
"""

from __future__ import annotations

import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

from pendulum_lqg.boundary.schemas import ALGORITHMS, training_record
from pendulum_lqg.errors import ConfigError, NotApplicable, PluginError
from pendulum_lqg.scoreboard.obs_design import ObservationDesign, ObservationHistory, normalise


class SB3Agent:
    """A model with stable-baselines3's ``predict(observation, state, episode_start,
    deterministic)`` as an agent of one env, seeing the observation design it was trained on
    (:mod:`pendulum_lqg.scoreboard.obs_design`; ``low``/``high``: the env's action bounds, which
    clip the previous action of a ``past_actions`` design)."""

    def __init__(self, model: Any, *, frame_stack: int = 1,
                 obs_norm: dict[str, Any] | None = None, past_actions: bool = False,
                 estimator: str | None = None, low: Any = -np.inf, high: Any = np.inf,
                 config: Any = None, normalize_action: bool | None = None) -> None:
        self.model, self.obs_norm = model, obs_norm
        self.design = ObservationDesign(frame_stack, past_actions, estimator)
        self.frame_stack = frame_stack
        self._bounds = (low, high)
        self._env = {"config": config, "normalize_action": normalize_action}
        self._history: ObservationHistory | None = None
        self._action: np.ndarray | None = None
        self._state: Any = None

    def reset(self) -> None:
        self._history, self._action, self._state = None, None, None

    def act(self, observation: np.ndarray) -> np.ndarray:
        obs = np.asarray(observation, dtype=float).reshape(1, -1)
        start = self._history is None
        if self._history is None:
            self._history = ObservationHistory(self.design, 1, obs.shape[1], *self._bounds,
                                               **self._env)
            stack = self._history.reset(obs)
        else:
            assert self._action is not None
            stack = self._history.step(obs, self._action)
        action, self._state = self.model.predict(
            normalise(stack, self.obs_norm), state=self._state,
            episode_start=np.array([start]), deterministic=True)
        self._action = np.asarray(action, dtype=float).reshape(1, -1)
        return self._action.reshape(-1)[:1].copy()


def read_metadata(path: Path) -> dict[str, Any]:
    """The training record beside a model zip (``PATH.json``), checked by
    :func:`~pendulum_lqg.boundary.schemas.training_record` (one line naming the file and key)."""
    meta_path = path.with_suffix(".json")
    if not meta_path.exists():
        raise ConfigError(f"agent: sb3:{path} needs its training record {meta_path} (no such file)")
    return training_record(meta_path, where_text="agent")


@contextmanager
def one_torch_thread() -> Iterator[None]:
    """torch on one thread while the block asks a model: a batch of at most a few hundred rows
    through a small network gains nothing from more threads, which would contend with the physics
    for the same cores, and a predict's floats then do not depend on the machine's core count (a
    re-score reproduces its score file). The previous thread count is restored after. Without
    torch loaded (a stand-in model) there is nothing to set."""
    torch = sys.modules.get("torch")
    if torch is None:
        yield
        return
    before = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        yield
    finally:
        torch.set_num_threads(before)


def load_model(path: Path, algo: str) -> Any:
    """Load the model with its algorithm's class (needs the ``rl`` extra)."""
    import importlib

    try:
        module = importlib.import_module(ALGORITHMS[algo])
    except ImportError as exc:
        raise ConfigError(f"agent: sb3:{path} needs {ALGORITHMS[algo].replace('_', '-')} "
                          "(install the rl extra: pip install 'pendulum_lqg-…whl[rl]')") from exc
    try:
        return getattr(module, algo).load(str(path), device="cpu")
    except Exception as exc:
        raise PluginError(f"agent: sb3:{path}: {algo}.load raised {type(exc).__name__}: "
                          f"{' '.join(str(exc).split())[:200]}") from exc


class SB3Factory:
    """The agent factory of ``sb3:PATH.zip``: ``factory(env)`` is an :class:`SB3Agent` of the
    model. ``normalize_action`` tells the score which action space the model was trained on;
    ``run`` (``method``, ``seed``, ``model_sha256``) and ``versions`` (torch, stable-baselines3,
    sb3-contrib) go into the score file."""

    def __init__(self, path_text: str, meta: dict[str, Any], model: Any) -> None:
        self.path_text, self.meta, self.model = path_text, meta, model
        self.normalize_action: bool = meta["normalize_action"]
        self.env: dict[str, Any] = dict(meta["env"])
        self.run: dict[str, Any] = {"model_sha256": file_sha256(Path(path_text))}
        self.run.update({k: meta[k] for k in ("method", "seed") if meta.get(k) is not None})
        self.versions = rl_versions()

    def __call__(self, env: gym.Env) -> SB3Agent:
        trained_on = self.env.get("observation_mode", "measurement")
        mode = getattr(env.unwrapped, "observation_mode", None)
        if mode != trained_on:
            raise NotApplicable(f"agent sb3:{self.path_text} was trained on observation_mode = "
                                f"{trained_on!r}; this suite's env has {mode!r}")
        space, base = env.action_space, env.unwrapped
        return SB3Agent(self.model, obs_norm=self.meta["obs_norm"],
                        **ObservationDesign.of(self.meta).record(),
                        low=getattr(space, "low", -np.inf), high=getattr(space, "high", np.inf),
                        config=getattr(base, "config", None),
                        normalize_action=getattr(base, "normalize_action", None))


def file_sha256(path: Path) -> str:
    """The sha256 of the file ``path`` (hex), read in 1 MiB chunks."""
    import hashlib

    digest = hashlib.sha256()
    with path.open("rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()


def rl_versions() -> dict[str, str]:
    """The installed versions of the RL libraries a model's score depends on (``"absent"``: not
    installed), read from the package metadata without importing them."""
    from importlib import metadata

    out = {}
    for lib in ("torch", "stable-baselines3", "sb3-contrib"):
        try:
            out[lib] = metadata.version(lib)
        except metadata.PackageNotFoundError:
            out[lib] = "absent"
    return out


def sb3_agent(path_text: str) -> SB3Factory:
    """The agent factory of ``sb3:PATH.zip`` (see :class:`SB3Factory`)."""
    from pendulum_lqg.util.resources import TRAINED_MODELS_NOTE

    path = Path(path_text)
    if not path.is_file():
        raise ConfigError(f"agent: sb3:{path_text}: no such model file ({TRAINED_MODELS_NOTE})")
    meta = read_metadata(path)
    return SB3Factory(path_text, meta, load_model(path, meta["algo"]))
