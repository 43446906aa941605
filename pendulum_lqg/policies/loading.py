"""Bring your own controller: the policy protocol, :class:`PolicyContext` and plugin loading.

Every policy the benchmark runs — the built-in LQG variants and a user's plugin alike — is built by
one function, :func:`build_policy`, and driven by the simulation core through one protocol. A
policy is a *batched* object::

    policy.reset(n)          # n episodes start; the policy's estimate starts from its own prior (0)
    u = policy.act(y)        # y (n, 2) = [p, θ] measured at the start of the period → u (n,) [N]
    policy.select(rows)      # optional: keep only these rows (episodes that ended are dropped)
    policy.needs_state       # optional, default False: True → act receives the true state (n, 4)
    policy.x_hat             # optional: the (n, 4) estimate used at this sample (metrics: RMS x̂−x)
    policy.independent_rows  # optional, default False: True promises that each row evolves on its
                             # own and the object deep-copies, so the core may split a large batch
                             # into shards run in parallel, each with its own copy (same results)

``u`` is held over the control period and saturated by the core to the actuator range. A plugin is
named ``MODULE:ATTR`` (an importable module) or ``path/to/file.py:ATTR``; ``ATTR`` is a factory
called once per batch with a :class:`PolicyContext`, returning such an object.

Rules the core enforces (documented in docs/plugins.md):

* a plugin that raises, whose ``act`` returns the wrong shape, or that lacks ``reset``/``act`` stops
  the run with a one-line :class:`~pendulum_lqg.errors.PluginError` naming the plugin (the CLI exits
  2; work units already written stay on disk);
* a non-finite force (nan, ±inf) ends that episode as ``diverged`` — a controller that blows up
  numerically has failed the episode, the rest of the batch goes on;
* without ``select`` the core keeps feeding the whole original batch (rows of ended episodes get
  zero measurements and their forces are dropped), so a plugin may keep its own fixed-size state.
"""

from __future__ import annotations

import copy
import dataclasses
import hashlib
import importlib
import importlib.util
import inspect
import sys
import types
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from pendulum_lqg.errors import ConfigError, PluginError
from pendulum_lqg.util.watchdog import watched

if TYPE_CHECKING:
    from pendulum_lqg.core.noise import NoiseModel
    from pendulum_lqg.core.protocol import PolicyProtocol
    from pendulum_lqg.core.scenario import Scenario
    from pendulum_lqg.model.interface import Layout, SimulatedPlant
    from pendulum_lqg.policies.lqg import DesignSpec


