"""The MuJoCo cart-pole: loading (with overrides), named read-outs, and the state vector.

The MJCF file ``models/cartpole.xml`` is the one source of truth for physical parameters. This module
reads masses, lengths, limits and the timestep from the compiled model and never repeats them.

State convention (used everywhere in the project): ``x = [p, θ, ṗ, θ̇]`` — cart position (m), pole
angle from upright (rad, positive tips the pole towards +x), and their rates. Input ``u`` is the
horizontal force on the cart in newtons; measurement ``y = [p, θ]``.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import msgspec
import mujoco
import numpy as np

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.model.interface import ContinuousModel, DiscreteModel, Layout
from pendulum_lqg.model.overrides import ModelOverrides, Randomization
from pendulum_lqg.problem import defaults

STATE_NAMES: tuple[str, ...] = ("p", "theta", "p_dot", "theta_dot")
OUTPUT_NAMES: tuple[str, ...] = ("p", "theta")

#: Names of MJCF elements the code relies on (the XML defines them; these are look-up keys).
SLIDER, HINGE, ACTUATOR = "slider", "hinge", "force"
CART_BODY, POLE_BODY, CART_GEOM, POLE_GEOM, POLE_TIP = "cart", "pole", "cart", "pole", "pole_tip"
SENSORS = ("cart_position", "pole_angle")

#: The cart-pole's layout (with the default scenario's initial state and weights): metrics of p
#: and θ (θ's columns first), the settling time of θ, ``y = [p, θ]``.
CARTPOLE = Layout(states=STATE_NAMES, outputs=OUTPUT_NAMES, x0=np.array(defaults.X0),
                  x0_std=np.array(defaults.X0_STD), C=None, cost_Q=defaults.COST_Q,
                  cost_R=defaults.COST_R, state_limits=None, covariances=None, reported=2,
                  order=(1, 0), settle=1)


def default_model_path() -> Path:
    """Path of the bundled ``cartpole.xml`` (the checkout's ``models/`` or the installed copy)."""
    from pendulum_lqg.util.resources import model_path

    return model_path()


def _named_geom(spec: mujoco.MjSpec, name: str, why: str) -> mujoco.MjsGeom:
    """The geom ``name``, which the override ``why`` edits (only then is the name required)."""
    geom = spec.geom(name)
    if geom is None:
        raise ConfigError(f"model: the override {why} needs a geom named {name!r}")
    return geom


def _apply_overrides(spec: mujoco.MjSpec, ov: ModelOverrides) -> None:
    if ov.pole_mass is not None or ov.pole_mass_scale is not None:
        pole = _named_geom(spec, POLE_GEOM, "pole_mass" if ov.pole_mass is not None
                           else "pole_mass_scale")
        pole.mass = ov.pole_mass if ov.pole_mass is not None else pole.mass * ov.pole_mass_scale
    if ov.cart_mass is not None or ov.cart_mass_scale is not None:
        cart = _named_geom(spec, CART_GEOM, "cart_mass" if ov.cart_mass is not None
                           else "cart_mass_scale")
        cart.mass = ov.cart_mass if ov.cart_mass is not None else cart.mass * ov.cart_mass_scale
    if ov.pole_length is not None or ov.pole_length_scale is not None:
        pole = _named_geom(spec, POLE_GEOM, "pole_length" if ov.pole_length is not None
                           else "pole_length_scale")
        start, end = np.array(pole.fromto[:3]), np.array(pole.fromto[3:])
        old = float(np.linalg.norm(end - start))
        if ov.pole_length is not None:
            new = ov.pole_length
        else:
            assert ov.pole_length_scale is not None          # one of the two, by the branch
            new = old * ov.pole_length_scale
        end = start + (end - start) * (new / old)
        pole.fromto = np.concatenate([start, end])
        tip = spec.site(POLE_TIP)
        if tip is not None:
            tip.pos = end
    if ov.force_limit is not None:
        act = spec.actuator(ACTUATOR)
        act.ctrlrange = np.array([-ov.force_limit, ov.force_limit])
    if ov.timestep is not None:
        spec.option.timestep = ov.timestep


def load_plant(path: str | Path | None = None, *, overrides: ModelOverrides | None = None) -> Plant:
    """Load and compile the cart-pole model, optionally with parameter overrides.

    Parameters
    ----------
    path : path to an MJCF file, default the bundled ``models/cartpole.xml``.
    overrides : changes applied to the spec before compiling (mismatch studies).
    """
    path = Path(path) if path is not None else default_model_path()
    if not path.is_file():
        raise ConfigError(f"model: file not found: {path}")
    try:
        spec = mujoco.MjSpec.from_file(str(path))
    except Exception as exc:  # MuJoCo raises ValueError with the parser message
        detail = " ".join(str(exc).split()) or type(exc).__name__   # one line
        raise ConfigError(f"model: cannot parse {path}: {detail}") from exc
    overrides = overrides or ModelOverrides()
    _apply_overrides(spec, overrides)
    try:
        model = spec.compile()
    except Exception as exc:
        raise ConfigError(f"model: cannot compile {path}: {' '.join(str(exc).split())}") from exc
    return Plant(model=model, path=path, overrides=overrides)


@dataclass(frozen=True, eq=False)
class Plant:
    """A compiled cart-pole model with named read-outs; a
    :class:`~pendulum_lqg.model.interface.SimulatedPlant`.

    Use :func:`load_plant` to make one. The attributes below are read from the model, never set.
    """

    model: mujoco.MjModel
    path: Path
    overrides: ModelOverrides

    #: MuJoCo itself, or its linearisation stepped in numpy (``Scenario.plant``).
    simulators = ("mujoco", "linear-zoh", "linear-euler")
    #: The state is the joints' own coordinates (the upright is qpos = 0): nothing to add.
    x_offset = None

    def __post_init__(self) -> None:
        m = self.model
        for kind, name in ((mujoco.mjtObj.mjOBJ_JOINT, SLIDER), (mujoco.mjtObj.mjOBJ_JOINT, HINGE),
                           (mujoco.mjtObj.mjOBJ_ACTUATOR, ACTUATOR),
                           (mujoco.mjtObj.mjOBJ_BODY, CART_BODY),
                           (mujoco.mjtObj.mjOBJ_BODY, POLE_BODY)):
            if mujoco.mj_name2id(m, kind, name) < 0:
                raise ConfigError(f"model: {self.path} has no {kind.name[6:].lower()} named "
                                  f"{name!r} (the cart-pole's contract, docs/model.md); any "
                                  f"other MuJoCo model is a plant of its own: --plant FILE.toml "
                                  f"(docs/family.md)")
        if m.nu != 1:
            raise ConfigError(f"model: {self.path}: expected exactly one actuator, found {m.nu}")
        if m.njnt != 2 or m.nq != 2 or m.nv != 2:
            # the loop rewrites [p, θ, ṗ, θ̇] each period: any other joint would be re-zeroed
            joints = ", ".join(repr(m.joint(j).name) for j in range(m.njnt))
            raise ConfigError(f"model: {self.path}: the cart-pole takes exactly the joints "
                              f"'slider' and 'hinge', found {m.njnt} ({joints}); a model with "
                              f"more joints is a plant of its own: a plant file, --plant "
                              f"FILE.toml (docs/family.md)")
        if m.opt.integrator == mujoco.mjtIntegrator.mjINT_RK4:
            raise ConfigError(f"model: {self.path}: the RK4 integrator is not supported "
                              f"(mjd_transitionFD refuses it); use Euler or implicitfast")
        self._check_contract()

    def _check_contract(self) -> None:
        """The rest of the model contract (docs/model.md): a finite positive
        timestep and finite gravity, joint kinds, a limited track, a limited motor on the slider,
        the two position sensors. Without these checks a missing ``range`` or ``ctrlrange`` read
        as a 0 m track or a 0 N motor, and a zero or nan timestep failed deep in the timing."""
        m, path = self.model, self.path
        h = float(m.opt.timestep)
        if not (np.isfinite(h) and h > 0):
            raise ConfigError(f"model: {path}: <option timestep> must be a finite positive number "
                              f"of seconds, found {h!r}")
        if not np.all(np.isfinite(m.opt.gravity)):
            raise ConfigError(f"model: {path}: <option gravity> must be finite, found "
                              f"{m.opt.gravity.tolist()!r}")
        jt = mujoco.mjtJoint
        slider, hinge = m.joint(SLIDER).id, m.joint(HINGE).id
        for jid, name, kind, word in ((slider, SLIDER, jt.mjJNT_SLIDE, "slide"),
                                      (hinge, HINGE, jt.mjJNT_HINGE, "hinge")):
            if m.jnt_type[jid] != kind:
                raise ConfigError(f"model: {path}: joint {name!r} must be of type \"{word}\"")
        lo, hi = m.jnt_range[slider]
        if not m.jnt_limited[slider] or not lo < 0 < hi:
            raise ConfigError(f"model: {path}: joint {SLIDER!r} needs a range around 0 (the "
                              f"track ends, e.g. range=\"-2.4 2.4\"); found limited="
                              f"{bool(m.jnt_limited[slider])}, range=[{lo:g}, {hi:g}]")
        act = m.actuator(ACTUATOR)
        if act.trntype[0] != mujoco.mjtTrn.mjTRN_JOINT or act.trnid[0] != slider:
            raise ConfigError(f"model: {path}: actuator {ACTUATOR!r} must act on the joint "
                              f"{SLIDER!r}")
        lo, hi = act.ctrlrange
        if not m.actuator_ctrllimited[act.id] or not lo < 0 < hi or abs(lo + hi) > 1e-9 * hi:
            raise ConfigError(f"model: {path}: actuator {ACTUATOR!r} needs a symmetric "
                              f"ctrlrange (ctrllimited) around 0, e.g. ctrlrange=\"-10 10\"; "
                              f"found ctrllimited={bool(m.actuator_ctrllimited[act.id])}, "
                              f"ctrlrange=[{lo:g}, {hi:g}]")
        if not act.gear[0] > 0:
            raise ConfigError(f"model: {path}: actuator {ACTUATOR!r} needs a positive gear, "
                              f"found {act.gear[0]:g}")
        for sensor, joint in zip(SENSORS, (SLIDER, HINGE), strict=True):
            sid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SENSOR, sensor)
            if sid < 0:
                raise ConfigError(f"model: {path}: no sensor named {sensor!r} (the measured "
                                  f"y = [p, θ] needs <jointpos name=\"{sensor}\" "
                                  f"joint=\"{joint}\"/>)")
            if (m.sensor_type[sid] != mujoco.mjtSensor.mjSENS_JOINTPOS
                    or m.sensor_objid[sid] != m.joint(joint).id):
                raise ConfigError(f"model: {path}: sensor {sensor!r} must be "
                                  f"<jointpos joint=\"{joint}\"/>")

    # ---- addresses -------------------------------------------------------------------------
    @cached_property
    def qpos_index(self) -> np.ndarray:
        """qpos addresses of ``[slider, hinge]``."""
        return np.array([self.model.joint(SLIDER).qposadr[0], self.model.joint(HINGE).qposadr[0]])

    @cached_property
    def qvel_index(self) -> np.ndarray:
        """qvel (dof) addresses of ``[slider, hinge]``."""
        return np.array([self.model.joint(SLIDER).dofadr[0], self.model.joint(HINGE).dofadr[0]])

    @cached_property
    def sensor_index(self) -> np.ndarray:
        """sensordata addresses of ``[cart_position, pole_angle]``."""
        return np.array([self.model.sensor(s).adr[0] for s in SENSORS])

    # ---- physical parameters, all read from the model --------------------------------------
    @property
    def timestep(self) -> float:
        """Physics step h [s]."""
        return float(self.model.opt.timestep)

    @property
    def force_limit(self) -> tuple[float, float]:
        """Actuator ``ctrlrange`` in newtons (force = gear · ctrl, gear read below)."""
        lo, hi = self.model.actuator(ACTUATOR).ctrlrange
        gear = float(self.model.actuator(ACTUATOR).gear[0])
        return float(lo * gear), float(hi * gear)

    @property
    def ctrl_gear(self) -> float:
        """The motor's gear: the force is ``gear · ctrl``, so MuJoCo's ctrl is ``u / gear``."""
        return float(self.model.actuator(ACTUATOR).gear[0])

    @property
    def u_max(self) -> float:
        """Largest force magnitude the motor can apply [N] (symmetric limits assumed)."""
        lo, hi = self.force_limit
        return float(min(-lo, hi))

    @property
    def track_limit(self) -> float:
        """Half-length of the track: the slider stops at ±track_limit [m]."""
        lo, hi = self.model.joint(SLIDER).range
        return float(min(-lo, hi))

    @property
    def gravity(self) -> float:
        return float(-self.model.opt.gravity[2])

    @property
    def cart_mass(self) -> float:
        return float(self.model.body(CART_BODY).mass[0])

    @property
    def pole_mass(self) -> float:
        return float(self.model.body(POLE_BODY).mass[0])

    @property
    def pole_com(self) -> float:
        """Distance from the hinge to the pole's centre of mass [m]."""
        return float(np.linalg.norm(self.model.body(POLE_BODY).ipos))

    @property
    def pole_length(self) -> float:
        """Full length of the pole rod (hinge to tip) [m]: from the geom named ``pole`` if there is
        one, else the farthest reach from the hinge of the pole body's geoms (centre distance plus
        half-length for capsules and cylinders, bounding radius for the others)."""
        m = self.model
        gid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, POLE_GEOM)
        if gid >= 0:
            return float(2.0 * m.geom_size[gid, 1])
        body = m.body(POLE_BODY).id
        hinge = m.jnt_pos[m.joint(HINGE).id]
        reach = 0.0
        for g in np.nonzero(m.geom_bodyid == body)[0]:
            centre = float(np.linalg.norm(m.geom_pos[g] - hinge))
            long = int(m.geom_type[g]) in (int(mujoco.mjtGeom.mjGEOM_CAPSULE),
                                           int(mujoco.mjtGeom.mjGEOM_CYLINDER))
            reach = max(reach, centre + (m.geom_size[g, 1] if long else m.geom_rbound[g]))
        return reach

    @property
    def pole_inertia_com(self) -> float:
        """Pole moment of inertia about its centre of mass, around the hinge axis [kg m²]."""
        body = self.model.body(POLE_BODY)
        # Principal inertia rotated into the body frame, then projected on the hinge axis.
        flat = np.zeros(9)
        mujoco.mju_quat2Mat(flat, body.iquat)
        rot = flat.reshape(3, 3)
        inertia = rot @ np.diag(body.inertia) @ rot.T
        axis = self.model.joint(HINGE).axis
        return float(axis @ inertia @ axis)

    def parameters(self) -> dict[str, float]:
        """Physical parameters as read from the compiled model (for reports and recordings)."""
        return {
            "cart_mass": self.cart_mass, "pole_mass": self.pole_mass,
            "pole_length": self.pole_length, "pole_com": self.pole_com,
            "pole_inertia_com": self.pole_inertia_com, "gravity": self.gravity,
            "force_limit": self.u_max, "track_limit": self.track_limit,
            "timestep": self.timestep,
        }

    # ---- state conversion ------------------------------------------------------------------
    def set_state(self, data: mujoco.MjData, x: np.ndarray) -> None:
        """Write ``x = [p, θ, ṗ, θ̇]`` into an MjData (and recompute derived quantities)."""
        data.qpos[self.qpos_index] = x[:2]
        data.qvel[self.qvel_index] = x[2:]
        mujoco.mj_forward(self.model, data)

    @cached_property
    def physics_state_layout(self) -> tuple[int, np.ndarray, np.ndarray]:
        """``(nstate, qpos_cols, qvel_cols)`` of the ``mjSTATE_FULLPHYSICS`` vector.

        The full-physics state is ``[time, qpos, qvel, act, history, plugin]`` in that order, so
        the qpos block starts after the time entry and the qvel block after the qpos block.
        """
        m = self.model
        st = mujoco.mjtState
        size = mujoco.mj_stateSize(m, st.mjSTATE_FULLPHYSICS)
        qpos0 = mujoco.mj_stateSize(m, st.mjSTATE_TIME)
        qvel0 = qpos0 + mujoco.mj_stateSize(m, st.mjSTATE_QPOS)
        return size, qpos0 + self.qpos_index, qvel0 + self.qvel_index

    def state_columns(self) -> np.ndarray:
        """Columns of the full-physics state vector holding ``[p, θ, ṗ, θ̇]``."""
        _, qpos_cols, qvel_cols = self.physics_state_layout
        return np.concatenate([qpos_cols, qvel_cols])

    # ---- the plant interface (pendulum_lqg.model.interface) ---------------------------------
    def layout(self, scenario: Any) -> Layout:
        """The cart-pole's vectors with the scenario's initial state and cost weights."""
        return msgspec.structs.replace(CARTPOLE, x0=np.asarray(scenario.x0),
                                   x0_std=np.asarray(scenario.x0_std), cost_Q=scenario.cost_Q,
                                   cost_R=scenario.cost_R)

    def limits(self, scenario: Any) -> tuple[float, float, float]:
        """``(theta_max, track_limit, u_max)``: the rule of
        :func:`pendulum_lqg.core.rules.limits` for the cart-pole (the scenario's limits, else the
        slider ``range`` and the actuator ``ctrlrange``; on MuJoCo no wider than those)."""
        track = self.track_limit if scenario.track_limit is None else scenario.track_limit
        u_max = self.u_max if scenario.force_limit is None else scenario.force_limit
        if scenario.plant == "mujoco":
            for name, value, model, where in (
                    ("track_limit", track, self.track_limit, "slider range"),
                    ("force_limit", u_max, self.u_max, "actuator ctrlrange (model override "
                                                       "force_limit)")):
                if value > model:
                    raise ConfigError(f"{name}: {value:g} is beyond the MuJoCo model's {where} "
                                      f"±{model:g}; use a linear plant (plant = 'linear-zoh' or "
                                      f"'linear-euler') or a model with a wider one")
        return scenario.theta_max, track, u_max

    def linear_model(self) -> ContinuousModel:
        """:func:`~pendulum_lqg.model.linearize.linearize`'s ``(A, B, C, D, F)`` about the upright
        (``F``: the slider's force and the hinge's torque, the force noise's inputs)."""
        from pendulum_lqg.model.linearize import linearize

        return linearize(self)

    def sampled(self, period: float, kind: str = "linear-zoh") -> tuple[np.ndarray, np.ndarray]:
        """``(Φ, Γ)`` of the linearisation at ``period``: exact ZOH or forward Euler."""
        from pendulum_lqg.design import euler, zoh

        lin = self.linear_model()
        if kind == "linear-zoh":
            return zoh(lin.A, lin.B, period)
        if kind == "linear-euler":
            return euler(lin.A, lin.B, period)          # I + TA, TB
        raise ConfigError(f"plant: expected 'linear-zoh' or 'linear-euler', got {kind!r}")

    def transition(self, period: float) -> DiscreteModel:
        """:func:`~pendulum_lqg.model.linearize.discretize_transition` at ``period``: MuJoCo's
        one-step ``mjd_transitionFD`` composed over the period."""
        from pendulum_lqg.model.linearize import discretize_transition

        return discretize_transition(self, period)

    def varied(self, scales: dict[str, float]) -> mujoco.MjModel:
        """The model of one randomised episode: the overrides times ``scales``
        (:meth:`Randomization.apply <pendulum_lqg.model.overrides.Randomization.apply>`)."""
        return load_plant(self.path, overrides=Randomization.apply(self.overrides, scales)).model

    def fingerprint(self) -> str:
        """SHA-256 of the MJCF file's bytes and the overrides applied to it."""
        text = json.dumps({"mjcf": hashlib.sha256(self.path.read_bytes()).hexdigest(),
                           "overrides": dataclasses.asdict(self.overrides)}, sort_keys=True)
        return hashlib.sha256(text.encode()).hexdigest()
