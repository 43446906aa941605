r"""Any linear plant given as matrices: ``ẋ = A x + B u + G w``, ``y = C x + v``, sampled at T.

A separate, explicit kind of plant beside the MuJoCo cart-pole (whose MJCF model stays the one
source of truth of the cart-pole): the documents' double integrator, Franklin's third-order plant
and Ogata's discrete example are files in ``experiments/lti/``, read by
:func:`load_lti` from TOML or ``.npz``. An :class:`LTIPlant` carries its own noise (the density W
of w, the per-sample covariance V of v), cost weights and input limits; its designs, scenario and
stationary closed loop are :mod:`pendulum_lqg.policies.lti`'s. A ``control.StateSpace`` becomes one
through :func:`pendulum_lqg.policies.control_io.from_statespace`.

A TOML file::

    name = "double_integrator"
    description = "…"
    control_period = 0.1          # T [s]
    A = [[0, 1], [0, 0]]          # or, for a plant given in discrete time: Phi, Gamma
    B = [[0], [1]]                # n × m: m inputs
    C = [[1, 0]]                  # p × n (default I)
    G = [[1, 0], [0, 1]]          # optional, default I: where w enters
    states = ["position", "velocity"]       # optional names (distinct identifiers)
    inputs = ["force"]            # optional names of u (default u1, u2, …)
    outputs = ["position"]        # optional names of y (default y1, y2, …)
    W = [1, 1]                    # density of w (diagonal or matrix), units²·s; or Wd, the
                                  # per-period covariance of w (the documents' discrete Rw)
    V = [1]                       # per-sample covariance of v (diagonal or matrix)
    Q = [[1, 0], [0, 0]]          # optional cost weights (default CᵀC, R = I): Q symmetric
    R = 1                         # ≥ 0 (diagonal or matrix), R m × m > 0 (a number: R·I),
    N = [[0], [0]]                # optional cross term of J = ∫ xᵀQx + 2xᵀNu + uᵀRu dt
    force_limit = inf             # optional saturation [input units], one or m numbers
    observer_poles = [-2, -3]     # optional continuous Luenberger poles (numbers or "a+bj"
                                  # strings, conjugate pairs; default 3× the controller's)
    x0 = [1, 0]                   # optional mean initial state (default 0) and its std
    x0_std = [0, 0]               # (default 0), drawn per episode by ``run`` and ``bench``
    state_limits = [inf, inf]     # optional failure limits |x_i| ≤ limit_i (default: none, only
                                  # divergence ends an episode)

An ``.npz`` holds the same names as arrays (``control_period`` a 0-d array; names as text
arrays, every other member numeric).

Files are read through :mod:`pendulum_lqg.boundary` (regular files only, at most
:data:`~pendulum_lqg.util.limits.MAX_INPUT_BYTES`, nesting at most
:data:`~pendulum_lqg.util.limits.MAX_NESTING` deep), every dimension n, m, p, q is at most
:data:`MAX_LTI_DIMENSION` (checked before any array is built), and every error is one line
``lti: FILE: KEY: expected …, got …``.
"""

from __future__ import annotations

import hashlib
import io
import math
import zipfile
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from pendulum_lqg.boundary.fields import Invalid, Where, any_text
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.model.interface import ContinuousModel, DiscreteModel, Layout

#: The keys of an LTI plant file.
LTI_KEYS = ("name", "description", "control_period", "A", "B", "C", "G", "Phi", "Gamma",
            "states", "inputs", "W", "Wd", "V", "Q", "R", "N", "force_limit", "observer_poles",
            "x0", "x0_std", "outputs", "state_limits")
#: The built-in designs an LTI plant takes: controllers and observers.
LTI_CONTROLLERS = ("lqr", "dlqr")
LTI_OBSERVERS = ("none", "kalman", "kalman-predictor", "luenberger")
#: Ceiling of each dimension of an LTI plant: states n, inputs m, outputs p and noise inputs q.
#: The designs solve Riccati and Lyapunov equations of size up to 2n (O(n³) work, (2n)² floats),
#: the theory a Lyapunov equation of the 2n-state loop, and the loop keeps n² numbers per episode:
#: far above the benchmark's plants, far below where one design takes minutes.
MAX_LTI_DIMENSION = 100
#: Bytes of one ``.npz`` member once inflated (a 100 × 100 float64 matrix is 80 kB; the ceiling
#: stops a small archive from inflating to gigabytes before its shape is read).
MAX_NPZ_MEMBER_BYTES = 2**20
_TEXT_KEYS = ("name", "description", "states", "inputs", "outputs", "observer_poles")


