"""Any MuJoCo model as a plant: a plant file (TOML) that points at an MJCF model.

A plant file has the keys of a matrix plant's file (:mod:`pendulum_lqg.model.lti`) except that
``model = "x.xml"`` (relative to the file) replaces ``A``, ``B``, ``G``, ``C`` and ``Phi``/``Gamma``::

    name = "double_cartpole"
    description = "…"
    model = "double_cartpole.xml"       # the MJCF: every physical parameter
    equilibrium = "upright"             # a keyframe's name (default the model's qpos0)
    control_period = 0.01               # T [s], a whole number of physics steps
    outputs = ["cart_position", "angle_1", "angle_2"]   # MJCF sensors (jointpos / jointvel)
    W = [0, 0, 0, 1e-4, 1e-4, 1e-4]     # process-noise density on the state, units²·s (n or n×n)
    V = [1e-4, 1e-4, 1e-4]              # per-sample measurement-noise covariance (p or p×p)
    Q = [1, 1, 1, 1, 1, 1]              # cost weights (default CᵀC), R (default 1), N
    x0 = [0, 0.01, 0, 0, 0, 0]          # optional mean initial state and its std (default 0)
    state_limits = [1.8, 0.5, 0.5, inf, inf, inf]   # default: the joints' ranges
    force_limit = 10                    # default: gear · ctrlrange; never more

The state is ``x = [q − q*, q̇]`` over the model's joints in their order (hinge and slide joints;
free and ball joints, whose qpos are quaternions, are refused), the inputs are the actuators in
physical units (``u = gear · ctrl``: a force in N or a torque in N·m), the outputs the named
sensors. The linearisation (:mod:`pendulum_lqg.model.mjcf_linear`) about the equilibrium makes the
plant's matrix model — every design, the theory and the linear simulators use it, as for a
matrix plant — and MuJoCo simulates the nonlinear model with the same noise, rules and metrics.

Every error is one line ``plant: FILE: KEY: expected …, got …``.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any, ClassVar

import mujoco
import numpy as np

from pendulum_lqg.boundary.fields import Where
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.model.interface import DiscreteModel, Layout, steps_per_period
from pendulum_lqg.model.lti import LTI_KEYS, LTIPlant, lti_from_mapping
from pendulum_lqg.model.mjcf_linear import JointMap, continuous_model, residual, transition_model

#: The keys of a plant file: a matrix plant's, with the model in place of its matrices.
PLANT_FILE_KEYS = (*(k for k in LTI_KEYS if k not in ("A", "B", "C", "G", "Phi", "Gamma", "Wd")),
                   "model", "equilibrium")
#: Largest ``max |q̈|`` at the equilibrium [unit/s²] (finite differences of a true equilibrium
#: leave round-off only).
EQUILIBRIUM_TOLERANCE = 1e-8


@dataclass(frozen=True, eq=False)
class MjcfPlant(LTIPlant):
    """A MuJoCo model as a plant (module docstring): its linearisation (the
    :class:`~pendulum_lqg.model.lti.LTIPlant` fields, which the designs and the theory read) and
    the model MuJoCo simulates. Make one with :func:`load_plant_file`.

    Attributes
    ----------
    model : the compiled ``MjModel``; mjcf : its file
    joints : where the state lives in qpos/qvel, the equilibrium, the sensors and the gears
    """

    model: Any = field(default=None, repr=False)
    mjcf: Path | None = None
    joints: Any = field(default=None, repr=False)
    equilibrium: str = ""

    #: MuJoCo itself, or the linearisation stepped in numpy.
    simulators: ClassVar[tuple[str, ...]] = ("mujoco", "linear-zoh", "linear-euler")
    #: The simulator a scenario of this plant uses unless it says otherwise.
    default_simulator = "mujoco"
    kind_label = "MuJoCo plant"

    @property
    def timestep(self) -> float:
        """MuJoCo's physics step h [s] (the control period is k·h)."""
        return float(self.model.opt.timestep)

    @property
    def qpos_index(self) -> np.ndarray:
        return self.joints.qpos_index

    @property
    def qvel_index(self) -> np.ndarray:
        return self.joints.qvel_index

    @property
    def x_offset(self) -> np.ndarray | None:
        """``[q*, 0]``: what the physics adds to x for MuJoCo's qpos (``None`` at q* = 0)."""
        eq = self.joints.qpos_eq
        return None if not np.any(eq) else np.concatenate([eq, np.zeros(len(eq))])

    @property
    def ctrl_gear(self) -> float:
        """The one actuator's gear: MuJoCo's ctrl is ``u / gear``."""
        return float(self.joints.gear[0])

    def layout(self, scenario: Any) -> Layout:
        """Its vectors (:func:`~pendulum_lqg.model.lti_layout.lti_layout`), refusing what
        MuJoCo's loop of this plant cannot run, one line naming the key."""
        from pendulum_lqg.model.lti_layout import lti_layout

        if scenario.plant == "mujoco":
            if scenario.noise.process != "state":
                raise ConfigError(f"noise: process noise on the state (process = 'state') for "
                                  f"the plant {self.name!r}; its W is a density on the state")
        if not scenario.randomize.is_empty():
            raise ConfigError(f"randomize: per-episode models scale the cart-pole's masses and "
                              f"length; not for the plant {self.name!r}")
        return lti_layout(self, scenario)

    def limits(self, scenario: Any) -> tuple[float, float, Any]:
        """No pole and no track (its ``state_limits`` are the failure rule); the input limit is
        the file's unless the scenario sets ``force_limit``, on MuJoCo no wider than
        ``gear · ctrlrange`` (MuJoCo clamps the control there)."""
        u_max = self.u_max if scenario.force_limit is None else scenario.force_limit
        if scenario.plant == "mujoco" and scenario.force_limit is not None:
            model_limit = float(np.min(self.model_limits))
            if scenario.force_limit > model_limit:
                raise ConfigError(f"force_limit: {scenario.force_limit:g} is beyond the MuJoCo "
                                  f"model's gear · ctrlrange ±{model_limit:g}; use a linear "
                                  f"simulator (plant = 'linear-zoh') or a wider ctrlrange")
        return math.inf, math.inf, u_max

    @property
    def model_limits(self) -> np.ndarray:
        """(m,) ``gear · ctrlrange`` of each actuator (``inf`` for an unlimited one)."""
        return actuator_limits(self.model)

    def transition(self, period: float) -> DiscreteModel:
        """``(Φ, Γ)`` at ``period`` by MuJoCo's ``mjd_transitionFD`` over its k physics steps:
        the check of the ZOH of ``(A, B)`` (they differ by the integrator's O(h))."""
        k = steps_per_period(self, period)
        Phi, Gamma = transition_model(self.model, self.joints, k)
        return DiscreteModel(Phi=Phi, Gamma=Gamma, C=self.C, dt=k * self.timestep,
                             method="mjd_transitionFD")

    def varied(self, scales: dict[str, float]) -> Any:
        """Refused: the scales are the cart-pole's masses and length (:meth:`layout` refuses a
        randomised scenario first)."""
        raise ConfigError(f"randomize: per-episode models scale the cart-pole's masses and "
                          f"length; not for the plant {self.name!r}")

    def fingerprint(self) -> str:
        """SHA-256 of the linear model's fields, the MJCF file's bytes and the equilibrium."""
        digest = self.linear_digest()
        assert self.mjcf is not None
        digest.update(hashlib.sha256(self.mjcf.read_bytes()).digest())
        digest.update(np.ascontiguousarray(self.joints.qpos_eq, dtype=float).tobytes())
        return digest.hexdigest()


