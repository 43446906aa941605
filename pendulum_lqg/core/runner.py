"""Running episodes: one batch through the loop, or shards of it on threads; trajectories on request.

:func:`run_episodes` is what the CLI, the sweeps, the recordings and the studies call. Episode ``e``
of a run seeded ``s`` draws everything from ``default_rng(episode_seed(s, e))``
(:mod:`~pendulum_lqg.core.seeding`), so its result does not depend on which other episodes share
its batch, on the backend, on the shard split or on the thread count — bit for bit on one machine.
"""

from __future__ import annotations

import copy
import threading
import time
from collections.abc import Iterable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any, Literal, cast

import numpy as np

from pendulum_lqg.core.loop import Simulator
from pendulum_lqg.core.physics import thread_count
from pendulum_lqg.core.protocol import (
    PolicyProtocol,
    SelectablePolicyProtocol,
    current_estimate,
    optional_members,
)
from pendulum_lqg.core.scenario import Scenario
from pendulum_lqg.core.seeding import episode_generators, episode_seeds
from pendulum_lqg.core.trajectory import Trajectory, TrajectoryLog, estimator_snapshot
from pendulum_lqg.errors import PendulumLQGError
from pendulum_lqg.model.interface import SimulatedPlant
from pendulum_lqg.util.limits import check_episodes


@dataclass
class BatchResult:
    """Per-episode metric rows (and trajectories on request) of one batch run.

    ``shard_seconds``: when each shard (:func:`shard_count`) started and ended, in seconds of
    ``time.perf_counter`` since the run started, one ``(start, end)`` per shard: a diagnostic of
    how evenly the shards shared the threads (``pendulum-lqg perf`` reports it).
    """

    rows: list[dict[str, Any]]
    trajectories: list[Trajectory] | None = None
    shard_seconds: list[tuple[float, float]] = field(default_factory=list)


class _WholeBatch:
    """A policy without ``select``: it keeps its whole original batch; rows of ended episodes get
    zero measurements and their forces are dropped."""

    def __init__(self, policy: PolicyProtocol, n: int) -> None:
        self.policy, self.n0, self.alive = policy, n, np.arange(n)

    def act(self, y: np.ndarray) -> np.ndarray:
        # no cast here: the loop converts the forces and refuses complex ones
        # (a cast to float would drop their imaginary part)
        if self.alive.size == self.n0:
            return np.asarray(self.policy.act(y)).reshape(-1)
        full = np.zeros((self.n0, y.shape[1]))
        full[self.alive] = y
        u = np.asarray(self.policy.act(full)).reshape(-1)
        return u[self.alive]

    def select(self, rows: np.ndarray) -> None:
        self.alive = self.alive[rows]

    @property
    def x_hat(self) -> np.ndarray | None:
        est = current_estimate(self.policy)
        return None if est is None else np.asarray(est)[self.alive]


#: Fewest episodes a shard of :func:`run_episodes` gets (smaller batches are run as one).
MIN_SHARD_ROWS = 32


