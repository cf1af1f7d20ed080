"""Distance estimators the braking controller can use: the pluggable distance source.

An estimator turns the per-step perception signals (and the car's speed) into the
distance the controller acts on. Raw depth is the paper's undefended pipeline; ODCA and
the forecasting baselines implement the same protocol.
"""

from __future__ import annotations

import math
from typing import Protocol, runtime_checkable

from racf.controllers.ekf import DistanceEKF, EKFConfig
from racf.controllers.perception import PerceptionSample

__all__ = ["DistanceEstimator", "RawDepthEstimator", "EKFEstimator"]


@runtime_checkable
class DistanceEstimator(Protocol):
    """Causal distance source: one call per control step, in order.

    ``name`` is the estimator's key in the episode's registry (``raw``, ``ekf``, ...).
    """

    name: str

    def reset(self) -> None:
        """Forget the past (a new episode)."""

    def estimate(self, sample: PerceptionSample, speed_mps: float, dt: float, yaw_rate_radps: float = 0.0) -> float:
        """Camera-to-sign distance in metres for this step; NaN when there is none (no target).

        ``speed_mps`` and ``yaw_rate_radps`` are the car's odometry (wheel speed, gyro less
        its bias estimate); an estimator may ignore what it has no use for."""

    def diagnostics(self) -> dict[str, float]:
        """What the last ``estimate`` call leaves to log beside the distance, by column name
        (ODCA: its gate ``w``; a defence with a detector: ``flag``, 1.0 when it flagged the
        step, and, if it has one, ``score``, the statistic it thresholds, higher is more
        suspicious: the scorecard sweeps a threshold over it); empty when the estimator has
        nothing to add. A defence may also declare ``n_parameters`` (trainable) and
        ``n_frozen_parameters`` for the scorecard's cost row."""

    def would_pass(self, *, depth: float, speed_mps: float, dt: float, yaw_rate_radps: float = 0.0,
                   lidar_shift: float = 0.0) -> bool:
        """Whether a next step whose depth distance is ``depth`` would leave the detector quiet,
        the LiDAR moved by the car's motion and ``lidar_shift`` m (a spoof moving it with the
        depth). Changes nothing: the question a white-box attacker asks. A defence that uses
        the size witness (``PerceptionSample.d_size``) also takes ``size_shift`` (m: an attack
        that scales the sign's image moves it); an attack passes it only to one that does."""


class RawDepthEstimator:
    """d~ as perception measured it: no defence (NaN without a detection)."""

    name = "raw"
    n_parameters = 0

    def reset(self) -> None:
        pass

    def estimate(self, sample: PerceptionSample, speed_mps: float, dt: float, yaw_rate_radps: float = 0.0) -> float:
        return sample.d_meas

    def diagnostics(self) -> dict[str, float]:
        return {}

    def would_pass(self, *, depth: float, speed_mps: float, dt: float, yaw_rate_radps: float = 0.0,
                   lidar_shift: float = 0.0) -> bool:
        return True  # no detector


class EKFEstimator:
    """The EKF baseline: depth and LiDAR fused with odometry (:mod:`racf.controllers.ekf`)."""

    name = "ekf"
    n_parameters = 0  # a filter with hand-set noise models: nothing trained

    def __init__(self, config: EKFConfig | None = None) -> None:
        self.filter = DistanceEKF(config)
        self._stepped = False

    def reset(self) -> None:
        self.filter.reset()
        self._stepped = False

    def estimate(self, sample: PerceptionSample, speed_mps: float, dt: float, yaw_rate_radps: float = 0.0) -> float:
        self._stepped = True
        return self.filter.step(sample.d_meas, sample.c_meas, sample.lidar_m, speed_mps, dt)

    def diagnostics(self) -> dict[str, float]:
        return {"flag": float(self.filter.flagged), "score": self.filter.score} if self._stepped else {}

    def would_pass(self, *, depth: float, speed_mps: float, dt: float, yaw_rate_radps: float = 0.0,
                   lidar_shift: float = 0.0) -> bool:
        """The innovation test at full confidence against the prediction over ``dt``; a spoof
        that moves the LiDAR with the depth (``lidar_shift``) must pass it as LiDAR too."""
        f = self.filter
        if not f.initialised:
            return True
        prediction = f.x[0] + (f.x[1] - speed_mps) * dt
        p00 = f.P[0, 0] + 2 * dt * f.P[0, 1] + dt * dt * f.P[1, 1] + f.config.accel_std_mps2 ** 2 * dt ** 4 / 4
        ok = abs(depth - prediction) <= f.config.innovation_sigma * math.sqrt(p00 + f.depth_variance(1.0))
        if lidar_shift:
            ok &= abs(depth - prediction) <= f.config.innovation_sigma * math.sqrt(p00 + f.config.lidar_std_m ** 2)
        return bool(ok)
