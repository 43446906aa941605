"""The design choices of a built-in policy: controller, observer, weights and poles
(:class:`DesignSpec`), checked when made."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from pendulum_lqg import design
from pendulum_lqg.design.checks import as_poles
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.names import CONTROLLERS, OBSERVERS
from pendulum_lqg.problem.declare import NonNegative, check, config_vector, positive_number


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
    Q: tuple[float, ...] = (1.0, 1.0, 1.0, 1.0)
    R: float = 1.0
    observer_poles: tuple[float, ...] = design.DEFAULT_OBSERVER_POLES
    M0: tuple[float, ...] = (0.01, 0.01, 0.01, 0.01)
    discretization: str = "zoh"
    reduced_order_poles: tuple[float, ...] = (-4.0, -5.0)
    ackermann_poles: tuple[float, ...] = (-2.0, -3.0, -4.0, -5.0)
    lmi_decay: float = 1.0

    def __post_init__(self) -> None:
        if self.controller not in CONTROLLERS:
            raise ConfigError(f"controller: unknown {self.controller!r}; expected one of "
                              + ", ".join(CONTROLLERS))
        if self.observer not in OBSERVERS:
            raise ConfigError(f"observer: unknown {self.observer!r}; expected one of "
                              + ", ".join(OBSERVERS))
        check("discretization", self.discretization, Literal["zoh", "euler"])
        values: dict[str, object] = {
            "Q": config_vector("Q", self.Q, 4, nonneg=True),     # diagonals of 4×4 matrices
            "M0": config_vector("M0", self.M0, 4, nonneg=True),
            "R": positive_number("R", self.R),
            "lmi_decay": float(check("lmi_decay", self.lmi_decay, NonNegative))}
        for name, count in (("observer_poles", 4), ("reduced_order_poles", 2),
                            ("ackermann_poles", 4)):
            checked = as_poles(name, getattr(self, name), count)
            values[name] = tuple(complex(p) if abs(p.imag) > 0 else float(p.real) for p in checked)
        for name, value in values.items():          # each in its checked type
            object.__setattr__(self, name, value)

    @property
    def Q_matrix(self) -> np.ndarray:
        return np.diag(self.Q)

    @property
    def R_matrix(self) -> np.ndarray:
        return np.array([[self.R]])
