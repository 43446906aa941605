r"""Closed-loop identification with certainty-equivalent LQG: a controller learned from ``y`` and ``u``.

The recipe (:func:`identify_closed_loop`), on a suite's env and nothing else — the native vector
env (:class:`~pendulum_lqg.envs.vector.CartPoleLQGVectorEnv`) for data, never the model matrices
or a designed gain:

0. **Open-loop bursts** (``open_loop_steps``, default 10 000 logged steps): episodes of ``burst``
   periods from the suite's initial state, driven by a random ±``burst_force``·``u_max`` force.
   An output-error fit (:func:`~pendulum_lqg.design.pem.fit_innovations` with ``K_p = 0``) of a
   **4-number model** — the structure of :func:`~pendulum_lqg.design.sysid.structured_model` with
   no velocity terms (``A₂₂ = 0``): ``p̈ = a θ + b_p u``, ``θ̈ = c θ + b_θ u`` — for each candidate
   delay ``0 … max_delay``; the best delay is kept. Short bursts of a falling pole cannot separate
   the velocity terms from the rest, and fitting them anyway gives the wild models of the
   open-loop ``sysid-lqg`` recipe (:mod:`pendulum_lqg.design.sysid`). The noise covariances
   (``W = q·I`` per period, ``V`` diagonal) come from the fit's residuals
   (:func:`~pendulum_lqg.design.sysid.noise_covariances`). The **cautious design**: the discrete LQR
   of the exact sampled cost and a Kalman filter for ``caution``·``W``: a filter that trusts the
   rough model little and the measurements more.
1. **Closed-loop rounds** (``rounds`` × ``episodes`` episodes of the suite's duration): the last
   round's controller plays, with a white force ``N(0, dither²)`` added to its output (the
   applied, saturated force is logged). A **prediction-error fit of the innovations form** on
   every closed-loop episode so far (:func:`~pendulum_lqg.design.pem.fit_delays`): all 8
   structured numbers, a free 4×2 predictor gain ``K_p`` and a shared initial state, the delay
   among the last one ±1 — consistent under feedback because ``K_p`` models the noise (Ljung
   §13.4). The dither is the excitation the feedback cannot explain: without it the plant's and
   the controller's dynamics are not separable from closed-loop data.
2. **The design** after each round: the discrete LQR of the exact sampled cost
   (:func:`~pendulum_lqg.design.sampled_cost`, :func:`~pendulum_lqg.design.dlqr`) on the
   identified ``(Φ, Γ)`` and the identified current-form filter gain ``L = Φ⁻¹ K_p``
   (:func:`~pendulum_lqg.design.pem.filter_gain`), as a state-space controller
   (:func:`~pendulum_lqg.scoreboard.linear.lqg_state_space`, ``action_scale`` 1 N). With a delay
   ``d`` the model carries the last ``d`` forces as states (:func:`~pendulum_lqg.design.augment_delays`
   with an actuator delay ``d``: a measurement delay is the same input–output delay) and the
   controller acts on the state predicted ``d`` periods ahead, as the reference
   ``dlqr+kalman-delay`` does.

**The delay is identified** in whole periods on every suite: the open-loop round compares every
candidate ``0 … max_delay``, each closed-loop round the last delay and its two neighbours, and
keeps the smallest innovations. **Missing samples** (``nan``: dropout, a measurement delay's
first samples) are left out of the fits (the predictor runs open loop over them); the scored
controller holds the last sample received, as every ``linear:`` controller does.

**Validation.** After the last round, ``validation_episodes`` further episodes are played with the
final controller and the dither (seeds after the training ones; not used by any fit or choice):
each round's model gives its one-step innovations on them (the open-loop round's model with its
Kalman predictor for ``W``, ``V``), their RMS per output beside the sensor's noise standard
deviation, the floor no predictor can go below. These episodes count in ``stepped_steps``, not
in ``logged_steps`` (the data the controller was learned from).

**Budget.** ``steps`` (logged env steps) splits into the open-loop part, at most a fifth of it
(and at most ``open_loop_steps``), and ``rounds`` equal closed-loop rounds of whole episodes; an
episode that fails early logs fewer steps, so the steps logged never exceed ``steps``.

**Seeds.** Every episode is seeded ``episode_seed(root, i)``, ``i`` counting up through the bursts,
the rounds and the validation episodes; the bursts' forces, the dither and the validation's dither
draw from ``numpy.random.default_rng([root, 2])``, ``[root, 3]`` and ``[root, 4]``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from pendulum_lqg import design
from pendulum_lqg.design import pem
from pendulum_lqg.design.sysid import noise_covariances, structured_model, structured_size
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.scoreboard.linear import StateSpacePolicy, lqg_state_space

__all__ = ["ClosedLoopSettings", "RoundResult", "certainty_equivalent", "identify_closed_loop"]


@dataclass(frozen=True)
class ClosedLoopSettings:
    """The knobs of :func:`identify_closed_loop` (module docstring), with why each default.

    Attributes
    ----------
    dither : std of the white force added in the closed-loop rounds [N]. A tenth of the
        actuator limit: the excitation the feedback cannot explain, large beside the
        loop's own force from the noise, small enough that the loop's cost rises little and the
        actuator rarely saturates.
    rounds : closed-loop rounds. Two: the first runs the cautious controller, whose data give a
        model good enough that the second's data are taken where the final loop operates.
    episodes : episodes per closed-loop round (of the suite's duration) in the default recipe.
        Thirty 10 s episodes per round: enough for a model whose one-step prediction error on
        held-out data is the true model's Kalman predictor's; the default recipe logs at most
        70 020 steps: whole bursts covering ``open_loop_steps`` (⌈10 000/30⌉ · 30 = 10 020), then
        the rounds' episodes (episodes that fail end early).
    open_loop_steps : logged steps of open-loop bursts (at most a fifth of a given budget).
        Enough for a 4-number model that stabilises under the cautious filter.
    burst : periods of one open-loop burst. The pole falls from θ₀ in about half a second.
    burst_force : the bursts' ± force, as a fraction of the actuator limit: half, so the logged
        force is the one applied.
    caution : the factor on the identified process noise of the first design's Kalman filter.
        The 4-number model is rough: its filter must follow the measurements, not the model.
    max_delay : the largest delay tried [periods].
    screen_episodes, screen_iterations : the closed-loop rounds choose the delay by fits of at
        most this many Levenberg–Marquardt steps on their last this many episodes, then fit the
        chosen delay on every episode: the choice needs far fewer data than the fit.
    validation_episodes : held-out episodes of the validation figure.
    max_iterations : Levenberg–Marquardt steps per fit.
    tolerance : a closed-loop fit stops when a step lowers its cost, in χ² units (innovations
        weighted by their std), by less than this: far below what changes a decision.
    """

    dither: float = 1.0
    rounds: int = 2
    episodes: int = 30
    open_loop_steps: int = 10_000
    burst: int = 30
    burst_force: float = 0.5
    caution: float = 100.0
    max_delay: int = 8
    screen_episodes: int = 20
    screen_iterations: int = 8
    validation_episodes: int = 4
    max_iterations: int = 30
    tolerance: float = 0.05

    def __post_init__(self) -> None:
        for name in ("dither", "burst_force", "caution", "tolerance"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float) \
                    or not np.isfinite(value) or value <= 0:
                raise ConfigError(f"{name}: expected a finite number > 0, got {value!r}")
        if self.burst_force > 1:
            raise ConfigError(f"burst_force: expected a fraction of the actuator limit ≤ 1, "
                              f"got {self.burst_force!r}")
        for name, low in (("rounds", 1), ("episodes", 1), ("open_loop_steps", 1), ("burst", 3),
                          ("max_delay", 0), ("screen_episodes", 1), ("screen_iterations", 1),
                          ("validation_episodes", 1), ("max_iterations", 1)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < low:
                raise ConfigError(f"{name}: expected an integer ≥ {low}, got {value!r}")

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


@dataclass(frozen=True)
class RoundResult:
    """One round of :func:`identify_closed_loop`: the controller designed after it.

    Attributes
    ----------
    logged_steps : env steps of every episode the fits used so far (the learning budget)
    stepped_steps : env steps simulated so far (with the rows of ended episodes and, in the last
        round, the validation episodes)
    state_space : the controller (:func:`~pendulum_lqg.scoreboard.linear.lqg_state_space`,
        ``action_scale`` 1 N)
    model : the identified parameters, JSON-able
    validation : one-step innovation RMS per output on the held-out episodes, beside the sensor
        noise's std (``innovation_rms``, ``sensor_std``, ``episodes``, ``samples``)
    """

    logged_steps: int
    stepped_steps: int
    state_space: dict[str, Any]
    model: dict[str, Any]
    validation: dict[str, Any]


@dataclass
class _Episodes:
    """Logged episodes: ``Y`` (E, H, p; nan = missing), ``U`` (E, H, 1) the applied force,
    ``valid`` (E, H) the periods before each episode ended."""

    Y: np.ndarray
    U: np.ndarray
    valid: np.ndarray

    @property
    def logged(self) -> int:
        return int(self.valid.sum())

    def __add__(self, other: _Episodes) -> _Episodes:
        return _Episodes(np.concatenate([self.Y, other.Y]), np.concatenate([self.U, other.U]),
                         np.concatenate([self.valid, other.valid]))


class _Env:
    """What the identification knows of a suite: its env keywords, the actuator limit, the
    control period and episode length, the cost weights; and the seeds it has used."""

    def __init__(self, suite: Any, root: int) -> None:
        from pendulum_lqg.core.rules import limits

        sc = suite.config.scenario
        self.suite, self.root = suite, root
        self.u_max = float(limits(suite.plants()[1], sc)[2])
        self.dt = float(sc.control_period)
        self.periods = round(sc.duration / sc.control_period)
        self.Q, self.R = np.diag(sc.cost_Q), np.array([[sc.cost_R]])
        noise = sc.noise
        self.sensor_std = np.sqrt(np.diag(noise.V)) * noise.scale
        self.next_episode, self.stepped = 0, 0

    def play(self, n: int, horizon: int, act: Callable[[np.ndarray, int], np.ndarray],
             ) -> _Episodes:
        """``n`` new episodes of at most ``horizon`` periods; ``act(y, k)`` returns the forces
        (n,) of period ``k`` (saturated: they are logged as the applied ones)."""
        from pendulum_lqg.core.seeding import episode_seeds
        from pendulum_lqg.envs.vector import CartPoleLQGVectorEnv

        env = CartPoleLQGVectorEnv(n, nthread=1, max_episode_steps=horizon, **self.suite.env)
        try:
            obs, _ = env.reset(seed=episode_seeds(self.root, range(self.next_episode,
                                                                    self.next_episode + n)))
            self.next_episode += n
            Y, U = np.full((n, horizon, 2), np.nan), np.zeros((n, horizon, 1))
            valid = np.zeros((n, horizon), dtype=bool)
            alive = np.ones(n, dtype=bool)
            for k in range(horizon):
                if not alive.any():
                    break
                Y[:, k], valid[:, k] = obs, alive
                u = act(obs, k)
                U[:, k, 0] = u
                obs, _, terminated, truncated, _ = env.step(u)
                self.stepped += n
                alive &= ~(terminated | truncated)
        finally:
            env.close()
        return _Episodes(np.where(valid[..., None], Y, np.nan), U, valid)


class _Dithered(StateSpacePolicy):
    """A state-space controller (``action_scale`` 1 N) with a white force added before the
    saturation; its history sees the applied force, as the controller's model assumes."""

    def __init__(self, state_space: dict[str, Any], dither: np.ndarray, u_max: float) -> None:
        m = state_space
        super().__init__(m["A"], m["B"], m["C"], m["D"], action_scale=1.0, u_max=u_max)
        self.dither, self.k = dither, 0

    def output(self, inputs: np.ndarray) -> np.ndarray:
        v = super().output(inputs) + self.dither[:, self.k]
        self.k += 1
        return v


def _closed_loop(env: _Env, state_space: dict[str, Any], n: int, dither: float,
                 rng: np.random.Generator) -> _Episodes:
    policy = _Dithered(state_space, dither * rng.standard_normal((n, env.periods)), env.u_max)
    policy.reset(n)
    return env.play(n, env.periods, lambda y, k: policy.act(y))


def _bursts(env: _Env, count: int, settings: ClosedLoopSettings) -> _Episodes:
    from pendulum_lqg.core.rules import saturate

    rng = np.random.default_rng([env.root, 2])
    force = settings.burst_force * env.u_max
    return env.play(count, settings.burst,
                    lambda y, k: saturate(force * rng.choice([-1.0, 1.0], size=count), env.u_max))


def certainty_equivalent(Phi: np.ndarray, Gamma: np.ndarray, A: np.ndarray, B: np.ndarray,
                         L: np.ndarray, *, delay: int, Q: np.ndarray, R: np.ndarray,
                         dt: float) -> dict[str, Any]:
    """The LQG controller designed as if ``x⁺ = Φx + Γu_{k−d}``, ``y = [I 0] x`` were the plant:
    the discrete LQR of the exact sampled cost of ``∫ xᵀQx + uᵀRu dt`` (continuous ``A``, ``B``
    at period ``dt``) on the state predicted ``d`` periods ahead, and the current-form filter gain
    ``L`` (n, p), as :func:`~pendulum_lqg.scoreboard.linear.lqg_state_space` (``action_scale``
    1 N; the controller's state carries the last ``d`` forces)."""
    n = Phi.shape[0]
    C = np.hstack([np.eye(n // 2), np.zeros((n // 2, n // 2))])
    Qd, Rd, Nd = design.sampled_cost(A, B, Q, R, dt)
    K = design.dlqr(Phi, Gamma, Qd, Rd, N=Nd).K
    aug = design.augment_delays(Phi, Gamma, C, measurement_delay=0, actuator_delay=int(delay))
    L_aug = np.vstack([L, np.zeros((aug.Phi.shape[0] - n, L.shape[1]))])
    return lqg_state_space(aug.Phi, aug.Gamma, aug.C, K @ aug.predict, L_aug)


def _open_loop_model(data: _Episodes, env: _Env, settings: ClosedLoopSettings,
                     ) -> tuple[pem.InnovationsModel, dict[int, float], np.ndarray, np.ndarray]:
    """The 4-number output-error model of the bursts, its delay costs and ``(W, V)``."""
    p = 2
    free = np.zeros(structured_size(p), dtype=bool)
    free[:p * (p - 1)] = True                          # the θ column of A₂₁
    free[p * (2 * p - 1):] = True                      # b
    first = _first_sample(data)
    model, costs = pem.fit_delays(
        data.Y, data.U, data.valid, env.dt, delays=range(settings.max_delay + 1),
        params=np.zeros(structured_size(p)), K_p=np.zeros((2 * p, p)),
        x0=np.concatenate([first, np.zeros(p)]), free=free, gain=False,
        max_iterations=settings.max_iterations)
    e = pem.innovations(model.Phi, model.Gamma, model.C, model.K_p, model.x0, data.Y, data.U,
                        data.valid, delay=model.delay)
    residuals = np.nan_to_num(e)
    W, V = noise_covariances(model.Phi, model.C, residuals, np.isfinite(e).all(axis=2))
    return model, costs, W, V


def _first_sample(data: _Episodes) -> np.ndarray:
    """The mean of every episode's first observed sample (the bursts' common start)."""
    observed = np.isfinite(data.Y).all(axis=2)
    first = observed.argmax(axis=1)
    rows = observed.any(axis=1)
    return data.Y[rows, first[rows]].mean(axis=0)


def _cautious_design(data: _Episodes, env: _Env, settings: ClosedLoopSettings,
                     ) -> tuple[dict[str, Any], dict[str, Any], dict[str, Any]]:
    """The open-loop round: the controller (cautious filter), the model's record and the start
    of the first closed-loop fit (the model, its Kalman predictor gain, innovation weights)."""
    m0, costs0, W, V = _open_loop_model(data, env, settings)
    L0 = design.dkalman(m0.Phi, np.eye(4), m0.C, settings.caution * W, V).L
    ss = certainty_equivalent(m0.Phi, m0.Gamma, m0.A, m0.B, L0, delay=m0.delay, Q=env.Q,
                              R=env.R, dt=env.dt)
    K_p0 = design.dkalman(m0.Phi, np.eye(4), m0.C, W, V).L_pred
    record = {**m0.to_dict(), "K_p": K_p0.tolist(), "L": L0.tolist(), "W": np.diag(W).tolist(),
              "V": np.diag(V).tolist(), "caution": settings.caution, "delay_costs": costs0,
              "fit": "output error, 4 numbers (A22 = 0), open-loop bursts"}
    start = {"params": m0.params, "K_p": K_p0, "x0": m0.x0, "delay": m0.delay,
             "weights": 1.0 / np.sqrt(np.diag(V))}
    return ss, record, start


def _closed_loop_model(data: _Episodes, env: _Env, start: dict[str, Any],
                       settings: ClosedLoopSettings,
                       ) -> tuple[pem.InnovationsModel, dict[int, float]]:
    """The prediction-error fit of the innovations form on every closed-loop episode so far,
    from the last round's model ``start`` (``params``, ``K_p``, ``x0``, ``delay``, ``weights``),
    the delay among the last one and its neighbours."""
    d = int(start["delay"])
    delays = [c for c in (d, d - 1, d + 1) if 0 <= c <= settings.max_delay]
    options = {"params": start["params"], "K_p": start["K_p"], "x0": start["x0"],
               "weights": start["weights"], "atol": settings.tolerance}
    recent = slice(max(0, data.valid.shape[0] - settings.screen_episodes), None)
    screened, costs = pem.fit_delays(data.Y[recent], data.U[recent], data.valid[recent], env.dt,
                                     delays=delays, max_iterations=settings.screen_iterations,
                                     **options)
    options.update(params=screened.params, K_p=screened.K_p, x0=screened.x0)
    return pem.fit_innovations(data.Y, data.U, data.valid, env.dt, delay=screened.delay,
                               max_iterations=settings.max_iterations, **options), costs


def _validation(models: list[dict[str, Any]], data: _Episodes, env: _Env) -> list[dict[str, Any]]:
    """Each model's one-step innovation RMS per output on the held-out episodes ``data``."""
    out = []
    for m in models:
        Phi, Gamma, C, _, _ = structured_model(np.asarray(m["params"]), 2, env.dt)
        e = pem.innovations(Phi, Gamma, C, np.asarray(m["K_p"]), np.asarray(m["x0"]), data.Y,
                            data.U, data.valid, delay=int(m["delay"]))
        observed = np.isfinite(e).all(axis=2)
        out.append({"innovation_rms": np.sqrt(np.mean(e[observed] ** 2, axis=0)).tolist(),
                    "sensor_std": env.sensor_std.tolist(), "outputs": ["p", "theta"],
                    "episodes": int(data.valid.shape[0]), "samples": int(observed.sum())})
    return out


def _plan(steps: int | None, env: _Env, settings: ClosedLoopSettings) -> tuple[int, int]:
    """``(bursts, episodes per round)`` of a budget of ``steps`` logged env steps."""
    if steps is None:
        return -(-settings.open_loop_steps // settings.burst), settings.episodes
    if isinstance(steps, bool) or not isinstance(steps, int | np.integer):
        raise ConfigError(f"steps: expected an integer number of env steps, got {steps!r}")
    smallest = 10 * settings.burst + settings.rounds * env.periods
    if steps < smallest:
        raise ConfigError(f"steps: expected at least {smallest:,} logged env steps (10 bursts and "
                          f"one episode per round), got {steps:,}")
    open_steps = min(settings.open_loop_steps, int(steps) // 5)
    bursts = max(10, open_steps // settings.burst)
    episodes = (int(steps) - bursts * settings.burst) // (settings.rounds * env.periods)
    return bursts, max(1, episodes)


@dataclass
class _Progress:
    """The identification after its stage ``stage`` (0: the open-loop round, r: closed-loop round
    r): what the next round needs, the rounds' results so far and the closed-loop episodes. The
    rounds' seeds are the generator's state and the env's episode counter, so a run continued
    from :meth:`checkpoint` plays the episodes an uninterrupted one plays."""

    stage: int
    bursts: int
    per_round: int
    open_logged: int
    ss: dict[str, Any]
    models: list[dict[str, Any]]
    start: dict[str, Any]
    results: list[tuple[int, int, dict[str, Any]]]
    rng: np.random.Generator
    closed: _Episodes | None = None

    @classmethod
    def open_loop(cls, env: _Env, bursts: int, per_round: int, settings: ClosedLoopSettings,
                  say: Callable[[str], None]) -> _Progress:
        data0 = _bursts(env, bursts, settings)
        ss, first, start = _cautious_design(data0, env, settings)
        say(f"open loop: {data0.logged:,} steps in {bursts} bursts, delay {first['delay']}, "
            f"a = {first['A'][2][1]:.3g}, c = {first['A'][3][1]:.3g}, b = "
            f"{np.round(np.asarray(first['B'])[2:, 0], 3).tolist()}")
        return cls(0, bursts, per_round, data0.logged, ss, [first], start,
                   [(data0.logged, env.stepped, ss)], np.random.default_rng([env.root, 3]))

    @classmethod
    def resumed(cls, state: dict[str, Any], data: dict[str, Any], env: _Env, bursts: int,
                per_round: int, settings: ClosedLoopSettings) -> _Progress:
        """The progress :meth:`checkpoint` gave, checked against this run's plan."""
        if (state["bursts"], state["per_round"]) != (bursts, per_round) \
                or not 0 <= state["stage"] <= settings.rounds:
            raise ConfigError(f"resume: stage {state['stage']} of a plan of {state['bursts']} "
                              f"bursts and {state['per_round']} episodes per round; this one is "
                              f"{bursts} and {per_round} of {settings.rounds} rounds")
        env.next_episode, env.stepped = int(state["next_episode"]), int(state["stepped"])
        rng = np.random.default_rng([env.root, 3])
        rng.bit_generator.state = state["rng"]
        start = {k: (int(v) if k == "delay" else np.asarray(v, dtype=float))
                 for k, v in state["start"].items()}
        closed = _Episodes(np.asarray(data["Y"], dtype=float), np.asarray(data["U"], dtype=float),
                           np.asarray(data["valid"], dtype=bool)) if state["stage"] else None
        return cls(int(state["stage"]), bursts, per_round, int(state["open_logged"]),
                   state["state_space"], list(state["models"]), start,
                   [(int(a), int(b), c) for a, b, c in state["results"]], rng, closed)

    def closed_round(self, r: int, env: _Env, settings: ClosedLoopSettings,
                     say: Callable[[str], None]) -> None:
        """Closed-loop round ``r``: episodes under the current design, the fit on every
        closed-loop episode so far, the new design."""
        new = _closed_loop(env, self.ss, self.per_round, settings.dither, self.rng)
        closed = self.closed = new if self.closed is None else self.closed + new
        model, costs = _closed_loop_model(closed, env, self.start, settings)
        self.ss = certainty_equivalent(model.Phi, model.Gamma, model.A, model.B, model.L,
                                       delay=model.delay, Q=env.Q, R=env.R, dt=env.dt)
        self.models.append({**model.to_dict(), "delay_costs": costs,
                            "fit": f"prediction error, innovations form, closed-loop rounds 1..{r}"})
        self.start = {"params": model.params, "K_p": model.K_p, "x0": model.x0,
                      "delay": model.delay, "weights": 1.0 / np.sqrt(np.diag(model.S))}
        self.results.append((self.open_logged + closed.logged, env.stepped, self.ss))
        self.stage = r
        say(f"round {r}: {new.logged:,} new steps ({closed.logged:,} closed-loop), delay "
            f"{model.delay}, innovation rms {np.sqrt(np.diag(model.S)).round(4).tolist()}, "
            f"{model.iterations} steps of the fit")

    def checkpoint(self, env: _Env) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
        """``(state, data)``: a JSON-able table and the closed-loop episodes so far."""
        kept = self.closed if self.closed is not None else _Episodes(
            np.zeros((0, env.periods, 2)), np.zeros((0, env.periods, 1)),
            np.zeros((0, env.periods), dtype=bool))
        state = _json({"stage": self.stage, "bursts": self.bursts, "per_round": self.per_round,
                       "open_logged": self.open_logged, "next_episode": env.next_episode,
                       "stepped": env.stepped, "state_space": self.ss, "models": self.models,
                       "start": self.start, "results": [list(x) for x in self.results],
                       "rng": self.rng.bit_generator.state})
        return state, {"Y": kept.Y, "U": kept.U, "valid": kept.valid}


def identify_closed_loop(suite: Any, *, root: int, steps: int | None = None,
                         settings: ClosedLoopSettings = ClosedLoopSettings(),
                         log: Callable[[str], None] | None = None,
                         on_stage: Callable[[dict[str, Any], dict[str, np.ndarray]], None]
                         | None = None,
                         resume: tuple[dict[str, Any], dict[str, np.ndarray]] | None = None,
                         ) -> list[RoundResult]:
    """Learn an LQG controller of ``suite`` from data (module docstring): the open-loop round,
    then ``settings.rounds`` closed-loop rounds; the last result is the final controller.

    Parameters
    ----------
    suite : a :class:`~pendulum_lqg.scoreboard.suites.Suite` (``load_suite(NAME|FILE)``): its env
        (model, overrides, noise, randomisation, delays, dropout) is the plant played
    root : the run's root seed (episode ``i`` is seeded ``episode_seed(root, i)``)
    steps : the budget of logged env steps (None: the default recipe, at most
        ``open_loop_steps + rounds·episodes·duration/T`` steps)
    log : called with one line per stage (progress)
    on_stage : called after the open-loop round (stage 0) and after each closed-loop round
        (stage r) with ``(state, data)``: what :func:`identify_closed_loop` needs to continue from
        there (a JSON-able table) and the closed-loop episodes so far (``Y``, ``U``, ``valid``);
        a checkpoint (``sysid-lqg``'s, :mod:`pendulum_lqg.learn.sysid_lqg`). It may raise to stop.
    resume : such a ``(state, data)``: the identification continues after its stage, with the
        same seeds, and gives the rounds an uninterrupted one gives
    """
    say = log or (lambda line: None)
    env = _Env(suite, root)
    if suite.observes_state:
        raise ConfigError(f"suite {suite.name!r} gives the true state; the identification learns "
                          "from y = [p, θ]")
    bursts, per_round = _plan(steps, env, settings)
    if resume is None:
        run = _Progress.open_loop(env, bursts, per_round, settings, say)
        if on_stage is not None:
            on_stage(*run.checkpoint(env))
    else:
        run = _Progress.resumed(*resume, env, bursts, per_round, settings)
        say(f"resumed after {'round ' + str(run.stage) if run.stage else 'the open loop'}")
    for r in range(run.stage + 1, settings.rounds + 1):
        run.closed_round(r, env, settings, say)
        if on_stage is not None:
            on_stage(*run.checkpoint(env))
    ss, models, results = run.ss, run.models, run.results
    held_out = _closed_loop(env, ss, settings.validation_episodes, settings.dither,
                            np.random.default_rng([root, 4]))
    checks = _validation(models, held_out, env)
    say(f"validation: innovation rms {checks[-1]['innovation_rms']} against the sensor's "
        f"{env.sensor_std.tolist()}")
    out = []
    for i, ((logged, stepped, state_space), model_doc, check) in enumerate(
            zip(results, models, checks, strict=True)):
        last = i == len(results) - 1
        out.append(RoundResult(logged_steps=int(logged),
                               stepped_steps=int(env.stepped if last else stepped),
                               state_space=state_space, model=_json(model_doc), validation=check))
    return out


def _json(doc: dict[str, Any]) -> dict[str, Any]:
    """``doc`` with numpy values as lists and numbers, and int keys as strings."""
    def conv(v: Any) -> Any:
        if isinstance(v, np.ndarray):
            return v.tolist()
        if isinstance(v, np.generic):
            return v.item()
        if isinstance(v, dict):
            return {str(k): conv(x) for k, x in v.items()}
        if isinstance(v, list | tuple):
            return [conv(x) for x in v]
        return v
    return conv(doc)