@dataclass(frozen=True, eq=False)
class LTIPlant:
    """A linear plant from matrices (module docstring); validated when made; a
    :class:`~pendulum_lqg.model.interface.SimulatedPlant`.

    Attributes
    ----------
    A (n, n), B (n, m), C (p, n), G (n, q) : the continuous model, or ``None`` for A, B when the
        plant is given in discrete time (``Phi``, ``Gamma``)
    Phi (n, n), Gamma (n, m) : the discrete model at ``control_period`` (exact ZOH of A, B)
    control_period : T [s]; W (q, q) density of w, or, with ``W_per_period``, the covariance of
        the w of one period; V (p, p) per-sample covariance of v
    Q (n, n), R (m, m), N (n, m) : cost weights of ``∫ xᵀQx + 2xᵀNu + uᵀRu dt``
    input_limits (m,) : saturation of each input (``inf``: none)
    observer_poles : continuous Luenberger poles (n,), or ``None`` for the default
    """

    name: str
    control_period: float
    Phi: np.ndarray
    Gamma: np.ndarray
    C: np.ndarray
    G: np.ndarray
    W: np.ndarray
    V: np.ndarray
    Q: np.ndarray
    R: np.ndarray
    A: np.ndarray | None = None
    B: np.ndarray | None = None
    W_per_period: bool = False
    observer_poles: tuple[complex, ...] | None = None
    states: tuple[str, ...] = ()
    x0: np.ndarray | None = None
    description: str = ""
    path: Path | None = field(default=None, repr=False)
    x0_std: np.ndarray | None = None
    outputs: tuple[str, ...] = ()
    state_limits: np.ndarray | None = None
    N: np.ndarray | None = None
    inputs: tuple[str, ...] = ()
    input_limits: np.ndarray | None = None

    #: What the simulation core asks a plant (:mod:`pendulum_lqg.model.interface`): an LTI plant
    #: is stepped by its own (Φ, Γ) once per control period (no MuJoCo model, no track).
    simulators: ClassVar[tuple[str, ...]] = ("linear-zoh",)
    #: The simulator a scenario of this plant uses unless it says otherwise.
    default_simulator = "linear-zoh"
    #: What the command line calls it.
    kind_label = "LTI plant"
    model = None
    track_limit = math.inf

    @property
    def timestep(self) -> float:
        """The simulation's step: one control period (the plant exists only at T)."""
        return self.control_period

    @property
    def limits_per_input(self) -> np.ndarray:
        """(m,) the saturation of each input (``inf``: none)."""
        m = self.n_inputs
        return np.full(m, math.inf) if self.input_limits is None else self.input_limits

    @property
    def force_limit(self) -> float:
        """The input limit as one number: a plant of one input, or inputs with one limit; else
        the largest (see :attr:`limits_per_input`)."""
        return float(np.max(self.limits_per_input))

    @property
    def u_max(self) -> Any:
        """The limit the core saturates to: a float for one input, (m,) for several."""
        return self.force_limit if self.n_inputs == 1 else self.limits_per_input

    @property
    def n_states(self) -> int:
        return int(self.Phi.shape[0])

    @property
    def n_inputs(self) -> int:
        return int(self.Gamma.shape[1])

    @property
    def n_outputs(self) -> int:
        return int(self.C.shape[0])

    @property
    def state_names(self) -> tuple[str, ...]:
        return self.states or tuple(f"x{i + 1}" for i in range(self.n_states))

    @property
    def input_names(self) -> tuple[str, ...]:
        return self.inputs or tuple(f"u{i + 1}" for i in range(self.n_inputs))

    @property
    def output_names(self) -> tuple[str, ...]:
        return self.outputs or tuple(f"y{i + 1}" for i in range(self.n_outputs))

    @property
    def cross_weight(self) -> np.ndarray:
        """(n, m) the cross term N of the cost (zeros when the file has none)."""
        return np.zeros(self.Gamma.shape) if self.N is None else self.N

    @property
    def discrete(self) -> bool:
        """Given in discrete time (no A, B): only its own (Φ, Γ) exist."""
        return self.A is None

    def transition(self, period: float) -> DiscreteModel | None:
        """``(Φ, Γ)`` of a second route (a MuJoCo plant's ``mjd_transitionFD``); ``None``: the
        matrices are the plant, there is no other route to check them by."""
        return None

    def process_covariance(self) -> np.ndarray:
        """Covariance of the process noise over one period, ``∫₀ᵀ e^{As} G W Gᵀ e^{Aᵀs} ds``
        (Van Loan), or ``G Wd Gᵀ`` for a per-period ``Wd`` (the documents' discrete ``Ψ Rw Ψᵀ``;
        a plant given in discrete time has only that)."""
        from pendulum_lqg import design

        if self.A is None or self.W_per_period:
            return self.G @ self.W @ self.G.T
        return design.process_noise_covariance(self.A, self.G, self.W, self.control_period)

    # ---- the plant interface (pendulum_lqg.model.interface) ---------------------------------
    def layout(self, scenario: Any) -> Layout:
        """Its vectors (:mod:`pendulum_lqg.model.lti_layout`)."""
        from pendulum_lqg.model.lti_layout import lti_layout

        return lti_layout(self, scenario)

    def limits(self, scenario: Any) -> tuple[float, float, Any]:
        """No pole and no track (``inf``): its own ``state_limits`` are the failure rule; the
        file's input limits unless the scenario sets ``force_limit``."""
        return (math.inf, math.inf,
                self.u_max if scenario.force_limit is None else scenario.force_limit)

    def linear_model(self) -> ContinuousModel:
        """``(A, B, C, 0)``; a plant given in discrete time has none (one line naming ``A``)."""
        if self.A is None or self.B is None:
            raise ConfigError(f"A: the LTI plant {self.name!r} is given in discrete time (Phi, "
                              "Gamma); it has no continuous model")
        return ContinuousModel(A=self.A, B=self.B, C=self.C,
                               D=np.zeros((self.n_outputs, self.n_inputs)))

    def sampled(self, period: float, kind: str = "linear-zoh") -> tuple[np.ndarray, np.ndarray]:
        """``(Φ, Γ)`` at ``period``: its own at its control period, else from ``(A, B)``."""
        from pendulum_lqg import design

        if kind == "linear-zoh" and period == self.control_period:
            return self.Phi, self.Gamma
        lin = self.linear_model()
        if kind == "linear-zoh":
            return design.zoh(lin.A, lin.B, period)
        if kind == "linear-euler":
            return design.euler(lin.A, lin.B, period)
        raise ConfigError(f"plant: expected 'linear-zoh' or 'linear-euler', got {kind!r}")

    def fingerprint(self) -> str:
        """SHA-256 of its name, period, matrices, limits and initial state (not the file's path
        or description: the same plant read from a copy has the same fingerprint)."""
        return self.linear_digest().hexdigest()

    def linear_digest(self) -> Any:
        """The running SHA-256 of the fields of an :class:`LTIPlant` (a subclass adds its own)."""
        digest = hashlib.sha256()
        for f in fields(LTIPlant):
            if f.name in ("path", "description"):
                continue
            value = getattr(self, f.name)
            digest.update(f.name.encode())
            if isinstance(value, np.ndarray):
                digest.update(repr(value.shape).encode() + np.ascontiguousarray(
                    value, dtype=float).tobytes())
            else:
                digest.update(repr(value).encode())
        return digest


