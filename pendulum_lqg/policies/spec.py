"""The design choices of a built-in policy: controller, observer, weights and poles
(:class:`DesignSpec`), checked when made."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np

from pendulum_lqg import design
from pendulum_lqg.design.checks import as_poles
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.names import CONTROLLERS, OBSERVERS
from pendulum_lqg.problem.declare import (
    Converted,
    NonNegative,
    check,
    config_vector,
    positive_number,
)


def _vector4(name: str, value: object) -> tuple[float, ...]:
    """The diagonal of a 4×4 weight or covariance: 4 numbers ≥ 0 (one number repeated)."""
    return config_vector(name, value, 4, nonneg=True)


def _non_negative(name: str, value: object) -> float:
    return float(check(name, value, NonNegative))


def _poles(count: int) -> Callable[[str, object], tuple[complex, ...]]:
    """The conversion of a set of ``count`` poles: closed under conjugation, each real one a
    float."""
    def convert(name: str, value: object) -> tuple[complex, ...]:
        checked = as_poles(name, value, count)  # type: ignore[arg-type]
        return tuple(complex(p) if abs(p.imag) > 0 else float(p.real) for p in checked)
    return convert


@dataclass(frozen=True)
class DesignSpec:
    """Everything a policy design depends on besides the plant, the period and the noise.

    Attributes
    ----------
    controller, observer : names from :data:`CONTROLLERS` / :data:`OBSERVERS`
    Q : diagonal of the state weight (4,), R : input weight (N⁻²)
    observer_poles : continuous-time Luenberger poles (s-plane), mapped by z = e^{sT}
    M0 : diagonal of the initial a-priori covariance of the time-varying Kalman filter
    discretization : model the discrete designs use, "zoh" (exact) or "euler" (first order)
    reduced_order_poles : continuous-time poles (2) of the reduced-order observer [rad/s]
    ackermann_poles : continuous-time poles (4) of the Ackermann observer from p alone [rad/s];
        faster than ``observer_poles``: estimating θ from the cart position alone with the slow
        default set is too slow for the falling pole (3.97 rad/s) even without noise
    lmi_decay : decay rate α [1/s] of the ``lmi`` observer (every error pole at Re λ ≤ −α)
    """

    controller: str = "dlqr"
    observer: str = "kalman"
    Q: Converted[tuple[float, ...]] = Converted(_vector4, (1.0, 1.0, 1.0, 1.0))
    R: Converted[float] = Converted(positive_number, 1.0)
    observer_poles: Converted[tuple[complex, ...]] = Converted(
        _poles(4), design.DEFAULT_OBSERVER_POLES)
    M0: Converted[tuple[float, ...]] = Converted(_vector4, (0.01, 0.01, 0.01, 0.01))
    discretization: str = "zoh"
    reduced_order_poles: Converted[tuple[complex, ...]] = Converted(_poles(2), (-4.0, -5.0))
    ackermann_poles: Converted[tuple[complex, ...]] = Converted(
        _poles(4), (-2.0, -3.0, -4.0, -5.0))
    lmi_decay: Converted[float] = Converted(_non_negative, 1.0)

    def __post_init__(self) -> None:
        if self.controller not in CONTROLLERS:
            raise ConfigError(f"controller: unknown {self.controller!r}; expected one of "
                              + ", ".join(CONTROLLERS))
        if self.observer not in OBSERVERS:
            raise ConfigError(f"observer: unknown {self.observer!r}; expected one of "
                              + ", ".join(OBSERVERS))
        check("discretization", self.discretization, Literal["zoh", "euler"])

    @property
    def Q_matrix(self) -> np.ndarray:
        return np.diag(self.Q)

    @property
    def R_matrix(self) -> np.ndarray:
        return np.array([[self.R]])
