"""Integer-period measurement and actuator delays as an augmented discrete-time system.

The exact treatment of a delay of a whole number of sampling periods (Åström & Wittenmark,
*Computer-Controlled Systems*, 3rd ed., §2.3 and §11.3): the delay line becomes part of the state.
With ``d_m`` periods of measurement delay and ``d_a`` of actuator delay the augmented state is

.. math::
    z_n = [x_n;\\ \\eta^1_n, …, \\eta^{d_m}_n;\\ \\nu^1_n, …, \\nu^{d_a}_n]

where :math:`\\eta^j_n = C x_{n-j}` are the outputs still in the measurement line and
:math:`\\nu^i_n = u_{n-d_a+i-1}` the forces still in the actuator line (:math:`\\nu^1` acts now):

.. math::
    x_{n+1} = \\Phi x_n + \\Gamma \\nu^1_n + w_n,\\quad \\eta^1_{n+1} = C x_n,\\quad
    \\eta^{j+1}_{n+1} = \\eta^j_n,\\quad \\nu^i_{n+1} = \\nu^{i+1}_n,\\quad \\nu^{d_a}_{n+1} = u_n

    y_n = \\eta^{d_m}_n + v_n \\quad (y_n = C x_n + v_n \\text{ if } d_m = 0)

(with :math:`d_a = 0`, :math:`x_{n+1} = \\Phi x_n + \\Gamma u_n`). A Kalman filter of
``(Φa, Γa, Ca)`` with process noise on ``x`` only is the exact (steady-state) filter of the delayed
system, and the state the force must be computed for, :math:`x_{n+d_a}`, is predicted from
:math:`z` by the known forces in the actuator line:

.. math:: \\hat x_{n+d_a|n} = \\Phi^{d_a}\\hat x_{n|n}
          + \\sum_{i=1}^{d_a} \\Phi^{d_a-i}\\Gamma\\,\\nu^i_n
"""

from __future__ import annotations

import msgspec
import numpy as np
from numpy.typing import ArrayLike

from pendulum_lqg.design.checks import as_matrix, as_square, design_function
from pendulum_lqg.errors import ShapeError


class DelayAugmented(msgspec.Struct, frozen=True):
    """The delay-augmented system of :func:`augment_delays`.

    Attributes
    ----------
    Phi : (na, na), Gamma : (na, m), C : (p, na) augmented model, ``na = n + p·d_m + m·d_a``
    G : (na, n) process-noise input (noise on the plant state only: ``[I; 0]``)
    predict : (n, na) the map ``z ↦ x̂_{n+d_a|n}``
    measurement_delay, actuator_delay : d_m and d_a in periods
    """

    Phi: np.ndarray
    Gamma: np.ndarray
    C: np.ndarray
    G: np.ndarray
    predict: np.ndarray
    measurement_delay: int
    actuator_delay: int


@design_function()
def augment_delays(Phi: ArrayLike, Gamma: ArrayLike, C: ArrayLike, *, measurement_delay: int,
                   actuator_delay: int) -> DelayAugmented:
    """Augment ``(Φ, Γ, C)`` with a measurement and an actuator delay line (see the module).

    Parameters
    ----------
    Phi : (n, n), Gamma : (n, m), C : (p, n) the undelayed discrete model
    measurement_delay, actuator_delay : whole periods ``d_m, d_a ≥ 0``
    """
    Phi = as_square("Phi", Phi)
    n = Phi.shape[0]
    Gamma = as_matrix("Gamma", Gamma, (n, None))
    C = as_matrix("C", C, (None, n))
    d_m, d_a = measurement_delay, actuator_delay
    for name, d in (("measurement_delay", d_m), ("actuator_delay", d_a)):
        if isinstance(d, bool) or not isinstance(d, int | np.integer) or d < 0:
            raise ShapeError(f"{name}: expected a whole number of periods ≥ 0, got {d!r}")
    m, p = Gamma.shape[1], C.shape[0]
    na = n + p * d_m + m * d_a
    eta, nu = n, n + p * d_m                           # first rows of the two delay lines
    Pa = np.zeros((na, na))
    Ga = np.zeros((na, m))
    Pa[:n, :n] = Phi
    if d_a:
        Pa[:n, nu:nu + m] = Gamma                     # ν¹ acts now
        for i in range(d_a - 1):                       # νⁱ⁺¹ → νⁱ
            Pa[nu + i * m:nu + (i + 1) * m, nu + (i + 1) * m:nu + (i + 2) * m] = np.eye(m)
        Ga[nu + (d_a - 1) * m:, :] = np.eye(m)         # the new force enters the line's end
    else:
        Ga[:n] = Gamma
    if d_m:
        Pa[eta:eta + p, :n] = C                       # η¹ ← C x
        for j in range(d_m - 1):                       # ηʲ → ηʲ⁺¹
            Pa[eta + (j + 1) * p:eta + (j + 2) * p, eta + j * p:eta + (j + 1) * p] = np.eye(p)
    Ca = np.zeros((p, na))
    if d_m:
        Ca[:, eta + (d_m - 1) * p:eta + d_m * p] = np.eye(p)
    else:
        Ca[:, :n] = C
    Gw = np.zeros((na, n))
    Gw[:n] = np.eye(n)
    predict = np.zeros((n, na))
    predict[:, :n] = np.linalg.matrix_power(Phi, d_a)
    for i in range(1, d_a + 1):                        # Φ^{d_a − i} Γ νⁱ
        predict[:, nu + (i - 1) * m:nu + i * m] = np.linalg.matrix_power(Phi, d_a - i) @ Gamma
    return DelayAugmented(Phi=Pa, Gamma=Ga, C=Ca, G=Gw, predict=predict,
                          measurement_delay=int(d_m), actuator_delay=int(d_a))