# ---- the schema: one value at a time --------------------------------------------------------------
def _real(value: Any) -> float:
    """A finite real number (a Python or numpy int or float; not a bool, a string, a complex)."""
    if isinstance(value, bool | np.bool_) or not isinstance(value, int | float | np.integer
                                                             | np.floating):
        raise Invalid("a finite number")
    try:
        real = float(value)
    except OverflowError:                   # an integer beyond any float
        raise Invalid("a finite number") from None
    if not math.isfinite(real):
        raise Invalid("a finite number")
    return real


def _numbers(value: Any) -> np.ndarray:
    """A number, a list of numbers or a list of equally long lists of numbers (or a numeric
    array of at most 2 dimensions) as a float array; every length at most
    :data:`MAX_LTI_DIMENSION`, checked before the items are read."""
    what = (f"numbers: a number, a list or a list of equally long rows (each at most "
            f"{MAX_LTI_DIMENSION} long)")
    if isinstance(value, np.ndarray):
        if value.dtype.kind not in "iuf" or value.ndim > 2 \
                or any(d > MAX_LTI_DIMENSION for d in value.shape):
            raise Invalid(what)
        arr = value.astype(float)
        if not np.all(np.isfinite(arr)):
            raise Invalid("finite numbers")
        return arr
    if not isinstance(value, list | tuple):
        try:
            return np.array(_real(value))
        except Invalid:
            raise Invalid(what) from None
    if len(value) > MAX_LTI_DIMENSION:
        raise Invalid(what)
    if not any(isinstance(v, list | tuple | np.ndarray) for v in value):
        try:
            return np.array([_real(v) for v in value], dtype=float)
        except Invalid:
            raise Invalid(what) from None
    if not all(isinstance(v, list | tuple) and len(v) <= MAX_LTI_DIMENSION for v in value) \
            or len({len(v) for v in value}) > 1:
        raise Invalid(what)
    try:
        return np.array([[_real(c) for c in row] for row in value], dtype=float).reshape(
            len(value), len(value[0]) if value else 0)
    except Invalid:
        raise Invalid(what) from None


