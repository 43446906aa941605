"""The policy protocol the core drives: what any controller — built-in or plug-in — provides.

A policy is a *batched* object over the rows of the running batch::

    policy.reset(n)                 # n episodes start (reset(n, x_hat0=…) with estimate0 = "true")
    u = policy.act(y)               # y (n, 2) = [p, θ] sampled at the start of the period → u (n,) [N]

and optionally::

    policy.select(rows)             # keep only these rows of the *current* batch (ended episodes go)
    policy.needs_state              # True → act receives the true state (n, 4) instead of y
    policy.x_hat                    # (n, 4) the estimate used at this sample, read right after act
    policy.estimator                # an object with x_prior, innovation, P (recordings log them)
    policy.independent_rows         # True: rows evolve independently and the object deep-copies,
                                    # so the runner may run shards in threads, one copy each

The core saturates ``u`` after ``act`` (:func:`~pendulum_lqg.core.rules.saturate`): an observer
that models the plant should be fed the saturated force. Under dropouts or a measurement delay,
rows of ``y`` are ``nan`` for samples that did not arrive.

The factory of a plug-in, :class:`~pendulum_lqg.policies.loading.PolicyFactory`, lives beside the loader
(it is called with a :class:`~pendulum_lqg.policies.loading.PolicyContext`).
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np


@runtime_checkable
class PolicyProtocol(Protocol):
    """The members every policy has (:mod:`pendulum_lqg.core.protocol` lists the optional ones)."""

    def reset(self, n: int, x_hat0: np.ndarray | None = None) -> None:
        """Start ``n`` episodes. ``x_hat0`` (n, 4), the true initial states, is passed only with
        ``estimate0 = "true"``: a policy never run that way may take ``n`` alone."""
        ...

    def act(self, y: np.ndarray) -> np.ndarray:
        """Forces (n,) [N] for the measurements ``y`` (n, 2) (or states (n, 4) with
        ``needs_state``)."""
        ...


class SelectablePolicyProtocol(PolicyProtocol, Protocol):
    """A policy that can drop rows when episodes end."""

    def select(self, rows: np.ndarray) -> None:
        """Keep only ``rows`` (indices into the current batch, in order)."""
        ...
