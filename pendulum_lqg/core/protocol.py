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

The optional members are read by one function, :func:`optional_members` (and the estimate of the
sample by :func:`current_estimate`), which the runner, the trajectories and the scoreboard share:
one place says what an absent member means.

The factory of a plug-in, :class:`~pendulum_lqg.policies.loading.PolicyFactory`, lives beside the loader
(it is called with a :class:`~pendulum_lqg.policies.loading.PolicyContext`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
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


@dataclass(frozen=True)
class OptionalMembers:
    """A policy's optional members, read once (:func:`optional_members`).

    Attributes
    ----------
    needs_state : ``act`` receives the true state (n, 4) instead of ``y`` (absent: False)
    independent_rows : the promise that rows evolve independently and the object deep-copies, so
        the runner may shard a batch (only the value ``True`` promises; absent: False)
    select : the bound ``select(rows)``, or ``None`` when the policy has none (the runner then
        keeps feeding the whole batch)
    estimator : the object whose ``x_prior``, ``innovation`` and ``P`` recordings log, or ``None``
    """

    needs_state: bool = False
    independent_rows: bool = False
    select: Callable[[np.ndarray], None] | None = None
    estimator: object | None = None


def optional_members(policy: object) -> OptionalMembers:
    """The optional members of ``policy`` (module docstring), an absent one at its default."""
    select = getattr(policy, "select", None)
    return OptionalMembers(needs_state=bool(getattr(policy, "needs_state", False)),
                           independent_rows=getattr(policy, "independent_rows", False) is True,
                           select=select if callable(select) else None,
                           estimator=getattr(policy, "estimator", None))


def current_estimate(policy: object) -> np.ndarray | None:
    """``policy.x_hat``, the (n, 4) estimate used at this sample, or ``None`` without one: read
    after each ``act``, since it changes every period."""
    return getattr(policy, "x_hat", None)
