"""The EKF baseline: a constant-velocity Kalman filter on the distance to a static target,
with the car's odometry as its control input, fusing the depth distance and the LiDAR reference.

State ``x = [d, r]``: the camera-to-target depth d (m) and r (m/s), the part of d's rate
that odometry does not explain (0 on a straight approach to a static target; nonzero on
curves, where depth falls slower than the car advances). Prediction over dt with speed v:

    d <- d + (r - v) dt,   r <- r,   P <- F P F^T + Q

Measurements are d itself: the depth distance with variance ``depth_std_m^2 / c~`` (low
confidence counts for less), and the aligned LiDAR reference with variance
``lidar_std_m^2``. Either may be missing (NaN), then the update is skipped.

Its innovation test (the residual detector of the stealthy-attack literature) flags a step
whose depth or LiDAR innovation lies more than ``innovation_sigma`` standard deviations
from the prediction (``flagged``). It only watches: the filter still takes the measurement,
as the paper's baseline does. The model is
linear, so the "extended" filter is the plain Kalman filter; the name follows the paper.
Pure numpy: one step costs a few microseconds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["EKFConfig", "DistanceEKF"]


@dataclass(frozen=True)
class EKFConfig:
    """Noise model of the distance filter.

    Attributes:
        depth_std_m: depth-distance noise at full confidence, m.
        lidar_std_m: LiDAR-reference noise, m.
        accel_std_mps2: white-noise acceleration driving r, m/s^2.
        init_rate_std_mps: prior std of r at the first measurement, m/s.
        min_confidence: confidences below this are clipped (a bounded variance).
        drop_after_s: the estimate turns NaN (and the filter restarts at the next
            measurement) after this long without one.
        innovation_sigma: the innovation test flags a measurement this many innovation
            standard deviations from the prediction (3: 0.27 % of clean Gaussian steps).
    """

    depth_std_m: float = 0.03
    lidar_std_m: float = 0.03
    accel_std_mps2: float = 1.0
    init_rate_std_mps: float = 0.3
    min_confidence: float = 0.05
    drop_after_s: float = 1.5
    innovation_sigma: float = 3.0

    def __post_init__(self) -> None:
        for name in ("depth_std_m", "lidar_std_m", "accel_std_mps2", "init_rate_std_mps", "min_confidence",
                     "drop_after_s", "innovation_sigma"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a positive finite number, got {value!r}")


class DistanceEKF:
    """Causal distance filter: call :meth:`step` once per control step, in order."""

    def __init__(self, config: EKFConfig | None = None) -> None:
        self.config = config or EKFConfig()
        self.reset()

    def reset(self) -> None:
        self.x = np.zeros(2)
        self.P = np.eye(2)
        self.initialised = False
        self.flagged = False
        self.score = 0.0
        self._since_measurement_s = 0.0

    def step(self, depth: float, confidence: float, lidar: float, speed: float, dt: float) -> float:
        """Predicts over ``dt`` with ``speed`` (m/s), updates with the valid measurements; returns d (NaN if none yet)."""
        if not (math.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a positive finite number of seconds, got {dt}")
        c = self.config
        depth_ok = _valid(depth)
        lidar_ok = _valid(lidar)
        speed = float(speed) if math.isfinite(speed) else 0.0
        if self.initialised:
            self._predict(speed, dt)
            self._since_measurement_s += dt
        self.score = 0.0  # the largest normalised innovation of this step's measurements
        if depth_ok:
            r = self.depth_variance(confidence)
            self.score = max(self.score, self.normalised_innovation(float(depth), r))
            self._update(float(depth), r)
        if lidar_ok:
            self.score = max(self.score, self.normalised_innovation(float(lidar), c.lidar_std_m ** 2))
            self._update(float(lidar), c.lidar_std_m ** 2)
        self.flagged = self.score > c.innovation_sigma
        if depth_ok or lidar_ok:
            self._since_measurement_s = 0.0
        elif self.initialised and self._since_measurement_s > c.drop_after_s:
            self.reset()
        return float(self.x[0]) if self.initialised else math.nan

    def depth_variance(self, confidence: float) -> float:
        """The depth measurement's variance at ``confidence``, m^2."""
        c = self.config
        conf = min(1.0, max(c.min_confidence, float(confidence) if math.isfinite(confidence) else 0.0))
        return c.depth_std_m ** 2 / conf

    def innovation_ok(self, z: float, r: float, prediction: float | None = None) -> bool:
        """Whether ``z`` (variance ``r``) passes the innovation test against the state (or
        ``prediction`` of it); True before the first measurement (nothing to test against)."""
        return self.normalised_innovation(z, r, prediction) <= self.config.innovation_sigma

    def normalised_innovation(self, z: float, r: float, prediction: float | None = None) -> float:
        """|z - prediction| in innovation standard deviations; 0 before the first measurement."""
        if not self.initialised:
            return 0.0
        x = self.x[0] if prediction is None else prediction
        return abs(z - x) / math.sqrt(self.P[0, 0] + r)

    def _predict(self, speed: float, dt: float) -> None:
        F = np.array([[1.0, dt], [0.0, 1.0]])
        q = self.config.accel_std_mps2 ** 2
        Q = q * np.array([[dt ** 4 / 4, dt ** 3 / 2], [dt ** 3 / 2, dt ** 2]])
        self.x = F @ self.x + np.array([-speed * dt, 0.0])
        self.P = F @ self.P @ F.T + Q

    def _update(self, z: float, r: float) -> None:
        if not self.initialised:
            self.x = np.array([z, 0.0])
            self.P = np.diag([r, self.config.init_rate_std_mps ** 2])
            self.initialised = True
            return
        # H = [1, 0]: the measurement is the distance itself.
        s = self.P[0, 0] + r
        k = self.P[:, 0] / s
        self.x = self.x + k * (z - self.x[0])
        self.P = self.P - np.outer(k, self.P[0, :])


def _valid(value: float) -> bool:
    return value is not None and math.isfinite(value) and value > 0
