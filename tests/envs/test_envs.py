"""The Gymnasium environment, its vector env and the LQG agent (issue 4).

Every warning is an error in this module (as in Gymnasium's own env tests); the few that
``check_env`` always raises for this env are allowed explicitly, by their text.
"""

from __future__ import annotations

import os
import pickle
import shutil
import subprocess
import sys
import textwrap
import warnings
from pathlib import Path

import gymnasium as gym
import mujoco
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import pendulum_lqg
from pendulum_lqg.core.metrics import summarize
from pendulum_lqg.core.runner import run_episodes
from pendulum_lqg.core.scenario import Scenario
from pendulum_lqg.core.seeding import episode_seed
from pendulum_lqg.envs.agent import LQGAgent
from pendulum_lqg.envs.config import REWARD_FLOOR
from pendulum_lqg.envs.single import CartPoleLQGEnv
from pendulum_lqg.envs.vector import CartPoleLQGVectorEnv
from pendulum_lqg.errors import ConfigError, PendulumLQGError
from pendulum_lqg.model.plant import load_plant
from pendulum_lqg.names import OBSERVERS
from pendulum_lqg.policies.lqg import DesignSpec, design_policy

pytestmark = pytest.mark.filterwarnings("error")

ID = pendulum_lqg.ENV_ID

#: check_env warnings that this env raises by design (Gymnasium's tests allow the same ones):
#: unbounded observations (Gaussian noise, unbounded rates) and an action space in newtons.
CHECK_ENV_ALLOWED = {
    "A Box observation space minimum value is -infinity. This is probably too low.",
    "A Box observation space maximum value is infinity. This is probably too high.",
    "For Box action spaces, we recommend using a symmetric and normalized space (range=[-1, 1] "
    "or [0, 1]). See https://stable-baselines3.readthedocs.io/en/master/guide/rl_tips.html for "
    "more information.",
}


def _warn_text(w: warnings.WarningMessage) -> str:
    return str(w.message).removeprefix("\x1b[33mWARN: ").removesuffix("\x1b[0m")


def _gl_in_process() -> bool:
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")          # glfw warns before it fails headless
            with mujoco.Renderer(load_plant().model, 8, 8):
                return True
    except Exception:
        return False


GL = _gl_in_process()


def rollout(env: gym.Env, seed: int, actions: np.ndarray) -> dict[str, list]:
    obs, info = env.reset(seed=seed)
    out: dict[str, list] = {"obs": [obs], "reward": [], "term": [], "trunc": [], "info": [info]}
    for a in actions:
        obs, r, term, trunc, info = env.step(a)
        for key, val in zip(("obs", "reward", "term", "trunc", "info"), (obs, r, term, trunc, info),
                            strict=True):
            out[key].append(val)
        if term or trunc:
            break
    return out


def assert_rollouts_equal(a: dict[str, list], b: dict[str, list]) -> None:
    assert len(a["obs"]) == len(b["obs"])
    np.testing.assert_array_equal(np.array(a["obs"]), np.array(b["obs"]))
    assert a["reward"] == b["reward"] and a["term"] == b["term"] and a["trunc"] == b["trunc"]
    for ia, ib in zip(a["info"], b["info"], strict=True):
        assert ia.keys() == ib.keys()
        for key in ia:
            np.testing.assert_array_equal(ia[key], ib[key])


# ---- registration ---------------------------------------------------------------------------------
def test_registered_with_episode_length_derived_from_duration_and_period():
    spec = gym.spec(ID)
    env = gym.make(ID)
    base = env.unwrapped
    assert isinstance(base, CartPoleLQGEnv)
    assert env.spec.max_episode_steps == base.max_episode_steps == Scenario().n_periods == 1000
    assert spec.kwargs == {}            # the env's own defaults: those of Scenario
    assert spec.vector_entry_point == "pendulum_lqg.envs.vector:CartPoleLQGVectorEnv"
    # the time limit follows the keywords: 20 s at 10 ms, 10 s at 20 ms, 0.05 s at 10 ms
    assert gym.make(ID, duration=20.0).spec.max_episode_steps == 2000
    assert gym.make(ID, control_period=0.02).spec.max_episode_steps == 500
    for duration, steps in ((0.05, 5), (12.5, 1250)):
        ep = gym.make(ID, duration=duration, noise_scale=0.0, x0=(0.0, 0.0, 0.0, 0.0))
        ep.reset(seed=0)
        truncs = [ep.step(np.zeros(1))[3] for _ in range(steps)]
        assert truncs == [False] * (steps - 1) + [True]