@dataclass(frozen=True, eq=False)
class PolicyContext:
    """Everything a policy factory may design from: the nominal plant's models, noise and limits,
    in the plant's own sizes (n states, m inputs, p outputs; :attr:`layout` names them).

    The models are those of the *nominal* plant (the XML without the scenario's mismatch overrides),
    the same ones the built-in designs use.

    Attributes
    ----------
    A : (n, n), B : (n, m), C : (p, n)
        Continuous linear model about the equilibrium, ``ẋ = Ax + Bu``, ``y = Cx`` (the cart-pole:
        ``x = [p, θ, ṗ, θ̇]``, u the cart force [N], ``y = [p, θ]``); ``A`` and ``B`` are
        ``None`` for a plant given in discrete time (only ``Phi``, ``Gamma`` exist).
    Phi : (n, n), Gamma : (n, m)
        Exact zero-order-hold discretisation at the control period ``dt``.
    dt : float
        Control period T [s]: ``act`` is called once per period and its force is held.
    W : (n, n)
        Process-noise spectral density in state form (``G W_in Gᵀ``; units²·s): for the lecture's
        state noise the state jumps by ``N(0, W·T)`` once per period. A plant file gives the
        jump's covariance ``Wd`` over a period; its ``W`` here is ``Wd / T``.
    V : (p, p)
        Measurement-noise covariance per sample (the outputs' units²).
    u_max : float or (m,) array
        Actuator limit per input in physical units [N or N·m] (the scenario's ``force_limit``,
        else the model's ``ctrlrange``; ``inf`` when saturation is off): inputs are saturated
        to ``[−u_max, u_max]`` by the core (:func:`pendulum_lqg.core.rules.limits`).
    Q : (n, n), R : (m, m)
        Weights of the benchmark's cost ``J = ∫ xᵀQx + uᵀRu dt`` (a plant file's cross term is in
        :attr:`N`).
    plant : pendulum_lqg.model.interface.SimulatedPlant
        The nominal plant (advanced use: parameters, the compiled model).
    noise : pendulum_lqg.core.noise.NoiseModel
        The nominal noise model of the scenario (the cart-pole's ``W``/``V`` above come from it;
        a plant file's come from the file).
    G : (n, q)
        Input matrix of the process noise (I for state noise, the generalised-force map for
        force noise).
    Wd : (n, n)
        Covariance of the process noise accumulated over one control period (what a discrete
        Kalman filter takes).
    N : (n, m)
        Cross weight of the cost ``2 xᵀ N u`` (zeros when there is none).
    layout : pendulum_lqg.model.interface.Layout
        The plant's vectors: the names of x, y and u, x₀ and its spread, the per-state limits.
    """

    A: np.ndarray | None
    B: np.ndarray | None
    C: np.ndarray
    Phi: np.ndarray
    Gamma: np.ndarray
    dt: float
    W: np.ndarray
    V: np.ndarray
    u_max: Any
    Q: np.ndarray
    R: np.ndarray
    plant: SimulatedPlant
    noise: NoiseModel
    G: np.ndarray = field(repr=False, default_factory=lambda: np.eye(4))
    Wd: np.ndarray | None = field(repr=False, default=None)
    N: np.ndarray | None = field(repr=False, default=None)
    layout: Layout | None = field(repr=False, default=None)

    @classmethod
    def build(cls, plant: SimulatedPlant, scenario: Scenario) -> PolicyContext:
        """The context of ``plant`` (nominal) under ``scenario``'s period, noise and cost."""
        from pendulum_lqg.core.rules import limits
        from pendulum_lqg.model.interface import steps_per_period
        from pendulum_lqg.policies.observers import (
            noise_design_matrices,
            per_sample_process_covariance,
        )

        steps_per_period(plant, scenario.control_period)
        dt = float(scenario.control_period)
        lay = plant.layout(scenario)
        n, m = lay.n, lay.m
        Phi, Gamma = plant.sampled(dt)
        try:
            lin = plant.linear_model()
            A, B = lin.A, lin.B
        except ConfigError:                  # given in discrete time: no continuous model
            lin, A, B = None, None, None
        if lay.covariances is None:          # the cart-pole: the scenario's noise model
            assert lin is not None
            G, W_in = noise_design_matrices(lin, scenario.noise)
            W, V = G @ W_in @ G.T, scenario.noise.V
            Wd = per_sample_process_covariance(lin, scenario.noise, dt)
        else:                                # a plant file's own covariances
            Wd, V = lay.covariances
            G, W = np.eye(n), Wd / dt
        if lay.cost_matrix is not None:
            Q, N = lay.cost_matrix[:n, :n], lay.cost_matrix[:n, n:]
            R = lay.cost_matrix[n:, n:]
        else:
            Q, N, R = np.diag(lay.cost_Q), np.zeros((n, m)), np.eye(m) * lay.cost_R
        if lay.C is not None:
            C = lay.C
        else:                                # the cart-pole: its sensors' rows
            assert lin is not None
            C = lin.C
        return cls(A=A, B=B, C=C, Phi=Phi, Gamma=Gamma, dt=dt, W=W, V=V,
                   u_max=limits(plant, scenario)[2], Q=Q, R=R, plant=plant,
                   noise=scenario.noise, G=G, Wd=Wd, N=N, layout=lay)