def actuator_limits(model: mujoco.MjModel) -> np.ndarray:
    """(nu,) ``gear · max(|ctrlrange|)`` of each actuator, ``inf`` where not ctrllimited."""
    out = np.full(model.nu, math.inf)
    for a in range(model.nu):
        if model.actuator_ctrllimited[a]:
            out[a] = float(model.actuator_gear[a, 0]) * float(np.max(np.abs(
                model.actuator_ctrlrange[a])))
    return out


def _identifier(name: str, fallback: str) -> str:
    """A metric-column name from an MJCF name (non-identifier characters become ``_``)."""
    text = "".join(c if c.isalnum() or c == "_" else "_" for c in name) or fallback
    return text if text.isidentifier() else f"{fallback}_{text}"


def _compile(w: Where, path: Path) -> mujoco.MjModel:
    if not path.is_file():
        raise w.error(f"expected an MJCF file, got {str(path)!r}: no such file", "model")
    try:
        return mujoco.MjModel.from_xml_path(str(path))
    except Exception as exc:  # MuJoCo raises ValueError with the parser's message
        raise w.error(f"cannot compile {path.name}: {' '.join(str(exc).split())}",
                      "model") from None


def _check_model(w: Where, model: mujoco.MjModel, name: str) -> None:
    """What the plant's loop needs of the model, one line each."""
    jt = mujoco.mjtJoint
    if int(model.opt.integrator) == int(mujoco.mjtIntegrator.mjINT_RK4):
        raise w.error(f"{name}: the RK4 integrator is not supported (mjd_transitionFD refuses "
                      f"it); use Euler or implicitfast", "model")
    if model.nu == 0:
        raise w.error(f"{name}: expected at least one actuator (the plant's input), found none",
                      "model")
    if model.nu > 1:
        raise w.error(f"{name}: expected one actuator (MuJoCo's loop takes one input), found "
                      f"{model.nu}", "model")
    if model.na:
        raise w.error(f"{name}: expected actuators without activation dynamics (dyntype none), "
                      f"found {model.na} activation states", "model")
    for j in range(model.njnt):
        if int(model.jnt_type[j]) not in (int(jt.mjJNT_HINGE), int(jt.mjJNT_SLIDE)):
            kind = "free" if int(model.jnt_type[j]) == int(jt.mjJNT_FREE) else "ball"
            raise w.error(f"{name}: joint {model.joint(j).name or j!r} is a {kind} joint (its "
                          f"qpos is a quaternion); the plant takes hinge and slide joints",
                          "model")
    for a in range(model.nu):
        act = model.actuator(a)
        if int(act.trntype[0]) != int(mujoco.mjtTrn.mjTRN_JOINT):
            raise w.error(f"{name}: actuator {act.name or a!r} must act on a joint", "model")
        gear = float(act.gear[0])
        if not (math.isfinite(gear) and gear > 0):
            raise w.error(f"{name}: actuator {act.name or a!r} needs a positive gear, found "
                          f"{gear:g}", "model")
        lo, hi = act.ctrlrange
        if model.actuator_ctrllimited[a] and not (lo < 0 < hi and abs(lo + hi) <= 1e-9 * hi):
            raise w.error(f"{name}: actuator {act.name or a!r} needs a symmetric ctrlrange "
                          f"around 0, found [{lo:g}, {hi:g}]", "model")
    h = float(model.opt.timestep)
    if not (math.isfinite(h) and h > 0):
        raise w.error(f"{name}: <option timestep> must be a finite positive number, found {h!r}",
                      "model")


