"""Time to the stop line at the attack's trigger: an example racf metric.

When an attack begins, how long would the car take to reach the stop line at the speed it is
driving? An attack that begins with 3 s to go leaves a defence time to notice; one that begins
with 0.5 s to go tests the braking alone. The metric reads the referee's columns of the per-step
log (``attack_active``, ``dist_to_stop_line``, ``speed``): ground truth, which a metric may read
and the car never does. Episodes whose attack never began score NaN.

It declares its field once (:class:`~racf.experiments.metrics.Field`: unit, meaning, summarised
by its median with a bootstrap interval); the result row, the sweep summary and report and the
scorecard's closed-loop rows read that declaration. Nothing in racf names it.
"""

from __future__ import annotations

import math

import numpy as np

from racf.experiments.metrics import Field, Metric

__all__ = ["TimeToLine"]


class TimeToLine(Metric):
    """Seconds to the stop line at the car's speed when the attack began (NaN: no attack began)."""

    name = "time_to_line"
    meaning = "seconds to the stop line, at the car's speed, when the attack began"
    always = True  # scored on every episode once installed
    higher_is_better = {"time_to_line_s": True}
    fields = (Field("time_to_line_s", math.nan, "s", "time to the stop line at the car's speed when the attack began",
                    "median"),)

    def score(self, episode):
        log = episode.log
        began = np.flatnonzero(log["attack_active"].to_numpy(bool))
        if not began.size:
            return {"time_to_line_s": math.nan}
        step = log.iloc[began[0]]
        speed = max(float(step["speed"]), 0.05)  # at rest: as long as crawling at the rest speed takes
        return {"time_to_line_s": max(float(step["dist_to_stop_line"]), 0.0) / speed}
