r"""Any linear plant given as matrices: ``ẋ = A x + B u + G w``, ``y = C x + v``, sampled at T.

A separate, explicit kind of plant beside the MuJoCo cart-pole (whose MJCF model stays the one
source of truth of the cart-pole): the documents' double integrator, Franklin's third-order plant
and Ogata's discrete example are files in ``experiments/lti/``, read by
:func:`load_lti` from TOML or ``.npz``. An :class:`LTIPlant` carries its own noise (the density W
of w, the per-sample covariance V of v), cost weights and force limit; its designs, scenario and
stationary closed loop are :mod:`pendulum_lqg.policies.lti`'s.

A TOML file::

    name = "double_integrator"
    description = "…"
    control_period = 0.1          # T [s]
    A = [[0, 1], [0, 0]]          # or, for a plant given in discrete time: Phi, Gamma
    B = [[0], [1]]
    C = [[1, 0]]
    G = [[1, 0], [0, 1]]          # optional, default I: where w enters
    states = ["position", "velocity"]       # optional names
    W = [1, 1]                    # density of w (diagonal or matrix), units²·s; or Wd, the
                                  # per-period covariance of w (the documents' discrete Rw)
    V = [1]                       # per-sample covariance of v (diagonal or matrix)
    Q = [[1, 0], [0, 0]]          # optional cost weights (default CᵀC, R = 1)
    R = 1
    force_limit = inf             # optional saturation [input unit] (default inf)
    observer_poles = [-2, -3]     # optional continuous Luenberger poles (default 3× the
                                  # controller's, the documents' rule of thumb)
    outputs = ["position"]        # optional names of y (default y1, y2, …)
    x0 = [1, 0]                   # optional mean initial state (default 0) and its std
    x0_std = [0, 0]               # (default 0), drawn per episode by ``run`` and ``bench``
    state_limits = [inf, inf]     # optional failure limits |x_i| ≤ limit_i (default: none, only
                                  # divergence ends an episode)

An ``.npz`` holds the same names as arrays (``control_period`` a 0-d array).
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.util.config import check_keys, positive_limit, positive_number

#: The keys of an LTI plant file.
LTI_KEYS = ("name", "description", "control_period", "A", "B", "C", "G", "Phi", "Gamma",
            "states", "W", "Wd", "V", "Q", "R", "force_limit", "observer_poles", "x0",
            "x0_std", "outputs", "state_limits")
#: The built-in designs an LTI plant takes: controllers and observers.
LTI_CONTROLLERS = ("lqr", "dlqr")
LTI_OBSERVERS = ("none", "kalman", "kalman-predictor", "luenberger")


@dataclass(frozen=True, eq=False)
class LTIPlant:
    """A linear plant from matrices (module docstring); validated when made.

    Attributes
    ----------
    A (n, n), B (n, m), C (p, n), G (n, q) : the continuous model, or ``None`` for A, B when the
        plant is given in discrete time (``Phi``, ``Gamma``)
    Phi (n, n), Gamma (n, m) : the discrete model at ``control_period`` (exact ZOH of A, B)
    control_period : T [s]; W (q, q) density of w, or, with ``W_per_period``, the covariance of
        the w of one period; V (p, p) per-sample covariance of v
    Q (n, n), R (m, m) : cost weights; force_limit : saturation (``inf``: none)
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
    force_limit: float = math.inf
    W_per_period: bool = False
    observer_poles: tuple[complex, ...] | None = None
    states: tuple[str, ...] = ()
    x0: np.ndarray | None = None
    description: str = ""
    path: Path | None = field(default=None, repr=False)
    x0_std: np.ndarray | None = None
    outputs: tuple[str, ...] = ()
    state_limits: np.ndarray | None = None

    #: What the simulation core asks a plant (:func:`pendulum_lqg.core.layout.layout`): an LTI
    #: plant is stepped by its own (Φ, Γ) once per control period (no MuJoCo model, no track).
    is_lti = True
    model = None
    track_limit = math.inf

    @property
    def timestep(self) -> float:
        """The simulation's step: one control period (the plant exists only at T)."""
        return self.control_period

    @property
    def u_max(self) -> float:
        return self.force_limit

    @property
    def output_names(self) -> tuple[str, ...]:
        return self.outputs or tuple(f"y{i + 1}" for i in range(self.C.shape[0]))

    @property
    def n_states(self) -> int:
        return int(self.Phi.shape[0])

    @property
    def state_names(self) -> tuple[str, ...]:
        return self.states or tuple(f"x{i + 1}" for i in range(self.n_states))

    @property
    def discrete(self) -> bool:
        """Given in discrete time (no A, B): only its own (Φ, Γ) exist."""
        return self.A is None

    def process_covariance(self) -> np.ndarray:
        """Covariance of the process noise over one period, ``∫₀ᵀ e^{As} G W Gᵀ e^{Aᵀs} ds``
        (Van Loan), or ``G Wd Gᵀ`` for a per-period ``Wd`` (the documents' discrete ``Ψ Rw Ψᵀ``;
        a plant given in discrete time has only that)."""
        from pendulum_lqg import design

        if self.A is None or self.W_per_period:
            return self.G @ self.W @ self.G.T
        return design.process_noise_covariance(self.A, self.G, self.W, self.control_period)


