"""Shared fixtures and helpers of the test suite.

MuJoCo reads ``MUJOCO_GL`` once, when it is first imported, and its default (GLFW) needs a display:
this file is imported before any test module, so it chooses the headless EGL backend here (unless
the caller chose one) and no test file has to import in a particular order.
"""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "egl")
# Ray reads this when it is imported, and tests/bench/test_executors_ray.py imports Ray before the executor
# can set it (pendulum_lqg.bench.executors explains why workers stay in this environment).
os.environ.setdefault("RAY_ENABLE_UV_RUN_RUNTIME_ENV", "0")

import pytest

from pendulum_lqg.model.plant import load_plant


@pytest.fixture(scope="session")
def plant():
    return load_plant()


def stationary_monte_carlo(plant, scenario, policy, *, episodes, burn_in, seed, backend="rollout"):
    """Per-episode time averages of x², u² and (x̂ − x)² at the sampling instants after
    ``burn_in`` seconds, through the core's loop with every limit off: their mean over the
    episodes and its standard error, arrays ordered ``[x (n), u, x̂ − x (n)]`` (episodes are
    independent, so the interval holds whatever the correlation within an episode)."""
    import math

    import numpy as np

    from pendulum_lqg.core.loop import Simulator
    from pendulum_lqg.core.seeding import episode_generators, episode_seeds

    gens = episode_generators(episode_seeds(seed, range(episodes)))
    burn = round(burn_in / scenario.control_period)
    with Simulator(plant, scenario, backend=backend, streamed_metrics=False) as sim:
        n = sim.nx
        sums = np.zeros((episodes, 2 * n + 1))
        x0 = sim.reset(gens, private_generators=True)
        policy.reset(episodes, x_hat0=x0.copy())
        for k in range(sim.n_periods):
            y = sim.measure()
            x = sim.x.copy()
            u = policy.act(y)
            if k >= burn:
                sums[:, :n] += x * x
                sums[:, n] += u * u
                sums[:, n + 1:] += (policy.x_hat - x) ** 2
            assert not sim.step(u).failed.any()          # every limit is off
    per_episode = sums / (sim.n_periods - burn)
    return per_episode.mean(axis=0), per_episode.std(axis=0, ddof=1) / math.sqrt(episodes)


def run_cli(capsys, argv):
    """``main(argv)``'s exit status and its stderr (argparse's own errors exit via SystemExit)."""
    from pendulum_lqg.cli import main

    try:
        status = main(argv)
    except SystemExit as exc:
        status = exc.code
    return status, capsys.readouterr().err


def assert_one_line_error(status, err, name):
    """Exit status 2, no traceback, one line ``error: NAME…``."""
    assert status == 2, err
    assert "Traceback" not in err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith(f"error: {name}"), err


#: Floats stored in the repository were computed on another machine: another CPU makes OpenBLAS
#: pick another kernel, whose products round differently (seen: 1e-15 … 4e-14 relative after a
#: closed loop of 200 periods). They are compared to this tolerance, stated once here; what cannot
#: drift — success, failure reason, the time of failure (a count of physics steps) — is compared
#: exactly. Bit-for-bit comparisons are kept for paths computed in the same test run.
STORED_RTOL, STORED_ATOL = 1e-10, 1e-12
#: Row fields that must match stored rows exactly on any machine.
EXACT_FIELDS = ("episode", "seed", "success", "failure_reason", "time_to_failure")


def _as_float(value):
    return float.fromhex(value) if isinstance(value, str) and value.startswith(("0x", "-0x")) \
        else value


def assert_close_to_stored(now, stored, where="stored"):
    """``now`` equals ``stored`` (nested dicts and lists; floats may be ``float.hex`` strings) with
    floats within :data:`STORED_RTOL` / :data:`STORED_ATOL` and :data:`EXACT_FIELDS` exact."""
    import math

    if isinstance(stored, dict):
        assert isinstance(now, dict) and now.keys() == stored.keys(), where
        for key in stored:
            if key in EXACT_FIELDS:
                assert _as_float(now[key]) == _as_float(stored[key]) or (
                    isinstance(_as_float(now[key]), float) and math.isnan(_as_float(now[key]))
                    and math.isnan(_as_float(stored[key]))), f"{where}.{key}"
            else:
                assert_close_to_stored(now[key], stored[key], f"{where}.{key}")
        return
    if isinstance(stored, list):
        assert isinstance(now, list) and len(now) == len(stored), where
        for i, (a, b) in enumerate(zip(now, stored, strict=True)):
            assert_close_to_stored(a, b, f"{where}[{i}]")
        return
    a, b = _as_float(now), _as_float(stored)
    if isinstance(b, float) and not isinstance(b, bool):
        assert isinstance(a, float), where
        assert (math.isnan(a) and math.isnan(b)) or math.isclose(
            a, b, rel_tol=STORED_RTOL, abs_tol=STORED_ATOL), f"{where}: {a!r} vs stored {b!r}"
    else:
        assert a == b, f"{where}: {a!r} vs stored {b!r}"


#: ``python -c`` code running the CLI with Ctrl-C raising ``KeyboardInterrupt``: a process started
#: from a background job begins with SIGINT ignored, as does every child it starts, and Python
#: installs its own handler only when SIGINT is at its default — so a test that interrupts a CLI
#: run would see it finish instead, whenever pytest itself runs in the background.
_INTERRUPTIBLE_CLI = ("import runpy, signal; signal.signal(signal.SIGINT, signal.default_int_handler); "
                      "runpy.run_module('pendulum_lqg.cli', run_name='__main__', alter_sys=True)")


def interruptible_cli(*args):
    """The command line of ``python -m pendulum_lqg.cli ARGS`` that a SIGINT interrupts."""
    import sys
    return [sys.executable, "-c", _INTERRUPTIBLE_CLI, *map(str, args)]


def load_benchmark_script(stem: str, alias: str):  # the measurement scripts of benchmarks/
    """The module of ``benchmarks/STEM.py`` (a script, not a package module), imported under
    ``alias`` and kept in ``sys.modules`` so that pickling and relative lookups find it."""
    import importlib.util
    import sys
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "benchmarks" / f"{stem}.py"
    spec = importlib.util.spec_from_file_location(alias, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[alias] = module
    spec.loader.exec_module(module)
    return module


@pytest.fixture
def few_curve_episodes(monkeypatch):
    """Training runs' learning curves on 4 episodes instead of 20: the tests check what a point
    is, not its precision (``pendulum_lqg.learn.runs.eval_suite`` reads the constant when called)."""
    from pendulum_lqg.learn import runs

    monkeypatch.setattr(runs, "EVAL_EPISODES", 4)
