"""Defaults and names written once: the env, the CLI and the experiment files take the episode's
defaults from Scenario's; the CLI's numpy-free list of observers is the registry's; the public API
loads lazily; the Wilson interval agrees with SciPy's binomial test."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import pytest

from pendulum_lqg.cli.commands import scenario_from_args
from pendulum_lqg.cli.parser import build_parser
from pendulum_lqg.core.metrics import wilson_interval
from pendulum_lqg.core.scenario import Scenario
from pendulum_lqg.envs.config import EnvConfig
from pendulum_lqg.names import OBSERVERS
from pendulum_lqg.policies.observers import OBSERVER_BUILDERS


def test_the_env_and_the_cli_default_to_scenario_defaults():
    assert EnvConfig.build().scenario == Scenario()
    args = build_parser().parse_args(["run"])
    assert scenario_from_args(args) == Scenario()


def test_a_changed_scenario_default_reaches_the_env_and_the_cli():
    """The env's keywords and the CLI's options read the one module of defaults when they are
    built, so a new default there is the new default everywhere."""
    code = textwrap.dedent("""
        from pendulum_lqg.problem import defaults
        defaults.THETA_MAX, defaults.DURATION = 0.25, 4.0
        from pendulum_lqg.core.scenario import Scenario
        from pendulum_lqg.envs.config import EnvConfig
        from pendulum_lqg.cli.parser import build_parser
        from pendulum_lqg.cli.commands import scenario_from_args
        s = Scenario()
        print(s.theta_max, s.duration, EnvConfig.build().scenario == s,
              scenario_from_args(build_parser().parse_args(["run"])) == s)
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120, check=True).stdout.split()
    assert out == ["0.25", "4.0", "True", "True"]


def test_the_cli_list_of_observers_is_the_registry_of_builders():
    assert list(OBSERVERS) == list(OBSERVER_BUILDERS)


def test_the_public_api_loads_lazily_and_resolves_every_name():
    code = textwrap.dedent("""
        import sys
        import pendulum_lqg
        heavy = [m for m in ("numpy", "gymnasium", "mujoco", "scipy") if m in sys.modules]
        missing = [n for n in pendulum_lqg.__all__ if getattr(pendulum_lqg, n, None) is None]
        print(heavy, missing)
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=120, check=True).stdout.strip()
    assert out == "[] []"


def test_the_0_3_paths_sim_and_agent_warn_and_still_work():
    for module, name in (("pendulum_lqg.sim", "Scenario"), ("pendulum_lqg.agent", "LQGAgent")):
        sys.modules.pop(module, None)
        with pytest.warns(DeprecationWarning, match=module):
            mod = __import__(module, fromlist=[name])
        assert getattr(mod, name) is getattr(__import__("pendulum_lqg"), name)


@pytest.mark.parametrize(("k", "n"), [(0, 10), (3, 10), (95, 100), (100, 100), (1, 7), (500, 1000)])
def test_wilson_interval_is_scipys(k, n):
    stats = pytest.importorskip("scipy.stats")
    ci = stats.binomtest(k, n).proportion_ci(confidence_level=0.95, method="wilson")
    lo, hi = wilson_interval(k, n)
    assert lo == pytest.approx(ci.low, abs=1e-12) and hi == pytest.approx(ci.high, abs=1e-12)