def test_import_registers_as_gymnasium_packages_do_without_an_import_hook():
    """``import pendulum_lqg`` loads no Gymnasium; the id is registered when Gymnasium was
    imported first, when ``pendulum_lqg.ENV_ID`` is read, and by the ``module:id`` form."""
    code = textwrap.dedent("""
        import sys
        import pendulum_lqg
        assert "gymnasium" not in sys.modules and "numpy" not in sys.modules
        import gymnasium as gym
        assert "pendulum_lqg/CartPoleLQG-v0" not in gym.registry
        assert pendulum_lqg.ENV_ID in gym.registry and "mujoco" not in sys.modules
        assert not any("pendulum" in type(f).__name__.lower() for f in sys.meta_path)
        gym.register_envs(pendulum_lqg)
        print("registered")
    """)
    gym_first = textwrap.dedent("""
        import gymnasium as gym
        import pendulum_lqg
        print("pendulum_lqg/CartPoleLQG-v0" in gym.registry)
    """)
    module_form = textwrap.dedent("""
        import gymnasium as gym
        env = gym.make("pendulum_lqg:pendulum_lqg/CartPoleLQG-v0")
        print(type(env.unwrapped).__name__, env.spec.max_episode_steps)
    """)
    for src, expected in ((code, "registered"), (gym_first, "True"),
                          (module_form, "CartPoleLQGEnv 1000")):
        out = subprocess.run([sys.executable, "-c", src], capture_output=True, text=True,
                             timeout=120, check=True)
        assert out.stdout.strip() == expected, out.stderr


def test_cli_help_imports_neither_gymnasium_nor_numpy():
    script = shutil.which("pendulum-lqg", path=str(Path(sys.executable).parent))
    assert script is not None
    out = subprocess.run([sys.executable, "-X", "importtime", script, "--help"],
                         capture_output=True, text=True, timeout=60, check=True)
    imported = {line.split("|")[-1].strip() for line in out.stderr.splitlines() if "|" in line}
    assert "pendulum_lqg" in imported and "pendulum_lqg.cli" in imported
    assert "numpy" not in imported and "gymnasium" not in imported
    assert "usage: pendulum-lqg" in out.stdout


# ---- gymnasium conformance -----------------------------------------------------------------------
@pytest.mark.parametrize("mode", ["measurement", "state"])
def test_check_env_passes_with_only_the_allowed_warnings(mode):
    env = gym.make(ID, observation_mode=mode, disable_env_checker=True).unwrapped
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env, skip_render_check=not GL)
    texts = {_warn_text(w) for w in caught}
    unexpected = texts - CHECK_ENV_ALLOWED
    assert not unexpected, f"unexpected warnings: {unexpected}"
    assert texts == CHECK_ENV_ALLOWED          # the allow-list is exactly what the env raises
    env.close()


def test_spaces_come_from_the_model():
    env = gym.make(ID).unwrapped
    assert env.action_space == gym.spaces.Box(-10.0, 10.0, (1,), np.float32)   # ctrlrange·gear
    assert env.observation_space.shape == (2,) and env.observation_space.dtype == np.float64
    assert gym.make(ID, observation_mode="state").observation_space.shape == (4,)
    assert env.dt == pytest.approx(0.01) and env.frame_skip == 10
    assert env.metadata["render_fps"] == 100
    assert gym.make(ID, control_period=0.02).unwrapped.frame_skip == 20


def test_same_seed_gives_exactly_equal_rollouts_and_other_seeds_differ():
    actions = np.random.default_rng(7).uniform(-3, 3, size=(200, 1))
    a = rollout(gym.make(ID, x0_std=(0.05, 0.05, 0.0, 0.0)), 42, actions)
    b = rollout(gym.make(ID, x0_std=(0.05, 0.05, 0.0, 0.0)), 42, actions)
    assert_rollouts_equal(a, b)
    assert len(a["reward"]) > 20
    c = rollout(gym.make(ID, x0_std=(0.05, 0.05, 0.0, 0.0)), 43, actions)
    assert not np.array_equal(a["obs"][0], c["obs"][0])


def test_env_pickles_mid_episode_and_continues_identically():
    env = gym.make(ID)
    agent = LQGAgent(env)
    obs, _ = env.reset(seed=3)
    agent.reset()
    for _ in range(300):                      # past one 256-period noise block
        obs = env.step(agent.act(obs))[0]
    clone = pickle.loads(pickle.dumps(env))
    agent2 = pickle.loads(pickle.dumps(agent))
    for _ in range(300):
        step_a = env.step(agent.act(obs))
        step_b = clone.step(agent2.act(obs))
        np.testing.assert_array_equal(step_a[0], step_b[0])
        assert step_a[1:4] == step_b[1:4]
        assert step_a[4]["running_cost"] == step_b[4]["running_cost"]
        obs = step_a[0]
    # a fresh reset with a seed is the same too
    np.testing.assert_array_equal(env.reset(seed=5)[0], clone.reset(seed=5)[0])