# ---- names ----------------------------------------------------------------------------------------
class PolicyFactory(Protocol):
    """What a plug-in reference ``MODULE:ATTR`` names: called once per batch with the design
    context, it returns a policy of the protocol (:class:`~pendulum_lqg.core.protocol.PolicyProtocol`
    and its optional members)."""

    def __call__(self, context: PolicyContext, /) -> PolicyProtocol: ...


def is_plugin_ref(name: str) -> bool:
    """``MODULE:ATTR`` / ``file.py:ATTR`` (a plugin) rather than ``controller+observer``."""
    return isinstance(name, str) and ":" in name


def resolve_ref(ref: str, base_dir: Path | None = None) -> str:
    """``ref`` with a relative ``file.py`` part made absolute, so a work unit finds the file
    wherever it runs: the first of ``base_dir``, the current folder and the shipped experiments
    folder that has it (:func:`~pendulum_lqg.util.resources.find_file`: ``plugin_example.py:make``
    and ``experiments/plugin_example.py:make`` work from an installed package). Module refs are
    returned unchanged."""
    from pendulum_lqg.util.resources import find_file

    module, attr = _split(ref)
    if not _is_path(module):
        return ref
    return f"{find_file(module, base_dir)}:{attr}"


def _split(ref: str) -> tuple[str, str]:
    if not isinstance(ref, str) or ":" not in ref:
        raise ConfigError(f"policy: expected 'controller+observer' or a plugin 'MODULE:ATTR' / "
                          f"'path/to/file.py:ATTR', got {ref!r}")
    module, _, attr = ref.rpartition(":")
    if not module or not attr.isidentifier():
        raise ConfigError(f"policy {ref!r}: expected 'MODULE:ATTR' or 'path/to/file.py:ATTR' with "
                          "ATTR a Python name")
    return module, attr


def _is_path(module: str) -> bool:
    return module.endswith(".py") or "/" in module or "\\" in module


def load_factory(ref: str, *, base_dir: Path | None = None) -> PolicyFactory:
    """Import the factory named by ``ref`` (``MODULE:ATTR`` or ``path/to/file.py:ATTR``).

    A file is imported as a module of its own, under a name derived from its path and its content
    (two plugin files of the same name do not collide, and a file edited since it was imported in
    this process is imported afresh). Errors are one-line :class:`PluginError` messages.
    """
    module_name, attr = _split(resolve_ref(ref, base_dir))
    if _is_path(module_name):
        module = _import_file(ref, Path(module_name))
    else:
        try:
            module = guarded(ref, "import", importlib.import_module, module_name)
        except PluginError as exc:
            raise PluginError(f"policy {ref!r}: cannot import module {module_name!r}: "
                              f"{_one_line(exc.__cause__ or exc)}") from exc.__cause__
    factory = guarded(ref, f"reading {attr}", getattr, module, attr, None)
    if factory is None:
        raise PluginError(f"policy {ref!r}: {module_name} has no attribute {attr!r}")
    if not callable(factory):
        raise PluginError(f"policy {ref!r}: {attr} is not callable (expected a factory taking a "
                          "PolicyContext)")
    return factory


def _import_file(ref: str, path: Path) -> types.ModuleType:
    """The module of the plug-in file ``path``, run from exactly the bytes read here: read, hashed
    (the module's name carries the hash), compiled and executed — never a cached ``.pyc``, whose
    check (the source's mtime in whole seconds and its size) misses an edit within the same second.
    The same bytes are what :func:`source_digest` fingerprints."""
    if not path.is_file():
        raise PluginError(f"policy {ref!r}: no file {path}")
    try:
        content = path.read_bytes()
    except OSError as exc:
        raise PluginError(f"policy {ref!r}: cannot read {path}: {exc.strerror or exc}") from exc
    where = hashlib.sha256(str(path).encode()).hexdigest()[:10]
    name = f"_pendulum_lqg_plugin_{path.stem}_{where}_{hashlib.sha256(content).hexdigest()[:10]}"
    module = sys.modules.get(name)
    if module is not None:
        return module
    code = guarded(ref, f"compiling {path}", compile, content, str(path), "exec",
                   dont_inherit=True)
    spec = importlib.util.spec_from_loader(name, loader=None, origin=str(path))
    module = importlib.util.module_from_spec(spec)       # type: ignore[arg-type]
    module.__file__ = str(path)
    sys.modules[name] = module                 # dataclasses and pickling look the module up
    try:
        guarded(ref, f"importing {path}", exec, code, module.__dict__)
    except PluginError:
        del sys.modules[name]
        raise
    return module


