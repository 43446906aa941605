"""Pure design layer: functions of matrices only (no MuJoCo), usable for any (A, B, C).

=====================  =====================================================================
module                 contents
=====================  =====================================================================
``lqr``                :func:`lqr`, :func:`dlqr` (prescribed decay), :func:`finite_horizon_dlqr`,
                       :func:`bryson`
``kalman``             :func:`kalman` (Kalman–Bucy), :func:`dkalman` (filter + predictor gains),
                       :func:`kalman_tv` (time-varying recursion)
``luenberger``         :func:`luenberger`, :func:`dluenberger`
``observers``          :func:`ackermann`, :func:`reduced_order_observer` (and ``d…``),
                       :func:`lmi_observer`, :func:`h2_filter`, :func:`hinf_filter` (LMIs)
``lqg``                :func:`lqg` closed-loop assembly and the separation check
``structure``          controllability / observability ranks and PBH tests
``discretize``         :func:`zoh`, :func:`euler`, :func:`process_noise_covariance`,
                       :func:`sampled_cost`
``delay``              :func:`augment_delays`: integer-period measurement / actuator delay lines
``checks``             the one validation helper of matrix arguments
``sysid``              nominal identification: a linear model from logged (y, u) by least squares
``pem``                prediction-error identification of the innovations form, under feedback
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
from pendulum_lqg.design.observers import (
    LMIObserverResult,
    ReducedOrderObserver,
    ackermann,
    dreduced_order_observer,
    h2_filter,
    hinf_filter,
    lmi_observer,
    reduced_order_observer,
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
    "LMIObserverResult",
    "LQGResult",
    "LQRResult",
    "ObserverResult",
    "ReducedOrderObserver",
    "StructureReport",
    "TimeVaryingKalmanGains",
    "ackermann",
    "augment_delays",
    "bryson",
    "c2d_poles",
    "controllability_matrix",
    "dkalman",
    "dlqr",
    "dluenberger",
    "dreduced_order_observer",
    "euler",
    "finite_horizon_dlqr",
    "h2_filter",
    "hinf_filter",
    "kalman",
    "kalman_tv",
    "lmi_observer",
    "lqg",
    "lqr",
    "luenberger",
    "observability_matrix",
    "process_noise_covariance",
    "reduced_order_observer",
    "sampled_cost",
    "structure",
    "zoh",
]