# ---- reward, info, episode end ---------------------------------------------------------------------
def test_reward_is_exp_of_the_step_cost_and_zero_on_failure():
    env = gym.make(ID, reward_scale=5.0)
    obs, info = env.reset(seed=1)
    assert info["cost"] == 0.0 and info["running_cost"] == 0.0 and info["failure_reason"] == ""
    np.testing.assert_array_equal(info["y_true"], [0.0, 0.1])
    total, rewards = 0.0, []
    while True:
        obs, r, term, trunc, info = env.step(np.array([10.0], dtype=np.float32))   # full push
        total += info["cost"]
        rewards.append(r)
        if term or trunc:
            break
    assert term and not trunc
    assert info["failure_reason"] in ("pole_fell", "track_limit")
    assert rewards[-1] == 0.0
    assert all(0.0 < r <= 1.0 for r in rewards[:-1])
    assert info["running_cost"] == pytest.approx(total, rel=1e-12)
    np.testing.assert_array_equal(obs, info["state"][:2])          # noise-free after failure
    with pytest.raises(PendulumLQGError, match=r"^step:"):
        env.unwrapped.step(np.zeros(1))
    # a surviving step: r = exp(-c / (scale·T))
    env.reset(seed=1)
    _, r, _, _, info = env.step(np.zeros(1))
    assert r == pytest.approx(np.exp(-info["cost"] / (5.0 * 0.01)), rel=1e-15)
    # ... never the failure reward, even where exp underflows (c / (s·T) ≈ 2.6e6 here)
    tiny = gym.make(ID, reward_scale=1e-9)
    tiny.reset(seed=1)
    _, r, term, _, info = tiny.step(np.zeros(1))
    assert not term and np.exp(-info["cost"] / (1e-9 * 0.01)) == 0.0
    assert r == REWARD_FLOOR > 0.0


def test_a_closed_env_says_so():
    env = gym.make(ID)
    env.reset(seed=0)
    env.close()
    env.reset(seed=0)
    with pytest.raises(PendulumLQGError, match=r"^simulator: closed"):
        env.step(np.zeros(1))


@pytest.mark.parametrize(("kwargs", "param"), [
    ({"observation_mode": "pixels"}, "observation_mode"),
    ({"control_period": 0.0105}, "control_period"),
    ({"duration": -1.0}, "duration"),
    ({"noise_scale": -1.0}, "noise_scale"),
    ({"process_noise": "wind"}, "process_noise"),
    ({"process_noise": "force"}, "process_density"),
    ({"measurement_variance": [1.0, 2.0, 3.0]}, "measurement_variance"),
    ({"x0": (0.0, 0.1)}, "x0"),
    ({"x0": None}, "x0"),
    ({"x0_std": "wide"}, "x0_std"),
    ({"cost_Q": None}, "cost_Q"),
    ({"noise_scale": True}, "noise_scale"),
    ({"theta_max": 0.0}, "theta_max"),
    ({"reward_scale": 0.0}, "reward_scale"),
    ({"model_overrides": {"pole_weight": 1.0}}, "model: unknown key"),
    ({"model_overrides": {"pole_mass": -1.0}}, "pole_mass"),
    ({"width": 4000}, "width"),
    ({"render_mode": "human"}, "render_mode"),
])
def test_bad_keywords_raise_config_errors_naming_the_parameter(kwargs, param):
    with pytest.raises(ConfigError, match=rf"^{param}"):
        CartPoleLQGEnv(**kwargs)


def test_bad_reset_options_and_actions_are_errors():
    env = CartPoleLQGEnv()
    with pytest.raises(ConfigError, match=r"^options"):
        env.reset(seed=0, options={"x0": [0, 0, 0, 0]})
    env.reset(seed=0)
    with pytest.raises(PendulumLQGError, match=r"^action"):
        env.step(np.zeros(2))
    with pytest.raises(PendulumLQGError, match=r"^action"):
        env.step(np.array([np.nan]))
    with pytest.raises(ConfigError, match=r"^num_envs"):
        CartPoleLQGVectorEnv(0)