def shard_count(n: int, nthread: int, backend: str, policy: object) -> int:
    """How many independent shards :func:`run_episodes` splits ``n`` episodes into.

    A batch on ``nthread ≥ 2`` physics threads runs as ``nthread`` shards of about ``n / nthread``
    episodes, each a :class:`Simulator` stepping its physics in its own Python thread
    (MuJoCo's batch and numpy's larger operations release the GIL): the policy and metrics work
    of one shard overlaps the physics of the others, where a single batch would leave the rollout
    threads idle during it. Results do not change (episodes are independent and each draws from its
    own generator). Only policies that declare ``independent_rows = True`` (every built-in; a plugin
    may opt in) are split — each shard gets a deep copy — others run as one batch.
    """
    if backend != "rollout" or nthread < 2 or not optional_members(policy).independent_rows:
        return 1
    return max(1, min(nthread, n // MIN_SHARD_ROWS))


def _shard_copy(policy: PolicyProtocol) -> PolicyProtocol:
    """A shard's own copy of ``policy`` (``independent_rows = True`` promises that it deep-copies);
    a copy that fails is a one-line error, not a traceback from inside ``copy``."""
    try:
        return copy.deepcopy(policy)
    except PendulumLQGError:
        raise
    except Exception as exc:
        text = " ".join(str(exc).split())
        raise PendulumLQGError(f"policy: independent_rows = True promises that the policy "
                               f"deep-copies (each thread shard runs a copy), but copy.deepcopy "
                               f"raised {type(exc).__name__}: {text}; set independent_rows = "
                               "False or make it copyable") from exc


class _Cancelled(Exception):
    """Another shard failed or the caller was interrupted: stop this one."""


def run_episodes(plant: SimulatedPlant, scenario: Scenario, policy: PolicyProtocol, *, seed: int,
                 episodes: Iterable[int] | np.ndarray, backend: Literal["rollout", "step"] = "rollout",
                 nthread: int | None = None, trajectory: bool = False,
                 initial_states: np.ndarray | None = None) -> BatchResult:
    """Run episodes ``episodes`` of the run seeded ``seed`` through the closed loop.

    Episode ``e`` draws everything from ``default_rng(episode_seed(seed, e))``, so its result does
    not depend on which other episodes share the batch, on the backend or on the thread count.

    Parameters
    ----------
    plant : the simulated plant (possibly mismatched with the policy's design model)
    scenario : the control problem
    policy : any policy of the protocol (:mod:`pendulum_lqg.core.protocol`) — ``reset(n)`` (or
        ``reset(n, x_hat0=…)`` when ``scenario.estimate0 == "true"``), ``act(y) -> u``, and
        optionally ``select(rows)``, ``needs_state``, ``x_hat`` (for the estimation-error metrics),
        ``estimator`` (for recordings) and ``independent_rows`` (see :func:`shard_count`);
        built-in policies and plugins alike
    seed : the run's seed
    episodes : episode numbers to run (non-negative integers): at least one, at most
        :data:`~pendulum_lqg.util.limits.MAX_BATCH_EPISODES` (100 000; with ``trajectory``
        :data:`~pendulum_lqg.util.limits.MAX_RECORDED_EPISODES`, 1 000), counted before anything
        is allocated — otherwise a one-line :class:`~pendulum_lqg.errors.ConfigError`
    backend, nthread : see :class:`Simulator` (with ``nthread ≥ 2`` a large batch is split into
        shards, :func:`shard_count`)
    trajectory : keep full trajectories (for recordings), not only the streamed metrics
    initial_states : optional (len(episodes), 4) initial states replacing the scenario's
        ``x0``/``x0_std`` draw (e.g. a region-of-attraction grid)
    """
    episodes = check_episodes(episodes, trajectory=trajectory)   # counted before anything is made
    nthread = thread_count(nthread)
    shards = shard_count(len(episodes), nthread, backend, policy)
    t0 = time.perf_counter()
    if shards == 1:
        return _run_batch(plant, scenario, policy, seed, episodes, backend, nthread, trajectory,
                          initial_states, None, t0)
    parts = np.array_split(np.arange(len(episodes)), shards)
    copies = [_shard_copy(policy) for _ in parts]        # all made before any shard starts
    stop = threading.Event()
    with ThreadPoolExecutor(max_workers=min(shards, nthread),
                            thread_name_prefix="pendulum-lqg-shard") as pool:
        futures = [pool.submit(_run_batch, plant, scenario, mine, seed,
                               [episodes[i] for i in part], backend, 1, trajectory,
                               None if initial_states is None
                               else np.asarray(initial_states)[part], stop, t0)
                   for part, mine in zip(parts, copies, strict=True)]
        try:
            results = [f.result() for f in futures]
        except BaseException:
            stop.set()                      # the other shards end at their next control period
            raise
    rows = [r for res in results for r in res.rows]
    trajectories = None if not trajectory else [
        tr for res in results for tr in (res.trajectories or [])]
    return BatchResult(rows=rows, trajectories=trajectories,
                       shard_seconds=[t for res in results for t in res.shard_seconds])


def _number_and_cover(trajectories: list[Trajectory], episodes: list[int],
                      estimator: object | None) -> None:
    """Give each trajectory its episode number and, where the estimator has one, the filter's
    covariance over the episode from its start (the snapshots hold a steady-gain filter's limit
    P from t = 0)."""
    over_time = getattr(estimator, "error_covariances", None)
    for tr, e in zip(trajectories, episodes, strict=True):
        tr.episode = e
        P = over_time(np.isfinite(tr.y).all(axis=1)) if callable(over_time) else None
        if P is not None:
            tr.P = P


def _run_batch(plant: SimulatedPlant, scenario: Scenario, policy: PolicyProtocol, seed: int,
               episodes: list[int],
               backend: Literal["rollout", "step"], nthread: int, trajectory: bool,
               initial_states: np.ndarray | None, stop: threading.Event | None,
               t0: float) -> BatchResult:
    """:func:`run_episodes` on one batch (one :class:`Simulator`); ``t0``: the run's start
    (``time.perf_counter``), for :attr:`BatchResult.shard_seconds`."""
    start = time.perf_counter() - t0
    seeds = episode_seeds(seed, episodes)       # = [episode_seed(seed, e) …], hashed at once
    gens = episode_generators(seeds)            # = [default_rng(s) …]
    n = len(episodes)
    log = TrajectoryLog() if trajectory else None
    with Simulator(plant, scenario, backend=backend, nthread=nthread) as sim:
        x0 = sim.reset(gens, initial_states=initial_states, private_generators=True)
        if scenario.estimate0 == "true":
            policy.reset(n, x_hat0=x0.copy())
        else:
            policy.reset(n)
        members = optional_members(policy)
        needs_state = members.needs_state
        # the policy as the loop drives it, on the running rows: itself when it selects them,
        # else fed the whole batch with only the running rows used
        loop_policy = (cast(SelectablePolicyProtocol, policy) if members.select is not None
                       else _WholeBatch(policy, n))
        # the estimator's rows are the running ones only when the policy selects them
        estimator = members.estimator if members.select is not None else None
        for _ in range(sim.n_periods):
            if stop is not None and stop.is_set():
                raise _Cancelled
            y = sim.measure()
            x_now = sim.x
            u = loop_policy.act(x_now if needs_state else y)
            x_hat = current_estimate(loop_policy)
            if log is not None:
                snap = dict(t=sim.t, x=x_now, y=y, **estimator_snapshot(estimator, x_hat, sim.n,
                                                                        sim.nx, sim.layout.p))
            res = sim.step(u, x_hat=x_hat)
            if log is not None:     # u: the requested force after saturation; u_policy: before
                log.add(sim.ids, u=res.requested, cost=res.cost, states=res.states,
                        u_policy=np.asarray(u, dtype=float).reshape(res.requested.shape),
                        **snap)
            if res.failed.any():
                keep = np.nonzero(~res.failed)[0]
                sim.select(keep)
                loop_policy.select(keep)
                if keep.size == 0:
                    break
        assert sim.metrics is not None
        rows = sim.metrics.rows(np.arange(n), np.array(seeds))
    for row, e in zip(rows, episodes, strict=True):
        row["episode"] = e
    trajectories = log.split(n, seeds, rows, sim.layout.C) if log is not None else None
    if trajectories is not None:
        _number_and_cover(trajectories, episodes, estimator)
    return BatchResult(rows=rows, trajectories=trajectories,
                       shard_seconds=[(start, time.perf_counter() - t0)])
