"""Plug-ins on every plant: the :class:`~pendulum_lqg.policies.loading.PolicyContext` of a plant
file has the plant's sizes, and a plug-in that returns the built-in design plays the built-in's
episodes to the last bit (``run --plant NAME|FILE --policy FILE.py:ATTR``)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from pendulum_lqg.cli import main
from pendulum_lqg.model.catalog import load_named_plant
from pendulum_lqg.policies.loading import PolicyContext
from pendulum_lqg.policies.lti import lti_scenario

PLUGIN = '''
from pendulum_lqg.policies.lti import design_lti_policy


def make(ctx):
    """The built-in dlqr+kalman, designed from the context's plant and limit."""
    return design_lti_policy(ctx.plant, "dlqr+kalman", u_max=ctx.u_max)
'''


@pytest.mark.parametrize(("ref", "sizes"), [("double-cartpole", (6, 1, 3)),
                                            ("experiments/lti/two_mass.toml", (4, 2, 2))])
def test_the_context_of_a_plant_file_has_the_plant_s_sizes(ref, sizes):
    plant = load_named_plant(ref, what="--plant")
    ctx = PolicyContext.build(plant, lti_scenario(plant))
    n, m, p = sizes
    assert ctx.A.shape == ctx.Phi.shape == ctx.Wd.shape == ctx.Q.shape == ctx.W.shape == (n, n)
    assert ctx.B.shape == ctx.Gamma.shape == ctx.N.shape == (n, m)
    assert ctx.C.shape == (p, n) and ctx.V.shape == (p, p) and ctx.R.shape == (m, m)
    assert ctx.layout.n == n and ctx.layout.m == m and ctx.layout.p == p
    np.testing.assert_array_equal(ctx.Phi, plant.sampled(ctx.dt)[0])
    np.testing.assert_allclose(ctx.W * ctx.dt, ctx.Wd, rtol=1e-15)


@pytest.mark.parametrize("ref", ["double-cartpole", "experiments/lti/two_mass.toml"])
def test_a_plugin_on_a_plant_file_plays_the_built_in_s_episodes(ref, tmp_path, capsys,
                                                                 monkeypatch):
    (tmp_path / "plug.py").write_text(PLUGIN)
    plant = str(Path.cwd() / ref) if ref.endswith(".toml") else ref     # before the chdir
    args = ["run", "--plant", plant, "--episodes", "3", "--duration", "1", "--json"]
    monkeypatch.chdir(tmp_path)
    assert main([*args, "--policy", "dlqr+kalman"]) == 0
    builtin = json.loads(capsys.readouterr().out)["episodes"]
    assert main([*args, "--policy", "plug.py:make"]) == 0
    plugin = json.loads(capsys.readouterr().out)["episodes"]
    assert plugin == builtin
    assert all(r["success"] for r in plugin)