# ---- the LQG agent ---------------------------------------------------------------------------------
def _agent_episodes(env: gym.Env, agent: LQGAgent, seed: int, episodes: range,
                    ) -> list[tuple[bool, float, str]]:
    out = []
    for k in episodes:
        obs, _ = env.reset(seed=episode_seed(seed, k))
        agent.reset()
        term = trunc = False
        while not (term or trunc):
            obs, _, term, trunc, info = env.step(agent.act(obs))
        out.append((not term, info["running_cost"], info["failure_reason"]))
    return out


@pytest.mark.parametrize(("observer", "episodes", "kwargs"), [
    ("kalman", 20, {}),
    ("none", 3, {"observation_mode": "state"}),
    ("luenberger", 3, {}),
    ("kalman-predictor", 3, {}),
    ("kalman-tv", 3, {}),
    ("kalman-bucy", 3, {}),
    # a non-default problem: force noise, a random x0, a mismatched plant, other weights
    ("kalman", 4, {"process_noise": "force", "process_density": [0.02, 0.002],
                   "x0_std": (0.05, 0.02, 0.0, 0.0), "model_overrides": {"pole_mass_scale": 1.3},
                   "cost_Q": (2.0, 1.0, 0.5, 0.1), "cost_R": 0.5, "duration": 4.0}),
])
def test_agent_through_env_equals_run_episodes_exactly(observer, episodes, kwargs):
    assert set(OBSERVERS) >= {observer}
    env = gym.make(ID, **kwargs)
    agent = LQGAgent(env, observer=observer)
    got = _agent_episodes(env, agent, seed=11, episodes=range(episodes))
    base = env.unwrapped
    policy = design_policy(load_plant(), base.scenario.control_period, base.scenario.noise,
                           DesignSpec(observer=observer))            # what bench designs
    rows = run_episodes(base.plant, base.scenario, policy, seed=11, episodes=range(episodes)).rows
    want = [(r["success"], r["cost"], r["failure_reason"]) for r in rows]
    assert got == want                                                # bit for bit
    if observer == "luenberger":                                      # failures are covered too
        assert not all(s for s, _, _ in got)


@pytest.mark.parametrize("n", [pytest.param(24, id="24"),
                               pytest.param(200, id="200", marks=pytest.mark.slow)])
def test_agent_stabilises_99_percent_and_matches_bench_summary(n):
    """n seeded lecture episodes, DLQR + Kalman, through the (native vector) env API: ≥ 99 %
    balance (of 200; all of the quick loop's 24), and the batch run gives the same success rate
    and mean cost."""
    seed = 2024
    envs = gym.make_vec(ID, num_envs=n)
    agent = LQGAgent(envs, observer="kalman")
    obs, _ = envs.reset(seed=[episode_seed(seed, k) for k in range(n)])
    agent.reset()
    done = np.zeros(n, dtype=bool)
    success = np.zeros(n, dtype=bool)
    cost = np.zeros(n)
    restarting = np.zeros(0, dtype=np.int64)
    while not done.all():
        obs, _, term, trunc, info = envs.step(agent.act(obs))
        agent.reset(restarting)        # NEXT_STEP: these rows now show their reset observation
        ended = (term | trunc) & ~done
        success[ended] = ~term[ended]
        cost[ended] = info["running_cost"][ended]      # the ending step reports the final J
        done |= ended
        restarting = np.nonzero(term | trunc)[0]
    assert success.mean() >= 0.99
    base = envs.unwrapped
    policy = design_policy(load_plant(), base.scenario.control_period, base.scenario.noise)
    summary = summarize(run_episodes(base.plant, base.scenario, policy, seed=seed,
                                     episodes=range(n)).rows)
    assert summary["success_rate"] == success.mean()
    assert summary["cost"]["mean"] == pytest.approx(cost[success].mean(), rel=1e-12)


def test_agent_refuses_an_observation_mode_it_cannot_use():
    with pytest.raises(ConfigError, match=r"^observer: 'none' needs observation_mode='state'"):
        LQGAgent(gym.make(ID), observer="none")
    with pytest.raises(ConfigError, match=r"^observer: 'kalman' needs"):
        LQGAgent(gym.make(ID, observation_mode="state"), observer="kalman")
    with pytest.raises(ConfigError, match=r"^env"):
        LQGAgent(gym.make("CartPole-v1"))


# ---- vector envs -----------------------------------------------------------------------------------
def _vector_run(envs: gym.vector.VectorEnv, seed: object, actions: np.ndarray) -> list[tuple]:
    out = [envs.reset(seed=seed)]
    for a in actions:
        out.append(envs.step(a))
    return out


MODES = [gym.vector.AutoresetMode.NEXT_STEP, gym.vector.AutoresetMode.SAME_STEP]