def _matrix(where: str, value: Any, rows: int | None = None, cols: int | None = None) -> np.ndarray:
    """A finite real matrix; a flat list is a row for ``C``-like keys only through ``rows``."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ConfigError(f"{where}: expected a matrix of numbers, got {value!r}") from None
    if arr.ndim == 1 and rows == 1:
        arr = arr[None, :]
    if arr.ndim != 2 or not np.all(np.isfinite(arr)):
        raise ConfigError(f"{where}: expected a finite 2-d matrix (a list of rows), got {value!r}")
    if (rows is not None and arr.shape[0] != rows) or (cols is not None and arr.shape[1] != cols):
        want = f"({rows if rows is not None else 'any'}, {cols if cols is not None else 'any'})"
        raise ConfigError(f"{where}: expected shape {want}, found {arr.shape}")
    return arr


def _covariance(where: str, value: Any, n: int) -> np.ndarray:
    """A diagonal (list of n) or an (n, n) symmetric positive semidefinite matrix."""
    arr = np.asarray(value, dtype=float) if not isinstance(value, int | float) else \
        np.full(n, float(value))
    if arr.ndim == 1:
        if arr.shape != (n,) or np.any(arr < 0) or not np.all(np.isfinite(arr)):
            raise ConfigError(f"{where}: expected {n} finite non-negative numbers (a diagonal) or "
                              f"an ({n}, {n}) matrix, got {value!r}")
        return np.diag(arr)
    arr = _matrix(where, arr, n, n)
    if not np.allclose(arr, arr.T) or np.min(np.linalg.eigvalsh(arr)) < -1e-12:
        raise ConfigError(f"{where}: expected a symmetric positive semidefinite matrix")
    return arr


def lti_from_mapping(data: dict[str, Any], *, name: str = "lti", path: Path | None = None,
                     ) -> LTIPlant:
    """Validate an LTI plant table (module docstring); every error names the key."""
    from pendulum_lqg import design

    check_keys("lti", data, LTI_KEYS)
    T = positive_number("control_period", data.get("control_period"))
    continuous = "A" in data or "B" in data
    if continuous == ("Phi" in data or "Gamma" in data):
        raise ConfigError("lti: give either A and B (continuous) or Phi and Gamma (discrete)")
    key_a, key_b = ("A", "B") if continuous else ("Phi", "Gamma")
    if key_a not in data or key_b not in data:
        raise ConfigError(f"lti: {key_a} and {key_b} are required together")
    M = _matrix(key_a, data[key_a])
    n = M.shape[0]
    M = _matrix(key_a, M, n, n)
    Bm = _matrix(key_b, data[key_b], n)
    C = _matrix("C", data.get("C", np.eye(n)), None, n)
    G = _matrix("G", data.get("G", np.eye(n)), n)
    p, m = C.shape[0], Bm.shape[1]
    if "W" in data and "Wd" in data:
        raise ConfigError("lti: give W (a density) or Wd (per period), not both")
    per_period = "Wd" in data or not continuous
    W = _covariance("Wd" if "Wd" in data else "W", data.get("Wd", data.get("W",
                                                                            np.zeros(G.shape[1]))),
                    G.shape[1])
    V = _covariance("V", data.get("V", np.zeros(p)), p)
    Q = _covariance("Q", data["Q"], n) if "Q" in data else C.T @ C
    R = _covariance("R", data.get("R", 1.0), m)
    if np.min(np.linalg.eigvalsh(R)) <= 0:
        raise ConfigError("R: expected a positive definite input weight")
    Phi, Gamma = design.zoh(M, Bm, T) if continuous else (M, Bm)
    poles = data.get("observer_poles")
    states = tuple(str(s) for s in data.get("states", ()))
    if states and len(states) != n:
        raise ConfigError(f"states: expected {n} names, got {len(states)}")
    x0 = None if "x0" not in data else _matrix("x0", data["x0"], 1, n)[0]
    x0_std = None if "x0_std" not in data else _matrix("x0_std", data["x0_std"], 1, n)[0]
    if x0_std is not None and np.any(x0_std < 0):
        raise ConfigError(f"x0_std: expected {n} non-negative numbers, got {data['x0_std']!r}")
    outputs = tuple(str(s) for s in data.get("outputs", ()))
    if outputs and len(outputs) != p:
        raise ConfigError(f"outputs: expected {p} names, got {len(outputs)}")
    state_limits = None
    if "state_limits" in data:
        raw = np.atleast_1d(np.asarray(data["state_limits"], dtype=object))
        if raw.shape != (n,):
            raise ConfigError(f"state_limits: expected {n} limits (inf: none), got "
                              f"{data['state_limits']!r}")
        state_limits = np.array([positive_limit("state_limits", v) for v in raw.tolist()])
    return LTIPlant(
        name=str(data.get("name", name)), description=str(data.get("description", "")),
        control_period=T, Phi=Phi, Gamma=Gamma, C=C, G=G, W=W, V=V, Q=Q, R=R,
        A=M if continuous else None, B=Bm if continuous else None,
        force_limit=positive_limit("force_limit", data.get("force_limit", math.inf)),
        W_per_period=per_period,
        observer_poles=None if poles is None else tuple(complex(z) for z in
                                                        np.atleast_1d(poles).tolist()),
        states=states, x0=x0, path=path, x0_std=x0_std, outputs=outputs,
        state_limits=state_limits)


def load_lti(path: str | Path) -> LTIPlant:
    """Read an LTI plant from a TOML file or an ``.npz`` archive (module docstring); a relative
    path not found in the current folder is looked up among the shipped files
    (:func:`~pendulum_lqg.util.resources.find_file`: ``experiments/lti/double_integrator.toml``
    works from an installed package)."""
    from pendulum_lqg.util.resources import find_file

    given = Path(path)
    path = given if given.is_file() else find_file(given)
    if not path.is_file():
        raise ConfigError(f"lti: no file {str(given)!r}")
    try:
        if path.suffix == ".npz":
            with np.load(path, allow_pickle=False) as npz:
                data: dict[str, Any] = {k: npz[k] for k in npz.files}
            data = {k: (v.item() if v.ndim == 0 else v.tolist()) for k, v in data.items()}
        else:
            data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError, ValueError, OSError) as exc:
        raise ConfigError(f"lti: cannot read {path}: {' '.join(str(exc).split())}") from exc
    try:
        return lti_from_mapping(data, name=path.name.split(".")[0], path=path)
    except ConfigError as exc:
        raise ConfigError(f"{exc} (in {path})") from exc