def source_digest(ref: str, *, base_dir: Path | None = None) -> str:
    """SHA-256 of a plugin's source, which an experiment's fingerprint includes: the bytes of
    ``file.py`` for a file reference; for ``MODULE:ATTR`` the module's source file (every ``.py``
    file of a package, with its relative path). Code the plugin imports from elsewhere is not
    covered."""
    module_name, _ = _split(resolve_ref(ref, base_dir))
    files: list[tuple[str, Path]] = []
    if _is_path(module_name):
        files = [("", Path(module_name))]
    else:
        spec = guarded(ref, "finding the module", importlib.util.find_spec, module_name)
        if spec is None:
            raise PluginError(f"policy {ref!r}: cannot import module {module_name!r}")
        for location in spec.submodule_search_locations or ():
            root = Path(location)
            files += sorted((str(f.relative_to(root)), f) for f in root.rglob("*.py"))
        if not files and spec.origin is not None and Path(spec.origin).is_file():
            files = [("", Path(spec.origin))]          # a plain module (or an extension's binary)
    digest = hashlib.sha256()
    for name, path in files:
        try:
            content = path.read_bytes()
        except OSError as exc:
            raise PluginError(f"policy {ref!r}: cannot read {path}: {exc.strerror or exc}") from exc
        digest.update(f"{name}\0{len(content)}\0".encode())
        digest.update(content)
    return digest.hexdigest()