@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("kwargs", [
    {"observation_mode": "measurement"},
    {"observation_mode": "state", "max_episode_steps": 17},
])
def test_native_vector_env_equals_single_envs(kwargs, mode):
    """Same seeds → the same episodes as SyncVectorEnv over single envs, through failures,
    truncations and autoresets, in each autoreset mode."""
    n = 5
    cfg = {"duration": 0.4, "x0_std": (0.5, 0.25, 0.5, 0.5), **kwargs}
    steps = kwargs.get("max_episode_steps")
    native = gym.make_vec(ID, num_envs=n, autoreset_mode=mode, **cfg)
    assert isinstance(native.unwrapped, CartPoleLQGVectorEnv)
    assert native.metadata["autoreset_mode"] == mode
    sync = gym.make_vec(ID, num_envs=n, vectorization_mode="sync",
                        vector_kwargs={"autoreset_mode": mode}, **cfg)
    if steps is not None:   # the sync sub-envs get their TimeLimit from make's keyword
        sync = gym.make_vec(ID, num_envs=n, vectorization_mode="sync", max_episode_steps=steps,
                            vector_kwargs={"autoreset_mode": mode},
                            **{k: v for k, v in cfg.items() if k != "max_episode_steps"})
    actions = np.random.default_rng(0).uniform(-10, 10, size=(90, n, 1))
    a = _vector_run(native, 100, actions)
    b = _vector_run(sync, 100, actions)
    ended = 0
    for sa, sb in zip(a, b, strict=True):
        np.testing.assert_array_equal(sa[0], sb[0])                     # observations
        for x, y in zip(sa[1:-1], sb[1:-1], strict=True):               # reward, term, trunc
            np.testing.assert_array_equal(x, y)
        ia, ib = sa[-1], sb[-1]
        for key in ("cost", "running_cost", "state", "y_true", "failure_reason", "time",
                    "force"):
            np.testing.assert_array_equal(ia[key], ib[key])
        if mode == gym.vector.AutoresetMode.NEXT_STEP and len(sa) == 5:
            ended += int((sa[2] | sa[3]).sum())
        if "final_obs" in ib:
            ended += int(ib["_final_obs"].sum())
            np.testing.assert_array_equal(ia["_final_obs"], ib["_final_obs"])
            for r in np.nonzero(ib["_final_obs"])[0]:
                np.testing.assert_array_equal(ia["final_obs"][r], ib["final_obs"][r])
                assert ia["final_info"]["running_cost"][r] == ib["final_info"]["running_cost"][r]
    assert ended >= 2 * n            # several failures/truncations and autoresets happened
    terms = np.array([s[2] for s in a[1:]])
    truncs = np.array([s[3] for s in a[1:]])
    assert terms.any() and truncs.any()


@pytest.mark.parametrize("observer", OBSERVERS)
def test_agent_on_native_vector_env_equals_agent_on_sync_env_through_autoresets(observer):
    """Every observer (the time-varying Kalman filter too) restarts single sub-envs: the batched
    agent on the native env acts exactly as on SyncVectorEnv's single envs."""
    n = 4
    cfg = {"duration": 0.3, "x0_std": (0.5, 0.3, 0.5, 0.5),
           "observation_mode": "state" if observer == "none" else "measurement"}
    same = gym.vector.AutoresetMode.SAME_STEP
    native = gym.make_vec(ID, num_envs=n, autoreset_mode=same, **cfg)
    sync = gym.make_vec(ID, num_envs=n, vectorization_mode="sync",
                        vector_kwargs={"autoreset_mode": same}, **cfg)
    runs = []
    for envs in (native, sync):
        agent = LQGAgent(native, observer=observer)
        obs, _ = envs.reset(seed=3)
        agent.reset()
        actions, ends = [], 0
        for _ in range(70):
            a = agent.act(obs)
            actions.append(a.copy())
            obs, _, term, trunc, _ = envs.step(a)
            ends += int((term | trunc).sum())
            agent.reset(np.nonzero(term | trunc)[0])
        runs.append((np.array(actions), ends))
    np.testing.assert_array_equal(runs[0][0], runs[1][0])
    assert runs[0][1] == runs[1][1] >= 2 * n          # sub-envs restarted at different steps


def test_native_vector_env_unseeded_resets_continue_like_sync():
    """reset() without a seed (or with None entries) continues each sub-env's generator."""
    cfg = {"num_envs": 3, "x0_std": (0.1, 0.1, 0.0, 0.0)}
    native = gym.make_vec(ID, **cfg)
    sync = gym.make_vec(ID, vectorization_mode="sync", **cfg)
    outs = []
    for envs in (native, sync):
        envs.reset(seed=7)
        for _ in range(3):
            envs.step(np.zeros((3, 1)))
        o1, i1 = envs.reset()
        o2, i2 = envs.reset(seed=[None, 4, None])
        outs.append((o1, i1["state"], o2, i2["state"]))
    for x, y in zip(*outs, strict=True):
        np.testing.assert_array_equal(x, y)
    assert not np.array_equal(outs[0][0], outs[0][2])