def _matrix(where: Where, key: str, value: Any, rows: int | None = None,
            cols: int | None = None) -> np.ndarray:
    """A finite real matrix of ``(rows, cols)`` (``None``: any, 1 … MAX); a flat list is one row
    when ``rows == 1``."""
    arr = where.check(value, _numbers, key)
    if arr.ndim == 1 and rows == 1:
        arr = arr[None, :]
    want = (f"a ({rows if rows is not None else 'r'} × {cols if cols is not None else 'c'}) "
            "matrix (a list of rows of numbers)")
    if arr.ndim != 2:
        raise where.error(f"expected {want}, got {arr.ndim}-d numbers", key)
    if (rows is not None and arr.shape[0] != rows) or (cols is not None and arr.shape[1] != cols) \
            or 0 in arr.shape:
        raise where.error(f"expected {want}, got shape {arr.shape}", key)
    return arr


def _vector(where: Where, key: str, value: Any, n: int) -> np.ndarray:
    arr = where.check(value, _numbers, key)
    if arr.shape != (n,):
        raise where.error(f"expected a list of {n} numbers, got shape {arr.shape}", key)
    return arr


def _covariance(where: Where, key: str, value: Any, n: int, *,
                definite: bool = False) -> np.ndarray:
    """A number (times I), a diagonal (list of n) or an (n, n) matrix, symmetric and positive
    semidefinite (``definite``: positive definite)."""
    arr = where.check(value, _numbers, key)
    kind = "positive definite" if definite else "positive semidefinite"
    if arr.ndim == 0:
        arr = np.full(n, float(arr))
    if arr.ndim == 1:
        if arr.shape != (n,):
            raise where.error(f"expected {n} non-negative numbers (a diagonal) or an ({n} × {n}) "
                              f"matrix, got shape {arr.shape}", key)
        arr = np.diag(arr)
    arr = _matrix(where, key, arr, n, n)
    if not np.allclose(arr, arr.T, rtol=1e-12, atol=1e-12 * max(1.0, float(np.max(np.abs(arr))))):
        raise where.error(f"expected a symmetric {kind} matrix, got an unsymmetric one", key)
    low = float(np.min(np.linalg.eigvalsh(arr)))
    scale = max(1.0, float(np.max(np.abs(arr))))
    if low < -1e-12 * scale or (definite and low <= 1e-14 * scale):
        raise where.error(f"expected a symmetric {kind} matrix, got smallest eigenvalue "
                          f"{low:.3g}", key)
    return arr