def _equilibrium(w: Where, model: mujoco.MjModel, data: dict[str, Any]) -> tuple[str, np.ndarray]:
    """The keyframe named by ``equilibrium`` (its qpos), or the model's qpos0."""
    if "equilibrium" not in data:
        return "", np.array(model.qpos0)
    key = data["equilibrium"]
    kid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, key) if isinstance(key, str) else -1
    if kid < 0:
        keys = [model.key(i).name for i in range(model.nkey)]
        known = ", ".join(keys) or "it has none"
        raise w.error(f"expected the name of a keyframe of the model ({known}), got {key!r}",
                      "equilibrium")
    return key, np.array(model.key_qpos[kid])


def _sensors(w: Where, model: mujoco.MjModel, names: Any, mjcf: str) -> np.ndarray:
    """The sensordata addresses of the outputs: jointpos / jointvel sensors (linear in x)."""
    if not isinstance(names, list) or not names or not all(isinstance(s, str) for s in names):
        raise w.error(f"expected a list of sensor names of {mjcf}, got {names!r}", "outputs")
    st = mujoco.mjtSensor
    out = []
    for s in names:
        sid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SENSOR, s)
        if sid < 0:
            known = [model.sensor(i).name for i in range(model.nsensor)]
            raise w.error(f"sensor {s!r} not found in {mjcf} (its sensors: "
                          f"{', '.join(known) or 'none'})", "outputs")
        if int(model.sensor_type[sid]) not in (int(st.mjSENS_JOINTPOS), int(st.mjSENS_JOINTVEL)):
            raise w.error(f"sensor {s!r}: expected a jointpos or jointvel sensor (y linear in "
                          f"the state)", "outputs")
        out.append(int(model.sensor_adr[sid]))
    return np.array(out)