def test_native_vector_env_seed_list_equals_single_env_resets():
    seeds = [5, 9, 2]
    envs = gym.make_vec(ID, num_envs=3, x0_std=(0.1, 0.1, 0.0, 0.0))
    obs, info = envs.reset(seed=seeds)
    for i, s in enumerate(seeds):
        single_obs, single_info = gym.make(ID, x0_std=(0.1, 0.1, 0.0, 0.0)).reset(seed=s)
        np.testing.assert_array_equal(obs[i], single_obs)
        np.testing.assert_array_equal(info["state"][i], single_info["state"])
    with pytest.raises(ConfigError, match=r"^seed"):
        envs.reset(seed=[1, 2])
    assert envs.metadata["autoreset_mode"] == gym.vector.AutoresetMode.NEXT_STEP   # the default


# ---- rendering -------------------------------------------------------------------------------------
def _frames(tmp_path) -> np.ndarray:
    if GL:
        pair = []
        for x0 in ((0.0, 0.4, 0.0, 0.0), (1.0, -0.4, 0.0, 0.0)):
            env = gym.make(ID, render_mode="rgb_array", x0=x0)
            env.reset(seed=0)
            pair.append(env.render())
            env.close()
        return np.stack(pair)
    pytest.skip("mujoco.Renderer cannot be created (no OpenGL platform)")


def test_render_rgb_array_frames_cart_and_pole(tmp_path):
    frames = _frames(tmp_path)
    assert frames.shape == (2, 480, 640, 3) and frames.dtype == np.uint8
    for f in frames:
        assert f.std() > 10                                  # not blank
    assert np.abs(frames[0].astype(int) - frames[1]).mean() > 1   # the state is what is drawn
    # the pole (orange, rgba 0.9 0.55 0.15) is in view
    orange = (frames[..., 0] > 150) & (frames[..., 1] > 70) & (frames[..., 1] < 170) \
        & (frames[..., 2] < 90)
    assert orange[0].sum() > 50 and orange[1].sum() > 50


def test_render_without_mode_warns_and_returns_none():
    env = CartPoleLQGEnv()
    env.reset(seed=0)
    with pytest.warns(UserWarning, match="render_mode"):
        assert env.render() is None


# ---- Gymnasium's vector conventions: wrappers, reset masks, rendering, RL keywords ----------------
def _vector_wrappers(tmp_path):
    """Every wrapper of gymnasium.wrappers.vector, with arguments that make sense for a Box."""
    from gymnasium.wrappers import vector as V

    return {
        "DictInfoToList": lambda e: V.DictInfoToList(e),
        "TransformObservation": lambda e: V.TransformObservation(e, lambda o: 2.0 * o),
        "FilterObservation": lambda e: V.FilterObservation(e, filter_keys=["p"]),
        "FlattenObservation": lambda e: V.FlattenObservation(e),
        "GrayscaleObservation": lambda e: V.GrayscaleObservation(e),
        "ResizeObservation": lambda e: V.ResizeObservation(e, shape=(2,)),
        "ReshapeObservation": lambda e: V.ReshapeObservation(e, shape=(2, 1)),
        "RescaleObservation": lambda e: V.RescaleObservation(e, min_obs=-1.0, max_obs=1.0),
        "DtypeObservation": lambda e: V.DtypeObservation(e, dtype=np.float32),
        "NormalizeObservation": lambda e: V.NormalizeObservation(e),
        "TransformAction": lambda e: V.TransformAction(e, lambda a: 0.5 * a),
        "ClipAction": lambda e: V.ClipAction(e),
        "RescaleAction": lambda e: V.RescaleAction(e, min_action=-1.0, max_action=1.0),
        "TransformReward": lambda e: V.TransformReward(e, lambda r: 2.0 * r),
        "ClipReward": lambda e: V.ClipReward(e, min_reward=0.0, max_reward=0.9),
        "NormalizeReward": lambda e: V.NormalizeReward(e),
        "RecordEpisodeStatistics": lambda e: V.RecordEpisodeStatistics(e),
        "RecordVideo": lambda e: V.RecordVideo(e, video_folder=str(tmp_path / "video")),
        "HumanRendering": lambda e: V.HumanRendering(e),
        "VectorizeTransformObservation": lambda e: V.VectorizeTransformObservation(
            e, wrapper=gym.wrappers.TransformObservation, func=lambda o: o + 1.0,
            observation_space=e.single_observation_space),
        "VectorizeTransformAction": lambda e: V.VectorizeTransformAction(
            e, wrapper=gym.wrappers.ClipAction),
        "VectorizeTransformReward": lambda e: V.VectorizeTransformReward(
            e, wrapper=gym.wrappers.TransformReward, func=lambda r: r - 1.0),
    }


