"""``racf bench service``: the defence service's round trip per step, on real samples.

One episode is run with the defence in the car's process and every sample it was asked about
is kept; those samples are then sent to a ``racf serve`` process, in order and again and again
(each pass starting with a reset, as episodes do) until ``n`` steps were answered, and each
round trip is timed on the car's side. The in-process estimate of the same samples is timed
beside it, so the service's own cost reads as the difference.
"""

from __future__ import annotations

import time

import numpy as np

from racf.experiments.car.estimators import make_estimator
from racf.experiments.link.remote import RemoteEstimator
from racf.experiments.sweeps.service_process import service_process

__all__ = ["service_process", "record_samples", "measure", "percentiles", "PAPER_CYCLE_MS"]


#: The paper's offboard cycle: "approximately 49 ms per frame (~20 Hz), including perception
#: transmission, ODCA inference, and control feedback".
PAPER_CYCLE_MS = 49.0


class _Recorder:
    """An estimator that answers as ``inner`` and keeps what it was asked."""

    def __init__(self, inner) -> None:
        self.inner, self.calls = inner, []

    def __getattr__(self, name):
        return getattr(self.inner, name)

    def reset(self) -> None:
        self.calls.append(None)
        self.inner.reset()

    def estimate(self, sample, speed_mps, dt, yaw_rate_radps=0.0):
        self.calls.append((sample, speed_mps, dt, yaw_rate_radps))
        return self.inner.estimate(sample, speed_mps, dt, yaw_rate_radps=yaw_rate_radps)


def record_samples(spec) -> tuple[list, object]:
    """The calls the car made to its defence over one episode of ``spec`` (None: a reset), and its build."""
    from racf.experiments.episode import run_trial
    from racf.experiments.episode.plan import plan_episode

    recorder = _Recorder(make_estimator(spec.estimator, spec.estimator_options))
    run_trial(spec, estimator=recorder, clean_pass=False)
    return recorder.calls, plan_episode(spec).calibration


def percentiles(ms: np.ndarray) -> dict:
    return {"n": int(ms.size), "mean_ms": float(ms.mean()), "p50_ms": float(np.percentile(ms, 50)),
            "p90_ms": float(np.percentile(ms, 90)), "p99_ms": float(np.percentile(ms, 99)),
            "p999_ms": float(np.percentile(ms, 99.9)), "max_ms": float(ms.max())}


def measure(endpoint: str, defence: str, calls: list, calibration, n: int, options: dict | None = None,
            keys=None) -> dict:
    """Round trips of ``n`` estimate requests to the service at ``endpoint`` and the in-process cost of
    the same calls; the distances of both must agree (a check the service changes nothing)."""
    remote = RemoteEstimator(endpoint, defence, options, timeout_ms=5000.0, keys=keys)
    local = make_estimator(defence, options or {})
    for est in (remote, local):
        if callable(getattr(est, "use_calibration", None)):
            est.use_calibration(calibration)
    rtt, cost, mismatches, done = [], [], 0, 0
    while done < n:
        for call in calls:
            if done >= n:
                break
            if call is None:
                remote.reset()
                local.reset()
                continue
            sample, speed, dt, yaw = call
            d_remote = remote.estimate(sample, speed, dt, yaw)
            rtt.append(remote.latency_s * 1000.0)
            start = time.perf_counter()
            d_local = local.estimate(sample, speed, dt, yaw_rate_radps=yaw)
            cost.append((time.perf_counter() - start) * 1000.0)
            mismatches += not (d_remote == d_local or (np.isnan(d_remote) and np.isnan(d_local)))
            done += 1
    remote.close()
    return {"defence": defence, "endpoint": endpoint, "round_trip": percentiles(np.array(rtt)),
            "in_process": percentiles(np.array(cost)), "distance_mismatches": mismatches,
            "paper_cycle_ms": PAPER_CYCLE_MS}