def load_plant_file(path: str | Path, data: dict[str, Any] | None = None) -> MjcfPlant:
    """Read a plant file (module docstring); ``data``: its table, already read."""
    from pendulum_lqg.boundary import read_toml

    path = Path(path)
    w = Where(f"plant: {path}")
    if data is None:
        data = read_toml(path, where="plant")
    if not isinstance(data, dict):
        raise w.error("expected a table")
    unknown = sorted(set(data) - set(PLANT_FILE_KEYS))
    if unknown:
        raise w.error(f"unknown key {unknown[0]!r}; known keys: " + ", ".join(PLANT_FILE_KEYS))
    if not isinstance(data.get("model"), str) or not data["model"].strip():
        raise w.error("expected the path of an MJCF file (relative to the plant file)", "model")
    mjcf = (path.parent / data["model"]).resolve()
    model = _compile(w, mjcf)
    _check_model(w, model, mjcf.name)
    key, qpos = _equilibrium(w, model, data)
    jt = list(range(model.njnt))
    joints = JointMap(qpos_index=np.array([model.jnt_qposadr[j] for j in jt]),
                      qvel_index=np.array([model.jnt_dofadr[j] for j in jt]),
                      qpos_eq=qpos[[model.jnt_qposadr[j] for j in jt]],
                      sensor_index=_sensors(w, model, data.get("outputs"), mjcf.name),
                      gear=np.array(model.actuator_gear[:, 0], dtype=float))
    res = residual(model, joints)
    if not res <= EQUILIBRIUM_TOLERANCE:
        where = f"keyframe {key!r}" if key else "qpos0"
        raise w.error(f"the model's {where} is no equilibrium: max |q̈| = {res:.3g} at zero "
                      f"input and velocity (at most {EQUILIBRIUM_TOLERANCE:g})", "equilibrium")
    A, B, C = continuous_model(model, joints)
    names = [_identifier(model.joint(j).name, f"q{j + 1}") for j in jt]
    table = {k: v for k, v in data.items() if k not in ("model", "equilibrium")}
    table.update(A=A, B=B, C=C, outputs=[_identifier(s, f"y{i + 1}") for i, s in
                                         enumerate(data["outputs"])])
    table.setdefault("states", names + [f"{s}_dot" for s in names])
    table.setdefault("inputs", [_identifier(model.actuator(a).name, f"u{a + 1}")
                                for a in range(model.nu)])
    table.setdefault("control_period", 0.01)
    limits = actuator_limits(model)
    table.setdefault("force_limit", [float(v) for v in limits])
    table.setdefault("state_limits", _joint_limits(model, joints) + [math.inf] * len(jt))
    lin = lti_from_mapping(table, name=path.name.split(".")[0], path=path, where=w)
    if np.any(lin.limits_per_input > limits * (1 + 1e-12)):
        raise w.error(f"expected at most the model's gear · ctrlrange {limits.tolist()}, got "
                      f"{lin.limits_per_input.tolist()}", "force_limit")
    k = round(lin.control_period / float(model.opt.timestep))
    if k < 1 or abs(k * model.opt.timestep - lin.control_period) > 1e-9 * lin.control_period:
        raise w.error(f"expected a whole number of physics steps of {model.opt.timestep:g} s, "
                      f"got {lin.control_period:g} s", "control_period")
    _check_structure(w, lin)
    return MjcfPlant(**{f.name: getattr(lin, f.name) for f in fields(LTIPlant)}, model=model,
                     mjcf=mjcf, joints=joints, equilibrium=key)


def _joint_limits(model: mujoco.MjModel, joints: JointMap) -> list[float]:
    """Each joint's distance from the equilibrium to its nearer range end (``inf``: no range)."""
    out = []
    for j, q in zip(range(model.njnt), joints.qpos_eq, strict=True):
        lo, hi = model.jnt_range[j]
        out.append(float(min(q - lo, hi - q)) if model.jnt_limited[j] else math.inf)
    return out


def _check_structure(w: Where, plant: LTIPlant) -> None:
    """Refuse a linearisation LQG cannot stabilise: an unstable mode (Re λ ≥ 0) that the input
    cannot move or the outputs cannot see, named by λ and its largest state."""
    from pendulum_lqg.design.structure import pbh_rank_deficient

    assert plant.A is not None and plant.B is not None
    A = plant.A
    names = plant.state_names
    for what, failed, modes, key in (
            ("uncontrollable", "stabilisable", pbh_rank_deficient(A, plant.B), "model"),
            ("unobservable", "detectable", pbh_rank_deficient(A.T, plant.C.T), "outputs")):
        for lam in modes:
            if np.real(lam) < -1e-9:
                continue
            vals, vecs = np.linalg.eig(A)
            i = int(np.argmin(np.abs(vals - lam)))
            state = names[int(np.argmax(np.abs(vecs[:, i])))]
            raise w.error(f"the linearisation is not {failed}: its mode λ = {complex(lam):.4g} "
                          f"(mostly {state}) is {what}", key)