def _wrapped_run(envs, steps=60):
    obs, info = envs.reset(seed=3)
    out = [(obs, info)]
    rng = np.random.default_rng(1)
    for _ in range(steps):
        out.append(envs.step(envs.action_space.sample() * 0 + rng.uniform(
            -1, 1, size=envs.action_space.shape).astype(np.float32)))
    return out


def test_every_vector_wrapper_that_works_on_sync_works_on_the_native_env(tmp_path):
    """Gymnasium's vector wrappers over the native env give SyncVectorEnv's results exactly."""
    cfg = {"num_envs": 3, "duration": 0.2, "x0_std": (0.3, 0.2, 0.3, 0.3)}
    from gymnasium.wrappers import vector as V

    wrappers = _vector_wrappers(tmp_path)
    assert set(wrappers) >= {n for n in V.__all__ if n not in ("JaxToNumpy", "JaxToTorch",
                                                                "NumpyToTorch", "ArrayConversion")}
    worked = []
    for name, wrap in wrappers.items():
        with warnings.catch_warnings():     # wrappers' own advice (e.g. float32 casts) aside
            warnings.simplefilter("ignore")
            try:
                sync_run = _wrapped_run(wrap(gym.make_vec(ID, vectorization_mode="sync", **cfg)))
            except Exception:      # not applicable to a Box observation (or needs a display)
                continue
            native_run = _wrapped_run(wrap(gym.make_vec(ID, **cfg)))
        for a, b in zip(native_run, sync_run, strict=True):
            for x, y in zip(a[:-1], b[:-1], strict=True):
                np.testing.assert_array_equal(np.asarray(x), np.asarray(y), err_msg=name)
        worked.append(name)
    assert {"NormalizeObservation", "FlattenObservation", "NormalizeReward", "ClipAction",
            "RescaleAction", "RecordEpisodeStatistics", "DictInfoToList",
            "VectorizeTransformObservation"} <= set(worked), worked
    print(f"\nvector wrappers that work on SyncVectorEnv and on the native env: {worked}")


def test_reset_mask_and_disabled_autoreset_follow_sync():
    cfg = {"num_envs": 3, "duration": 0.1, "x0_std": (0.3, 0.2, 0.3, 0.3)}
    disabled = gym.vector.AutoresetMode.DISABLED
    runs = []
    for envs in (gym.make_vec(ID, autoreset_mode="disabled", **cfg),
                 gym.make_vec(ID, vectorization_mode="sync",
                              vector_kwargs={"autoreset_mode": disabled}, **cfg)):
        assert envs.metadata["autoreset_mode"] == disabled
        obs, _ = envs.reset(seed=5)
        trace = [obs]
        for _ in range(25):
            obs, r, term, trunc, _ = envs.step(np.full((3, 1), 1.0, dtype=np.float32))
            trace += [obs, r]
            ended = term | trunc
            if ended.any():
                obs, info = envs.reset(options={"reset_mask": ended})
                trace += [obs, info["_state"]]
        runs.append(trace)
    for a, b in zip(*runs, strict=True):
        np.testing.assert_array_equal(a, b)
    native = gym.make_vec(ID, autoreset_mode="disabled", **cfg)
    native.reset(seed=0)
    for _ in range(10):
        native.step(np.zeros((3, 1), dtype=np.float32))
    with pytest.raises(PendulumLQGError, match=r"step: sub-env\(s\) \[0, 1, 2\] ended"):
        native.step(np.zeros((3, 1), dtype=np.float32))


def test_step_before_reset_and_bad_actions_are_clear_errors():
    with pytest.raises(PendulumLQGError, match="step: call reset"):
        CartPoleLQGEnv().step(np.zeros(1))
    vec = CartPoleLQGVectorEnv(4)
    with pytest.raises(PendulumLQGError, match="step: call reset"):
        vec.step(np.zeros((4, 1)))
    vec.reset(seed=0)
    with pytest.raises(PendulumLQGError, match=r"action: expected shape \(4, 1\)"):
        vec.step(np.zeros((2, 2)))


