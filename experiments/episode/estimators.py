"""The distance estimators a closed-loop episode can run, found by name in ``ESTIMATORS``.

Each is causal and sees, per 50 Hz step, the live depth distance, its confidence and
bearing, the LiDAR reference and the car's odometry (the ``DistanceEstimator`` protocol):

- ``raw``: d~ as perception measured it (no defence; NaN without a detection);
- ``odca``: the shipped ODCA checkpoint (frozen Chronos-2 prior, kinematic branch on the
  car's speed and yaw rate, the gate that votes, delta head);
- ``ekf``: the constant-velocity Kalman filter of depth and LiDAR with odometry;
- ``chronos``: Chronos-2 forecast-only: the prior's one-step-ahead mean from the last 64
  depth distances, refreshed every 4 steps as ODCA's is (full replacement of d~).

Each reports in ``diagnostics()["flag"]`` whether its detector flagged the step (ODCA: the
gate repaired it; the EKF: its innovation test; Chronos-only: the depth lies more than
3 standard deviations of the forecast from its mean; raw depth has no detector), and
answers ``would_pass(depth=..., ...)``: would a next step with this depth stay unflagged
(the question a white-box attacker asks; it changes nothing).

The ODCA checkpoint and the prior load once per process and are shared by the episodes a
worker runs (loading takes about a second).
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import Callable

import numpy as np

from odca.features import usable_forecast
from odca.gate import DEPTH, DEPTH_UNCONFIRMED

from controllers import DistanceEstimator, EKFEstimator, PerceptionSample, RawDepthEstimator

__all__ = ["ESTIMATORS", "make_estimator", "ODCAEstimator", "ChronosEstimator"]


@lru_cache(maxsize=None)
def _odca(checkpoint: str | None):
    from odca import ODCA

    return ODCA.load(checkpoint)


class ODCAEstimator:
    """ODCA's d_fused: depth passed through while it agrees with the LiDAR or the kinematic
    branch, repaired from the witnesses that agree when it is outvoted; NaN with no target.

    ``last`` holds the step's full output; ``diagnostics()`` logs the gate's verdict, its
    source and the kinematic branch.
    """

    name = "odca"

    def __init__(self, checkpoint: str | None = None) -> None:
        self.model = _odca(checkpoint)
        self.last = None
        self._had_depth = False

    def reset(self) -> None:
        self.model.reset()
        self.last = None
        self._had_depth = False

    def estimate(self, sample: PerceptionSample, speed_mps: float, dt: float, yaw_rate_radps: float = 0.0) -> float:
        self.last = self.model.step(depth=sample.d_meas, confidence=sample.c_meas, lidar=sample.lidar_m,
                                    speed=speed_mps, yaw_rate=yaw_rate_radps, bearing=sample.bearing_rad, dt=dt,
                                    lidar_confirmed=sample.lidar_confirmed)
        self._had_depth = math.isfinite(sample.d_meas)
        return self.last.d_fused

    def diagnostics(self) -> dict[str, float]:
        if self.last is None:
            return {}
        # The gate flags a depth it outvotes (or one off the kinematic baseline); a missing
        # depth, or one passed on first sight, is nothing to flag.
        flagged = self._had_depth and int(self.last.source) not in (DEPTH, DEPTH_UNCONFIRMED)
        return {"w": self.last.w, "flag": float(flagged), "odca_source": self.last.source, "d_kin": self.last.d_kin}

    def would_pass(self, *, depth: float, speed_mps: float, dt: float, yaw_rate_radps: float = 0.0,
                   lidar_shift: float = 0.0) -> bool:
        return self.model.would_pass(depth=depth, speed=speed_mps, yaw_rate=yaw_rate_radps, lidar_shift=lidar_shift,
                                     dt=dt)


class ChronosEstimator:
    """Chronos-2 forecast-only: the prior's forecast for this step from the depths before it.

    Its detector flags a depth more than ``flag_sigma`` forecast standard deviations from the
    forecast's mean (a residual test; the estimate is the forecast either way).
    """

    name = "chronos"

    def __init__(self, context_length: int = 64, horizon: int = 16, refresh_steps: int = 4,
                 flag_sigma: float = 3.0) -> None:
        self.prior = _odca(None).prior
        self.context_length, self.horizon, self.refresh_steps = context_length, horizon, refresh_steps
        self.flag_sigma = flag_sigma
        self.reset()

    def reset(self) -> None:
        self._context = np.full(self.context_length, np.nan)
        self._mean = np.full(self.horizon, np.nan)
        self._std = np.full(self.horizon, np.nan)
        self._t = 0
        self.flagged = False
        self._probe_cache: tuple = (-1, None, None)

    def _forecast(self) -> tuple[np.ndarray, np.ndarray]:
        if not np.isfinite(self._context).any():
            return np.full(self.horizon, np.nan), np.full(self.horizon, np.nan)
        mean, std = usable_forecast(*self.prior.forecast(self._context[None], self.horizon))
        return mean[0], std[0]

    def _residual_ok(self, d: float, mean: float, std: float) -> bool:
        return not (math.isfinite(d) and math.isfinite(mean) and math.isfinite(std)) or \
            abs(d - mean) <= self.flag_sigma * std

    def estimate(self, sample: PerceptionSample, speed_mps: float, dt: float, yaw_rate_radps: float = 0.0) -> float:
        k = self._t % self.refresh_steps
        if k == 0:
            self._mean, self._std = self._forecast()
        d = sample.d_meas if math.isfinite(sample.d_meas) and sample.d_meas > 0 else math.nan
        self.flagged = not self._residual_ok(d, self._mean[k], self._std[k])
        self._context = np.roll(self._context, -1)
        self._context[-1] = d
        self._t += 1
        return float(self._mean[k])

    def would_pass(self, *, depth: float, speed_mps: float, dt: float, yaw_rate_radps: float = 0.0,
                   lidar_shift: float = 0.0) -> bool:
        k = self._t % self.refresh_steps
        if k == 0:  # the next step refreshes the forecast: make it once per step however often asked
            if self._probe_cache[0] != self._t:
                self._probe_cache = (self._t, *self._forecast())
            _, mean, std = self._probe_cache
        else:
            mean, std = self._mean, self._std
        return self._residual_ok(depth, mean[k], std[k])

    def diagnostics(self) -> dict[str, float]:
        return {"flag": float(self.flagged)} if self._t else {}


#: Every estimator by name (each one's ``name``): a new one is a class and a line here.
ESTIMATORS: dict[str, Callable[[], DistanceEstimator]] = {cls.name: cls for cls in (
    RawDepthEstimator, ODCAEstimator, EKFEstimator, ChronosEstimator)}


def make_estimator(name: str) -> DistanceEstimator:
    """A fresh estimator by name (a key of ``ESTIMATORS``)."""
    if name not in ESTIMATORS:
        raise ValueError(f"estimator must be one of {tuple(ESTIMATORS)}, got {name!r}")
    return ESTIMATORS[name]()
