"""How the defence service answered an episode (the ``service`` metric, scored where the spec runs
its estimator through ``racf serve``): the round trips the car measured, the steps they made it
late, and the steps it fell back on its onboard defence (or, with ``estimator_fallback`` raw, its own depth
distance): which steps ran where."""

from __future__ import annotations

import math

import numpy as np

from racf.experiments.metrics.base import Episode, Field, Metric

__all__ = ["ServiceMeasures"]


class ServiceMeasures(Metric):
    """Round trips to the defence service, late steps and fallbacks."""

    name = "service"
    meaning = "the defence service's round trips, late actions and fallbacks (an estimator run by racf serve)"
    order = 80
    higher_is_better = {"service_fallback_steps": False, "service_rtt_p99_ms": False}
    fields = (
        Field("service_steps", 0, "steps", "steps whose estimate came from the service"),
        Field("service_rtt_p50_ms", math.nan, "ms", "median round trip of a step's request", summary="median"),
        Field("service_rtt_p99_ms", math.nan, "ms", "99th percentile of the round trips", summary="median"),
        Field("service_late_steps", 0, "steps", "actions delayed a control period or more by a slow answer"),
        Field("service_fallback_steps", 0, "steps", "steps with no answer the car may act on (none in time, one "
                                                    "the protocol's check refused): the car's fallback drove"),
        Field("service_onboard_steps", 0, "steps", "of those, steps the car's onboard defence drove (the rest: its "
                                                   "own depth distance, unrepaired)"),
        Field("service_fallback", False, "", "the car fell back at least once", summary="rate"),
        Field("service_invalid", 0, "", "answers the protocol's check refused (out of range, of the wrong kind, an "
                                        "error, an answer to another request)"),
        Field("service_restarts", 0, "", "defence restarts: times the service rebuilt the car's defence after it "
                                         "raised"),
        Field("service_new_sessions", 0, "", "new sessions: times the car opened its session again after a failure"),
        Field("service_outvoted", 0, "", "served answers the car's own witnesses outvoted (a distance farther than "
                                         "its onboard defence's, or nothing standing where they see a target)"),
        Field("service_refusals", 0, "", "answers lost to a failed authentication: a peer that is not the service "
                                         "the car pins (a man in the middle on a CurveZMQ link)"),
    )

    def score(self, episode: Episode) -> dict:
        log = episode.log
        if "service_rtt_ms" not in log:
            return {}
        control = log["control"].astype(bool)
        rtt = log.loc[control, "service_rtt_ms"].to_numpy(float)
        answered = rtt[np.isfinite(rtt)]
        fallback = int((log.loc[control, "service_fallback"] == 1.0).sum())
        dt = float(log["t"].diff().median()) if len(log) > 1 else 0.02
        return {"service_steps": int(answered.size),
                "service_rtt_p50_ms": float(np.percentile(answered, 50)) if answered.size else math.nan,
                "service_rtt_p99_ms": float(np.percentile(answered, 99)) if answered.size else math.nan,
                "service_late_steps": int((answered >= dt * 1000.0).sum()),
                "service_fallback_steps": fallback, "service_fallback": fallback > 0,
                "service_onboard_steps": int((log.loc[control, "service_onboard"] == 1.0).sum())
                if "service_onboard" in log else 0,
                **{name: _last_count(log, name) for name in ("service_invalid", "service_restarts",
                                                             "service_new_sessions", "service_refusals",
                                                             "service_outvoted")}}


def _last_count(log, column: str) -> int:
    """A counter the car carries through the episode: its last value (0 where never logged)."""
    if column not in log:
        return 0
    values = log[column].to_numpy(float)
    values = values[np.isfinite(values)]
    return int(values.max()) if values.size else 0
