"""The optional members of a policy, read by one function for the runner, the trajectories and
the scoreboard: what an absent or odd member means, and that the runner follows it."""

from __future__ import annotations

import numpy as np

from pendulum_lqg.core.protocol import OptionalMembers, current_estimate, optional_members
from pendulum_lqg.core.runner import MIN_SHARD_ROWS, run_episodes, shard_count
from pendulum_lqg.core.scenario import Scenario
from pendulum_lqg.policies.loading import build_policy


class _Zero:
    """The smallest policy: zero force, no optional member."""

    def reset(self, n, x_hat0=None):
        self.n = n

    def act(self, y):
        return np.zeros(y.shape[0])


def test_absent_members_take_their_defaults():
    assert optional_members(_Zero()) == OptionalMembers(needs_state=False, independent_rows=False,
                                                        select=None, estimator=None)
    assert current_estimate(_Zero()) is None


def test_only_true_promises_independent_rows_and_only_a_callable_selects():
    odd = _Zero()
    odd.independent_rows = 1          # truthy, but not the promise
    odd.select = "rows"               # not a method
    members = optional_members(odd)
    assert members.independent_rows is False and members.select is None
    n = 4 * MIN_SHARD_ROWS
    assert shard_count(n, 4, "rollout", odd) == 1
    odd.independent_rows = True
    assert shard_count(n, 4, "rollout", odd) == 4


def test_a_builtin_policy_reads_as_its_own_members(plant):
    scenario = Scenario(duration=0.05)
    kalman = build_policy("dlqr+kalman", plant=plant, scenario=scenario)
    members = optional_members(kalman)
    assert members.needs_state is False and members.independent_rows is True
    assert members.select == kalman.select and members.estimator is kalman.estimator
    assert optional_members(build_policy("dlqr+none", plant=plant, scenario=scenario)).needs_state


def test_the_runner_logs_the_estimator_only_of_a_policy_that_selects_its_rows(plant):
    """Without ``select`` the runner feeds the whole batch, so the estimator's rows are not the
    running episodes': its intermediates are not logged (nan), while a selecting policy's are."""
    scenario = Scenario(duration=0.05)
    kalman = build_policy("dlqr+kalman", plant=plant, scenario=scenario)

    class Unselecting:
        """The Kalman policy without its ``select``: every other member passed through."""

        def __init__(self, inner):
            self._inner = inner

        def __getattr__(self, name):
            if name == "select":
                raise AttributeError(name)
            return getattr(self._inner, name)

    kw = dict(seed=3, episodes=range(2), trajectory=True, nthread=1)
    selecting = run_episodes(plant, scenario, kalman, **kw).trajectories
    whole = run_episodes(plant, scenario, Unselecting(kalman), **kw).trajectories
    assert np.all(np.isfinite(selecting[0].x_prior)) and np.all(np.isnan(whole[0].x_prior))
    # the estimate itself is read through current_estimate in both cases, row for row the same
    np.testing.assert_array_equal(selecting[1].x_hat, whole[1].x_hat)
