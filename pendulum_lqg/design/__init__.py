"""Pure design layer: functions of matrices only (no MuJoCo), usable for any (A, B, C).

=====================  =====================================================================
module                 contents
=====================  =====================================================================
``lqr``                :func:`lqr`, :func:`dlqr` (prescribed decay), :func:`finite_horizon_dlqr`,
                       :func:`bryson`
``kalman``             :func:`kalman` (Kalman–Bucy), :func:`dkalman` (filter + predictor gains),
                       :func:`kalman_tv` (time-varying recursion)
``luenberger``         :func:`luenberger`, :func:`dluenberger`
``lqg``                :func:`lqg` closed-loop assembly and the separation check
``structure``          controllability / observability ranks and PBH tests
``discretize``         :func:`zoh`, :func:`euler`, :func:`process_noise_covariance`,
                       :func:`sampled_cost`
``delay``              :func:`augment_delays`: integer-period measurement / actuator delay lines
=====================  =====================================================================
"""

from pendulum_lqg.design.delay import DelayAugmented, augment_delays
from pendulum_lqg.design.discretize import (
    c2d_poles,
    euler,
    process_noise_covariance,
    sampled_cost,
    zoh,
)
from pendulum_lqg.design.kalman import (
    DKalmanResult,
    KalmanResult,
    TimeVaryingKalmanGains,
    dkalman,
    kalman,
    kalman_tv,
)
from pendulum_lqg.design.lqg import LQGResult, lqg
from pendulum_lqg.design.lqr import (
    FiniteHorizonLQR,
    LQRResult,
    bryson,
    dlqr,
    finite_horizon_dlqr,
    lqr,
)
from pendulum_lqg.design.luenberger import (
    DEFAULT_OBSERVER_POLES,
    ObserverResult,
    dluenberger,
    luenberger,
)
from pendulum_lqg.design.structure import (
    StructureReport,
    controllability_matrix,
    observability_matrix,
    structure,
)

__all__ = [
    "DEFAULT_OBSERVER_POLES",
    "DKalmanResult",
    "DelayAugmented",
    "FiniteHorizonLQR",
    "KalmanResult",
    "LQGResult",
    "LQRResult",
    "ObserverResult",
    "StructureReport",
    "TimeVaryingKalmanGains",
    "augment_delays",
    "bryson",
    "c2d_poles",
    "controllability_matrix",
    "dkalman",
    "dlqr",
    "dluenberger",
    "euler",
    "finite_horizon_dlqr",
    "kalman",
    "kalman_tv",
    "lqg",
    "lqr",
    "luenberger",
    "observability_matrix",
    "process_noise_covariance",
    "sampled_cost",
    "structure",
    "zoh",
]
