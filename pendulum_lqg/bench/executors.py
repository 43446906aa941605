"""Where a sweep's work units run: in this process, or as Ray tasks on a cluster.

An executor takes the pending :class:`~pendulum_lqg.bench.experiments.WorkUnit` s and yields
``(unit, rows, error)`` as each one finishes, in any order; :func:`pendulum_lqg.bench.sweep.run_sweep`
writes them. ``rows`` is ``None`` and ``error`` a one-line message for a unit that failed for good.

* :class:`LocalExecutor` — one unit after another in this process (the rollout of each unit uses
  ``nthread`` threads); an error stops the sweep (units already written stay).
* :class:`RayExecutor` — each unit is a Ray task (``pip install 'pendulum-lqg[ray]'``). Without
  ``address`` a local Ray instance is started for the run; with ``"auto"`` or ``"HOST:PORT"`` the
  driver joins an existing cluster, whose workers need only the installed package. A bounded number
  of tasks is in flight; a task lost with its node, or raising, is retried ``max_retries`` times;
  a unit that keeps failing is reported with its key while the rest of the sweep goes on.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from typing import Any, Protocol

from pendulum_lqg.bench.experiments import WorkUnit, run_unit
from pendulum_lqg.errors import ConfigError

Outcome = tuple[WorkUnit, list[dict[str, object]] | None, str | None]

#: How to get Ray when ``--executor ray`` finds none.
RAY_INSTALL_HINT = ("install the extra: pip install 'pendulum-lqg[ray]' (in a checkout: "
                    "uv run --extra ray pendulum-lqg …)")


class Executor(Protocol):
    """Runs work units; see the module docstring."""

    def run(self, units: Sequence[WorkUnit]) -> Iterator[Outcome]: ...

    def close(self) -> None: ...

    def describe(self) -> dict[str, object]: ...


class LocalExecutor:
    """Units one after another in this process, ``nthread`` rollout threads each."""

    def __init__(self, *, nthread: int | None = None) -> None:
        self.nthread = nthread

    def run(self, units: Sequence[WorkUnit]) -> Iterator[Outcome]:
        for unit in units:
            yield unit, run_unit(unit, nthread=self.nthread), None

    def close(self) -> None:
        return None

    def describe(self) -> dict[str, object]:
        return {"name": "local", "nthread": self.nthread}


def _run_unit_task(unit_json: str, nthread: int) -> list[dict[str, object]]:
    """The body of a Ray task: one work unit, from its JSON form (plain data over the wire)."""
    return run_unit(WorkUnit.from_json(unit_json), nthread=nthread)


class RayExecutor:
    """Work units as Ray tasks (see the module docstring).

    Parameters
    ----------
    address : ``None`` starts a local Ray instance for the run; ``"auto"`` or ``"HOST:PORT"`` joins
        an existing cluster
    num_cpus : CPUs of the local instance (default: all); ignored when joining a cluster
    max_in_flight : tasks submitted at once (default 2 × the cluster's CPUs)
    max_retries : retries of a task lost with its worker/node or raising (default 3)
    nthread : rollout threads inside each task (default 1: one task per CPU)
    """

    def __init__(self, *, address: str | None = None, num_cpus: int | None = None,
                 max_in_flight: int | None = None, max_retries: int = 3, nthread: int = 1) -> None:
        if address not in (None, "auto"):
            check_reachable(str(address))
            _token_auth_for_explicit_address()         # read by Ray when it is imported
        _workers_in_this_environment()
        try:
            import ray
        except ImportError:
            raise ConfigError(f"--executor ray: Ray is not installed; {RAY_INSTALL_HINT}") from None
        if isinstance(max_retries, bool) or not isinstance(max_retries, int) or max_retries < 0:
            raise ConfigError(f"max_retries: expected a non-negative integer, got {max_retries!r}")
        self._ray = ray
        self.address = address
        self.max_retries = max_retries
        self.nthread = nthread
        self._connected_here = not ray.is_initialized()   # else the caller owns the connection
        #: a Ray instance started for this run on this machine (close() stops it)
        self._local_instance = self._connected_here and address is None
        try:
            if self._connected_here:
                ray.init(address=address, num_cpus=num_cpus if address is None else None,
                         include_dashboard=False, log_to_driver=False,
                         configure_logging=False)
        except ConnectionError as exc:
            raise ConfigError(f"--address: cannot reach a Ray cluster at {address!r}: "
                              f"{' '.join(str(exc).split())}") from exc
        except Exception as exc:           # Ray's own refusals (a bad address, a failed start)
            where = "a local Ray instance" if address is None else f"the Ray cluster at {address!r}"
            raise ConfigError(f"--executor ray: cannot start or join {where}: "
                              f"{type(exc).__name__}: {' '.join(str(exc).split())[:300]}"
                              ) from exc
        cpus = int(ray.cluster_resources().get("CPU", 1))
        self.max_in_flight = max_in_flight or max(1, 2 * cpus)
        self._task = ray.remote(num_cpus=1, max_retries=max_retries,
                                retry_exceptions=True)(_run_unit_task)

    def run(self, units: Sequence[WorkUnit]) -> Iterator[Outcome]:
        ray = self._ray
        pending = list(units)[::-1]
        in_flight: dict[Any, WorkUnit] = {}
        try:
            while pending or in_flight:
                while pending and len(in_flight) < self.max_in_flight:
                    unit = pending.pop()
                    in_flight[self._task.remote(unit.to_json(), self.nthread)] = unit
                ready, _ = ray.wait(list(in_flight), num_returns=1)
                unit = in_flight.pop(ready[0])
                try:
                    rows = ray.get(ready[0])
                except ray.exceptions.RayError as exc:
                    yield unit, None, _ray_error_line(exc)
                    continue
                yield unit, rows, None
        finally:
            # interrupted: stop what is still running. A local instance started for this run is
            # stopped whole by close(), workers included; cancelling there too only risks Ray's
            # race between a cancel and a task's reply arriving, which aborts the driver
            # ("it != submissible_tasks_.end()", ray-project/ray#54798) and turns a clean
            # Ctrl-C into a crash. On a cluster the tasks must be cancelled, or they run on.
            if not self._local_instance:
                for ref in in_flight:
                    ray.cancel(ref, force=True)

    def close(self) -> None:
        """Disconnect (and stop the local instance started for the run), unless the caller had
        connected to Ray before."""
        if self._connected_here and self._ray.is_initialized():
            self._ray.shutdown()

    def describe(self) -> dict[str, object]:
        return {"name": "ray", "address": self.address or "local",
                "max_retries": self.max_retries, "max_in_flight": self.max_in_flight,
                "nthread": self.nthread, "ray": self._ray.__version__}


#: Seconds the driver waits for a TCP connection to ``--address HOST:PORT`` before giving up.
CONNECT_TIMEOUT_S = 10.0


def check_reachable(address: str, timeout: float = CONNECT_TIMEOUT_S) -> None:
    """Refuse ``HOST:PORT`` (or ``ray://HOST:PORT``) at once when nothing accepts a TCP
    connection there: Ray's own connect keeps retrying for many minutes. A one-line
    :class:`ConfigError` naming ``--address``."""
    import socket

    hostport = address.split("://", 1)[-1]
    host, sep, port = hostport.rpartition(":")
    host = host.strip("[]")                            # [::1]:6379
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ConfigError(f"--address: expected 'auto' or HOST:PORT (e.g. 10.0.0.5:6379), got "
                          f"{address!r}")
    try:
        with socket.create_connection((host, int(port)), timeout=timeout):
            pass
    except OSError as exc:
        why = "timed out" if isinstance(exc, TimeoutError) else (exc.strerror or str(exc))
        raise ConfigError(f"--address: no Ray cluster answers at {address} ({why} within "
                          f"{timeout:g} s); start its head with `ray start --head` or give the "
                          "address it prints") from None


def _workers_in_this_environment() -> None:
    """Keep Ray's workers in the environment pendulum_lqg is installed in (read by Ray when it is
    imported; a choice the user made in the environment stands).

    Under ``uv run`` Ray (≥ 2.43) would otherwise start every worker as ``uv run … python`` in a
    zipped copy of the current folder: with ``--no-sync`` that copy has no environment and each
    worker dies on ``import ray``; without it each node resolves and installs the whole project
    again before its worker can register. A work unit travels as JSON and needs only the installed
    package, which a worker of the driver's own interpreter has.
    """
    import os

    os.environ.setdefault("RAY_ENABLE_UV_RUN_RUNTIME_ENV", "0")


def _token_auth_for_explicit_address() -> None:
    """Send this machine's Ray token when joining a cluster by ``HOST:PORT``.

    ``ray start --head`` (Ray ≥ 2.59) enables token authentication and stores the token in
    ``~/.ray/auth_token``; ``address="auto"`` picks that up, but a driver given ``HOST:PORT``
    defaults to ``RAY_AUTH_MODE=disabled`` and is refused. When the user has not chosen a mode and a
    token is at hand, use it (a cluster without authentication ignores it).
    """
    import os
    from pathlib import Path

    if os.environ.get("RAY_AUTH_MODE"):
        return
    token_path = Path(os.environ.get("RAY_AUTH_TOKEN_PATH", Path.home() / ".ray" / "auth_token"))
    if os.environ.get("RAY_AUTH_TOKEN") or token_path.is_file():
        os.environ["RAY_AUTH_MODE"] = "token"


def _ray_error_line(exc: BaseException) -> str:
    """The cause of a failed Ray task in one line (the task's own exception if it raised)."""
    cause = getattr(exc, "cause", None)
    err = cause if isinstance(cause, BaseException) else exc
    text = " ".join(str(err).split())
    return f"{type(err).__name__}: {text[:300]}"


def make_executor(name: str, *, address: str | None = None, nthread: int | None = None,
                  ) -> LocalExecutor | RayExecutor:
    """The executor named on the command line (``--executor local|ray``)."""
    if name == "local":
        if address is not None:
            raise ConfigError("--address: only with --executor ray")
        return LocalExecutor(nthread=nthread)
    if name == "ray":
        return RayExecutor(address=address, nthread=nthread or 1)
    raise ConfigError(f"--executor: expected 'local' or 'ray', got {name!r}")