def _names(where: Where, key: str, value: Any, count: int) -> tuple[str, ...]:
    """``count`` distinct identifiers (``rms_NAME`` is a metric's column): a state may not be
    called ``u`` nor start with ``est_err_`` (the input's and the estimate's columns)."""
    what = f"a list of {count} distinct names (identifiers: letters, digits, _)"
    if not isinstance(value, list | tuple) or len(value) != count \
            or not all(isinstance(s, str) and s.isidentifier() for s in value):
        raise where.error(f"expected {what}, got {_short(value)}", key)
    seen: set[str] = set()
    for s in value:
        if s in seen:
            raise where.error(f"expected {what}, got {s!r} twice (each name's metrics would "
                              "overwrite the other's)", key)
        seen.add(s)
    if key == "states" and any(s == "u" or s.startswith("est_err_") for s in value):
        raise where.error(f"expected {what} other than 'u' and 'est_err_…' (the input's and the "
                          f"estimate error's metric columns), got {_short(value)}", key)
    return tuple(value)


def _short(value: Any) -> str:
    from pendulum_lqg.boundary.fields import short

    return short(value)


def _limits(where: Where, key: str, value: Any, count: int) -> np.ndarray:
    """``count`` limits, each a positive number or ``inf`` (the string too); one number for all."""
    from pendulum_lqg.problem.declare import positive_limit

    items: Any = value if isinstance(value, list | tuple | np.ndarray) else [value] * count
    what = f"one or {count} limits, each a positive number or inf"
    if isinstance(items, np.ndarray):
        items = items.reshape(-1).tolist() if items.dtype.kind in "iuf" else None
    if items is None or len(items) != count:
        raise where.error(f"expected {what}, got {_short(value)}", key)
    try:
        return np.array([positive_limit(key, v) for v in items])
    except ValueError:
        raise where.error(f"expected {what}, got {_short(value)}", key) from None


def _poles(where: Where, value: Any, n: int) -> tuple[complex, ...]:
    """``n`` continuous observer poles: numbers or ``"a+bj"`` strings, closed under conjugation
    (a real gain places them)."""
    what = f"a list of {n} poles (numbers or 'a+bj' strings, complex ones in conjugate pairs)"
    items = value.reshape(-1).tolist() if isinstance(value, np.ndarray) else value
    if not isinstance(items, list | tuple) or len(items) != n:
        raise where.error(f"expected {what}, got {_short(value)}", "observer_poles")
    poles = []
    for z in items:
        try:
            pole = complex(z.replace(" ", "")) if isinstance(z, str) else complex(_real(z))
        except (ValueError, Invalid):
            raise where.error(f"expected {what}, got {_short(z)}", "observer_poles") from None
        if not (math.isfinite(pole.real) and math.isfinite(pole.imag)):
            raise where.error(f"expected {what}, got {_short(z)}", "observer_poles")
        poles.append(pole)
    arr = np.array(poles)
    if not np.allclose(np.sort_complex(arr), np.sort_complex(arr.conj()), rtol=1e-12, atol=0.0):
        raise where.error(f"expected {what}, got {_short(value)} (not in conjugate pairs)",
                          "observer_poles")
    return tuple(poles)


def _check_keys(where: Where, data: Any) -> None:
    if not isinstance(data, dict):
        raise where.error(f"expected a table of an LTI plant, got {type(data).__name__}")
    unknown = sorted(set(data) - set(LTI_KEYS))
    if unknown:
        raise where.error(f"unknown key {unknown[0]!r}; known keys: " + ", ".join(LTI_KEYS))


# ---- a plant from a table -------------------------------------------------------------------------
def _model(where: Where, data: dict[str, Any]) -> tuple[bool, np.ndarray, np.ndarray]:
    """``(continuous, A or Φ, B or Γ)`` of the table, shapes checked (n, m ≤ MAX)."""
    continuous = "A" in data or "B" in data
    if continuous == ("Phi" in data or "Gamma" in data):
        raise where.error("expected either A and B (continuous) or Phi and Gamma (discrete)")
    key_a, key_b = ("A", "B") if continuous else ("Phi", "Gamma")
    for key in (key_a, key_b):
        if key not in data:
            raise where.error(f"missing ({key_a} and {key_b} go together)", key)
    M = _matrix(where, key_a, data[key_a])
    n = M.shape[0]
    M = _matrix(where, key_a, M, n, n)
    return continuous, M, _matrix(where, key_b, data[key_b], n)