def test_normalized_actions_and_the_applied_force_in_info():
    plain = gym.make(ID)
    normalized = gym.make(ID, normalize_action=True)
    assert normalized.action_space == gym.spaces.Box(-1.0, 1.0, (1,), np.float32)
    plain.reset(seed=0)
    normalized.reset(seed=0)
    for a in (0.25, -1.0, 0.9):
        o1, r1, *_, i1 = plain.step(np.array([10.0 * a]))
        o2, r2, *_, i2 = normalized.step(np.array([a]))
        np.testing.assert_array_equal(o1, o2)
        assert r1 == r2 and i1["force"] == i2["force"] == pytest.approx(10.0 * a)
    _, _, _, _, info = plain.step(np.array([25.0]))            # out of range: clipped
    assert info["force"] == 10.0
    vec = gym.make_vec(ID, num_envs=2, normalize_action=True)
    vec.reset(seed=0)
    _, _, _, _, info = vec.step(np.array([[0.5], [3.0]]))
    np.testing.assert_array_equal(info["force"], [5.0, 10.0])
    with pytest.raises(ConfigError, match="normalize_action"):
        gym.make(ID, normalize_action="yes")


def test_vector_env_renders_one_frame_per_sub_env():
    code = textwrap.dedent("""
        import numpy as np, gymnasium as gym, pendulum_lqg
        kw = dict(render_mode="rgb_array", width=160, height=120, x0_std=(0.5, 0.2, 0, 0))
        vec = gym.make_vec(pendulum_lqg.ENV_ID, num_envs=2, **kw)
        vec.reset(seed=[1, 2])
        frames = vec.render()
        single = gym.make(pendulum_lqg.ENV_ID, **kw)
        single.reset(seed=2)
        one = single.render()
        print(len(frames), frames[0].shape, bool((frames[1] == one).all()),
              bool((frames[0] != frames[1]).any()))
    """)
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120, env=env)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["2", "(120,", "160,", "3)", "True", "True"]


def test_headless_machine_gets_a_working_gl_backend_automatically():
    """No MUJOCO_GL and no display: importing pendulum_lqg first picks EGL, so check_env with its
    render check and render() work; with MuJoCo imported first on GLFW, render says what to set."""
    code = textwrap.dedent("""
        import os, warnings
        warnings.simplefilter("ignore")
        import pendulum_lqg, gymnasium as gym
        from gymnasium.utils.env_checker import check_env
        env = gym.make(pendulum_lqg.ENV_ID, render_mode="rgb_array")
        check_env(env.unwrapped)
        env.reset(seed=0)
        print(os.environ["MUJOCO_GL"], env.render().shape)
    """)
    env = {k: v for k, v in os.environ.items()
           if k not in ("DISPLAY", "WAYLAND_DISPLAY", "MUJOCO_GL")}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120, env=env)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["egl", "(480,", "640,", "3)"]
    forced = textwrap.dedent("""
        import warnings
        warnings.simplefilter("ignore")
        import mujoco, pendulum_lqg, gymnasium as gym
        env = gym.make(pendulum_lqg.ENV_ID, render_mode="rgb_array")
        env.reset(seed=0)
        try:
            env.render()
        except Exception as exc:
            print(type(exc).__name__, str(exc).count(chr(10)), "MUJOCO_GL=egl" in str(exc))
    """)
    out = subprocess.run([sys.executable, "-c", forced], capture_output=True, text=True,
                         timeout=120, env={**env, "MUJOCO_GL": "glfw"})
    assert out.stdout.split() == ["PendulumLQGError", "0", "True"], out.stderr


def test_both_envs_take_their_keywords_from_one_list():
    """The declarations are the one keyword list: an unknown keyword is a one-line ConfigError
    naming it for the single and the vector env alike, and both get the same defaults."""
    from pendulum_lqg.envs.config import EnvConfig
    from pendulum_lqg.envs.single import CartPoleLQGEnv
    from pendulum_lqg.envs.vector import CartPoleLQGVectorEnv
    from pendulum_lqg.errors import ConfigError

    for make in (lambda: CartPoleLQGEnv(bogus=1), lambda: CartPoleLQGVectorEnv(2, bogus=1)):
        with pytest.raises(ConfigError, match=r"^bogus: not a keyword of the environment"):
            make()
    from pendulum_lqg.problem.env import env_keywords

    defaults = {d.name: d.default for d in env_keywords()}
    assert defaults["duration"] == 10.0 and defaults["control_period"] == 0.01
    single, vector = CartPoleLQGEnv(), CartPoleLQGVectorEnv(2)
    assert single.scenario == vector.scenario == EnvConfig.build().scenario
    vector.close()
