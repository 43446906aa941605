"""metrics at its 0.3 import path (the module is :mod:`pendulum_lqg.core.metrics`; the failure codes
and the period cost are :mod:`pendulum_lqg.core.rules`)."""

from pendulum_lqg.core.metrics import (
    EPISODE_FIELDS,
    EST_FIELDS,
    SUMMARY_METRICS,
    MetricsAccumulator,
    mean_se,
    summarize,
    wilson_interval,
)
from pendulum_lqg.core.rules import (
    FAIL_DIVERGED,
    FAIL_NONE,
    FAIL_POLE,
    FAIL_REASONS,
    FAIL_TRACK,
    period_cost,
    period_integrals,
)

__all__ = ["EPISODE_FIELDS", "EST_FIELDS", "FAIL_DIVERGED", "FAIL_NONE", "FAIL_POLE", "FAIL_REASONS",
           "FAIL_TRACK", "SUMMARY_METRICS", "MetricsAccumulator", "mean_se", "period_cost",
           "period_integrals", "summarize", "wilson_interval"]