def _weights(where: Where, data: dict[str, Any], C: np.ndarray, m: int,
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """``(Q, R, N)`` of the table: Q ≥ 0 (default CᵀC), R > 0 (default I), the cross term N
    (n, m) with ``[[Q, N], [Nᵀ, R]] ≥ 0`` (the cost of every (x, u) non-negative)."""
    n = C.shape[1]
    Q = _covariance(where, "Q", data["Q"], n) if "Q" in data else C.T @ C
    R = _covariance(where, "R", data.get("R", 1.0), m, definite=True)
    if "N" not in data:
        return Q, R, None
    N = _matrix(where, "N", data["N"], n, m)
    # Q − N R⁻¹ Nᵀ ≥ 0 (the Schur complement) ⇔ the joint weight is positive semidefinite
    schur = Q - N @ np.linalg.solve(R, N.T)
    if float(np.min(np.linalg.eigvalsh((schur + schur.T) / 2))) < -1e-10 * max(
            1.0, float(np.max(np.abs(Q)))):
        raise where.error("expected a cross term with [[Q, N], [Nᵀ, R]] positive semidefinite "
                          "(Q − N R⁻¹ Nᵀ ≥ 0), got one that makes some cost negative", "N")
    return Q, R, N


def lti_from_mapping(data: dict[str, Any], *, name: str = "lti", path: Path | None = None,
                     where: Where | None = None) -> LTIPlant:
    """Validate an LTI plant table (module docstring); every error is one line naming the file
    (``where``, default ``lti``) and the key."""
    from pendulum_lqg import design

    w = where or Where("lti")
    _check_keys(w, data)
    if "control_period" not in data:
        raise w.error("missing", "control_period")
    T = w.check(data["control_period"], _positive, "control_period")
    continuous, M, Bm = _model(w, data)
    n, m = M.shape[0], Bm.shape[1]
    C = _matrix(w, "C", data.get("C", np.eye(n)), None, n)
    G = _matrix(w, "G", data.get("G", np.eye(n)), n)
    p = C.shape[0]
    if "W" in data and "Wd" in data:
        raise w.error("expected W (a density) or Wd (per period), not both", "Wd")
    per_period = "Wd" in data or not continuous
    key_w = "Wd" if "Wd" in data else "W"
    W = _covariance(w, key_w, data.get(key_w, np.zeros(G.shape[1])), G.shape[1])
    V = _covariance(w, "V", data.get("V", np.zeros(p)), p)
    Q, R, N = _weights(w, data, C, m)
    x0 = None if "x0" not in data else _vector(w, "x0", data["x0"], n)
    x0_std = None if "x0_std" not in data else _vector(w, "x0_std", data["x0_std"], n)
    if x0_std is not None and np.any(x0_std < 0):
        raise w.error(f"expected {n} non-negative numbers, got {_short(data['x0_std'])}",
                      "x0_std")
    text = {key: w.get(data, key, any_text, default="") for key in ("name", "description")}
    Phi, Gamma = design.zoh(M, Bm, T) if continuous else (M, Bm)
    plant = LTIPlant(
        name=text["name"] or name, description=text["description"],
        control_period=T, Phi=Phi, Gamma=Gamma, C=C, G=G, W=W, V=V, Q=Q, R=R, N=N,
        A=M if continuous else None, B=Bm if continuous else None,
        input_limits=_limits(w, "force_limit", data.get("force_limit", math.inf), m),
        W_per_period=per_period,
        observer_poles=(None if "observer_poles" not in data
                        else _poles(w, data["observer_poles"], n)),
        states=_names(w, "states", data["states"], n) if "states" in data else (),
        inputs=_names(w, "inputs", data["inputs"], m) if "inputs" in data else (),
        outputs=_names(w, "outputs", data["outputs"], p) if "outputs" in data else (),
        x0=x0, path=path, x0_std=x0_std,
        state_limits=(_limits(w, "state_limits", data["state_limits"], n)
                      if "state_limits" in data else None))
    shared = sorted(set(plant.state_names) & set(plant.input_names)) if m > 1 else []
    if shared:              # several inputs' metrics are rms_NAME, as the states'
        raise w.error(f"expected names other than the states', got {shared[0]!r} for both a "
                      "state and an input", "inputs")
    return plant


def _positive(value: Any) -> float:
    try:
        real = _real(value)
    except Invalid:
        real = 0.0
    if real <= 0:
        raise Invalid("a finite positive number")
    return real


# ---- files ----------------------------------------------------------------------------------------
def load_lti(path: str | Path) -> LTIPlant:
    """Read an LTI plant from a TOML file or an ``.npz`` archive (module docstring) through the
    file boundary; a relative path not found in the current folder is looked up among the shipped
    files (:func:`~pendulum_lqg.util.resources.find_file`:
    ``experiments/lti/double_integrator.toml`` works from an installed package). A plant file of a
    MuJoCo model (a ``model`` key) is read by :func:`pendulum_lqg.model.catalog.load_plant_at`."""
    resolved, data, where = read_plant_data(path)
    return lti_from_mapping(data, name=resolved.name.split(".")[0], path=resolved, where=where)


def read_plant_data(path: str | Path) -> tuple[Path, dict[str, Any], Where]:
    """``(resolved path, its mapping, its error prefix)`` of the plant file ``path``: TOML or
    ``.npz`` through the file boundary, a relative path not found here looked up among the
    shipped files."""
    from pendulum_lqg.boundary import read_toml
    from pendulum_lqg.util.resources import find_file

    given = Path(path)
    resolved = given if given.is_file() else find_file(given)
    where = Where(f"lti: {given}")
    data = _read_npz(resolved, where) if resolved.suffix == ".npz" else read_toml(
        resolved, where="lti")
    return resolved, data, where


def _read_npz(path: Path, where: Where) -> dict[str, Any]:
    """The members of the ``.npz`` archive ``path`` (read whole within the boundary's ceiling),
    each checked from its header before it is inflated: a known key, numeric (text only for the
    names), at most 2-d, every dimension at most :data:`MAX_LTI_DIMENSION`."""
    from pendulum_lqg.boundary import read_bytes

    raw = read_bytes(path, where="lti")
    try:
        archive = zipfile.ZipFile(io.BytesIO(raw))
        infos = archive.infolist()
    except (zipfile.BadZipFile, zipfile.LargeZipFile, ValueError, OSError) as exc:
        raise where.error(f"expected an .npz archive (numpy.savez), got an unreadable file "
                          f"({' '.join(str(exc).split())})") from None
    out: dict[str, Any] = {}
    for info in infos:
        key = info.filename.removesuffix(".npy")
        _check_keys(where, {key: None})
        if info.file_size > MAX_NPZ_MEMBER_BYTES:
            raise where.error(f"expected a member of at most {MAX_NPZ_MEMBER_BYTES:,} bytes, got "
                              f"{info.file_size:,}", key)
        try:
            out[key] = _npz_member(archive, info, key)
        except Invalid as exc:
            raise where.error(f"expected {exc.expected}", key) from None
        except (ValueError, OSError, EOFError, zipfile.BadZipFile, NotImplementedError) as exc:
            raise where.error(f"expected a .npy array, got an unreadable member "
                              f"({' '.join(str(exc).split())[:80]})", key) from None
    return out


def _npz_member(archive: zipfile.ZipFile, info: zipfile.ZipInfo, key: str) -> Any:
    """One member: its header read first (dtype, shape), the array only if they pass."""
    fmt = np.lib.format
    with archive.open(info) as f:
        version = fmt.read_magic(f)
        header = fmt.read_array_header_1_0 if version == (1, 0) else fmt.read_array_header_2_0
        shape, _, dtype = header(f)
    text = key in _TEXT_KEYS and dtype.kind == "U"
    if dtype.kind not in "iuf" and not text:
        raise Invalid("a numeric array" + (" or text" if key in _TEXT_KEYS else "")
                      + f", got dtype {dtype.str}")
    if len(shape) > 2 or any(d > MAX_LTI_DIMENSION for d in shape):
        raise Invalid(f"at most 2 dimensions of at most {MAX_LTI_DIMENSION}, got shape {shape}")
    with archive.open(info) as f:
        arr = fmt.read_array(f, allow_pickle=False)
    if text:
        return str(arr.item()) if arr.ndim == 0 else [str(s) for s in arr.reshape(-1)]
    return arr.item() if arr.ndim == 0 else arr
