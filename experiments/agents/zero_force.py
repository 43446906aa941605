"""The do-nothing Gymnasium agent: 0 N at every step. The floor of the leaderboard::

    uv run pendulum-lqg score --agent experiments/agents/zero_force.py:make --suite lecture
"""

from __future__ import annotations

import numpy as np


class ZeroForce:
    """Applies no force: the pole falls from θ₀ = 0.1 rad within about a second."""

    def reset(self) -> None:
        pass

    def act(self, observation: np.ndarray) -> np.ndarray:
        return np.zeros(1)


def make(env) -> ZeroForce:
    """The agent factory ``f(env)``."""
    return ZeroForce()