def check_source(ref: str, expected: str | None) -> None:
    """The plugin's source must still be the one ``expected`` (its :func:`source_digest` when the
    experiment was read): a file edited while a sweep runs would otherwise mix two versions of
    the controller in one results folder."""
    if expected is not None and source_digest(ref) != expected:
        raise PluginError(f"policy {ref!r}: its source changed since the experiment was read; "
                          "run the sweep again with --resume (the units of the old source are "
                          "then recomputed)")


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split())
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def guarded(ref: str, what: str, fn: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
    """``fn(*args, **kwargs)`` — plugin code — through :func:`guard`, naming the plug-in
    ``policy 'REF'``."""
    return guard(f"policy {ref!r}", what, fn, *args, **kwargs)


def guard(label: str, what: str, fn: Callable[..., Any], *args: Any,
          passing: tuple[type[BaseException], ...] = (), **kwargs: Any) -> Any:
    """``fn(*args, **kwargs)`` — user code: a plug-in's or an agent's — with whatever it raises
    turned into one :class:`PluginError` line ``LABEL: WHAT raised …``: every exception,
    ``SystemExit`` (``sys.exit`` in user code) included, except a Ctrl-C (``KeyboardInterrupt``),
    which stops the run as a Ctrl-C does. A call that does not return within the active
    :class:`~pendulum_lqg.util.watchdog.Watchdog`'s limit is stopped with a
    :class:`~pendulum_lqg.util.watchdog.CallTimeout` line. User code cannot end the run with a success
    status or without a message this way (``os._exit`` ends the process at once, uncatchable;
    docs/reliability.md). Exceptions of the types ``passing`` are re-raised as they are (an
    agent's factory declines a suite with :class:`~pendulum_lqg.errors.NotApplicable`)."""
    keep: tuple[type[BaseException], ...] = (PluginError, KeyboardInterrupt, *passing)
    try:
        with watched(label, what):
            return fn(*args, **kwargs)
    except keep:
        raise
    except BaseException as exc:
        raise PluginError(f"{label}: {what} raised {_one_line(exc)}") from exc


_MISSING = object()


# ---- the adapter the core drives ------------------------------------------------------------------
class PluginPolicy:
    """A user's policy behind the core's protocol: checks every call and names the plugin.

    The optional members are read and validated once, here; a member that raises when read or
    holds the wrong kind of value is a one-line :class:`PluginError`.

    Attributes
    ----------
    name : the plugin reference as given
    inner : the object the factory returned
    needs_state : from ``inner`` (default False)
    info : design data for reports and recordings (``inner.info``, a dict with string keys)
    select : present only if ``inner`` has one (otherwise the core keeps the whole batch)
    independent_rows : ``inner``'s promise (default False); True is checked by one deep copy
    estimator : present only if ``inner`` has one (recordings log its ``x_prior``,
        ``innovation`` and ``P``)
    sizes : ``(n, m, p)``, the plant's states, inputs and outputs (default the cart-pole's
        ``(4, 1, 2)``): ``act`` returns m inputs per row, ``x_hat`` has n columns
    """

    def __init__(self, name: str, inner: object, sizes: tuple[int, int, int] = (4, 1, 2)) -> None:
        self.name = name
        self.inner = inner
        self.sizes = sizes
        for method in ("reset", "act"):
            if not callable(self._member(method, None)):
                raise PluginError(f"policy {name!r}: the factory returned {type(inner).__name__}, "
                                  f"which has no {method}() method (expected reset(n) and act(y))")
        needs = self._member("needs_state", False)
        if not isinstance(needs, bool | np.bool_):
            raise PluginError(f"policy {name!r}: needs_state must be True or False, got "
                              f"{_short(needs)}")
        self.needs_state = bool(needs)
        info = self._member("info", None)
        if info is None:
            info = {}
        if not isinstance(info, Mapping):
            raise PluginError(f"policy {name!r}: info must be a dict of design data (gains, "
                              f"poles), got {type(info).__name__}")
        self.info: dict[str, Any] = guarded(name, "reading info", dict, info)
        if not all(isinstance(k, str) for k in self.info):
            raise PluginError(f"policy {name!r}: info must have string keys, got "
                              f"{sorted(map(repr, self.info))[:3]}")
        select = self._member("select", None)
        if select is not None:
            if not callable(select):
                raise PluginError(f"policy {name!r}: select must be a method select(rows), got "
                                  f"{type(select).__name__}")
            self.select = self._select
        rows = self._member("independent_rows", False)
        if not isinstance(rows, bool | np.bool_):
            raise PluginError(f"policy {name!r}: independent_rows must be True or False, got "
                              f"{_short(rows)}")
        #: the plugin's promise that its rows are independent (the core may shard the batch)
        self.independent_rows = bool(rows)
        if self.independent_rows:
            copy.deepcopy(self)                     # the promise checked once: it deep-copies
        est = self._member("estimator", None)
        if est is not None:
            if isinstance(est, int | float | complex | str | bytes | list | tuple | dict
                          | np.ndarray | np.generic):
                raise PluginError(f"policy {name!r}: estimator must be an object with x_prior, "
                                  f"innovation and P (what recordings log), got "
                                  f"{type(est).__name__}")
            self.estimator = _EstimatorView(self, est)
        self._rows = 0                              # rows of the last act
        params: Mapping[str, Any]
        try:
            params = inspect.signature(inner.reset).parameters    # type: ignore[attr-defined]
        except (KeyboardInterrupt, PluginError):
            raise
        except BaseException:
            params = {}
        self._reset_takes_x_hat0 = "x_hat0" in params

    def _member(self, attr: str, default: object) -> Any:
        """``inner.attr`` (``default`` if absent); raising when read is a :class:`PluginError`."""
        return guarded(self.name, f"reading {attr}", getattr, self.inner, attr, default)

    def _call(self, what: str, fn: Callable[..., Any], *args: Any, **kwargs: Any) -> Any:
        return guarded(self.name, what, fn, *args, **kwargs)

    def reset(self, n: int, x_hat0: np.ndarray | None = None) -> None:
        """Start ``n`` episodes (``x_hat0`` only for plugins whose ``reset`` takes it)."""
        if x_hat0 is None:
            self._call("reset", self.inner.reset, n)                   # type: ignore[attr-defined]
        elif self._reset_takes_x_hat0:
            self._call("reset", self.inner.reset, n, x_hat0=x_hat0)    # type: ignore[attr-defined]
        else:
            raise PluginError(f"policy {self.name!r}: estimate0 = 'true' needs "
                              "reset(n, x_hat0=…); this plugin's reset takes only n")
        self._rows = n

    def act(self, y: np.ndarray) -> np.ndarray:
        """Inputs (n,) — (n, m) for a plant of m > 1 inputs — for the rows of ``y``; shape and
        type checked, non-finite values kept (the core ends those episodes as ``diverged``)."""
        self._rows = y.shape[0]
        return self._check(self._call("act", self.inner.act, y), y.shape[0])  # type: ignore[attr-defined]

    def _check(self, u: object, n: int) -> np.ndarray:
        m = self.sizes[1]
        if m > 1:
            arr = self._array("act", "inputs", u, f"an array of {n} × {m} inputs, shape ({n}, {m})")
            if arr.shape != (n, m):
                raise PluginError(f"policy {self.name!r}: act returned shape {arr.shape}; "
                                  f"expected ({n}, {m}): {m} inputs per running episode")
            return arr
        arr = self._array("act", "forces", u, f"an array of {n} forces in newtons, shape ({n},)")
        if arr.shape not in ((n,), (n, 1)):
            raise PluginError(f"policy {self.name!r}: act returned shape {arr.shape}; expected "
                              f"({n},) forces in newtons")
        return arr.reshape(n)

    def _array(self, member: str, what: str, value: object, expected: str) -> np.ndarray:
        """``value`` as a real float array; what a plugin returns, converted (``__array__`` of a
        plugin's object is plugin code too): a complex value or a non-number is refused."""
        arr = self._call(f"converting {member}", np.asarray, value)
        if arr.dtype.kind == "c":            # a cast would drop the imaginary part silently
            raise PluginError(f"policy {self.name!r}: {member} returned complex {what} "
                              f"{_short(arr.reshape(-1)[:3])}; expected real {what}")
        try:
            return np.asarray(arr, dtype=float)
        except (TypeError, ValueError) as exc:
            raise PluginError(f"policy {self.name!r}: {member} returned "
                              f"{type(value).__name__}; expected {expected}") from exc

    def _select(self, rows: np.ndarray) -> None:
        self._call("select", self.inner.select, rows)                  # type: ignore[attr-defined]
        self._rows = len(rows)

    @property
    def x_hat(self) -> np.ndarray | None:
        """The plugin's current estimate (rows, n), or None; anything else is a
        :class:`PluginError`."""
        est = self._member("x_hat", None)
        if est is None:
            return None
        return self.checked_rows("x_hat", est, (self.sizes[0],))

    def checked_rows(self, member: str, value: object, tail: tuple[int, ...]) -> np.ndarray:
        """``value`` as a real (n, *tail) array, n the rows of the last ``act``."""
        want = (self._rows, *tail)
        arr = self._array(member, "values", value, f"an array of shape {want}")
        if arr.shape != want:
            raise PluginError(f"policy {self.name!r}: {member} has shape {arr.shape}; expected "
                              f"{want} (one row per running episode) or None")
        return arr

    def __deepcopy__(self, memo: dict[int, Any]) -> PluginPolicy:
        """A copy for a shard (``independent_rows = True``): the plugin's object deep-copied; what
        that raises is a one-line :class:`PluginError`."""
        new = object.__new__(type(self))
        memo[id(self)] = new
        state = guarded(self.name, "copy.deepcopy (independent_rows = True promises a working "
                        "deep copy)", copy.deepcopy, self.__dict__, memo)
        new.__dict__.update(state)
        return new


class _EstimatorView:
    """A plugin's ``estimator`` as recordings read it: ``x_prior`` (rows, n), ``innovation``
    (rows, p) and ``P`` (n, n) or (rows, n, n), each checked when read (absent: not recorded)."""

    def __init__(self, policy: PluginPolicy, estimator: object) -> None:
        self._policy, self._estimator = policy, estimator

    def _read(self, attr: str, tails: tuple[tuple[int, ...], ...]) -> np.ndarray | None:
        policy = self._policy
        value = guarded(policy.name, f"reading estimator.{attr}", getattr, self._estimator, attr,
                        None)
        if value is None:
            return None
        if len(tails) > 1 and np.shape(value) == tails[0]:
            return policy._array(f"estimator.{attr}", "values", value, f"shape {tails[0]}")
        return policy.checked_rows(f"estimator.{attr}", value, tails[-1])

    @property
    def x_prior(self) -> np.ndarray | None:
        return self._read("x_prior", ((self._policy.sizes[0],),))

    @property
    def innovation(self) -> np.ndarray | None:
        return self._read("innovation", ((self._policy.sizes[2],),))

    @property
    def P(self) -> np.ndarray | None:
        n = self._policy.sizes[0]
        return self._read("P", ((n, n), (n, n)))


def _short(value: object) -> str:
    text = " ".join(repr(value).split())
    return text if len(text) <= 80 else text[:77] + "..."


# ---- one way to build any policy ------------------------------------------------------------------
def build_policy(name: str | None, *, plant: SimulatedPlant, scenario: Scenario,
                 spec: DesignSpec | None = None, base_dir: Path | None = None,
                 context: PolicyContext | None = None) -> Any:
    """The policy ``name`` for the nominal ``plant`` under ``scenario`` — built-in or plugin.

    Parameters
    ----------
    name : ``"controller+observer"`` (a built-in, e.g. ``"dlqr+kalman"``), a plugin reference
        ``MODULE:ATTR`` / ``path/to/file.py:ATTR``, or ``None`` for ``spec``'s own controller and
        observer
    plant : the nominal plant the design believes in (not the mismatched, simulated one)
    scenario : period, nominal noise (its ``scale`` is ignored by designs) and cost weights
    spec : weights and other design options of the built-ins (default :class:`DesignSpec`)
    base_dir : folder that relative plugin file paths are taken from (an experiment file's folder)
    context : a prebuilt :class:`PolicyContext` (saves re-linearising for many plugins)
    """
    from pendulum_lqg.policies.lqg import DesignSpec, delay_periods, design_policy

    spec = spec or DesignSpec()
    if name is not None and is_plugin_ref(name):
        factory = load_factory(name, base_dir=base_dir)
        ctx = context if context is not None else PolicyContext.build(plant, scenario)
        lay = ctx.layout if ctx.layout is not None else plant.layout(scenario)
        return PluginPolicy(name, guarded(name, "the factory", factory, ctx),
                            sizes=(lay.n, lay.m, lay.p))
    if name is not None:
        controller, observer = split_builtin(name)
        spec = dataclasses.replace(spec, controller=controller, observer=observer)
    from pendulum_lqg.core.rules import limits

    return design_policy(plant, scenario.control_period, scenario.noise, spec,
                         delays=delay_periods(scenario), u_max=limits(plant, scenario)[2])


def split_builtin(name: str) -> tuple[str, str]:
    """``"dlqr+kalman"`` → ``("dlqr", "kalman")`` (validated by :class:`DesignSpec`)."""
    if not isinstance(name, str) or name.count("+") != 1:
        raise ConfigError(f"policy: expected 'controller+observer' (e.g. 'dlqr+kalman') or a "
                          f"plugin 'MODULE:ATTR' / 'path/to/file.py:ATTR', got {name!r}")
    controller, observer = name.split("+")
    return controller, observer
