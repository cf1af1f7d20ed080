"""Distance estimators the braking controller can use: the pluggable distance source.

An estimator turns the per-step perception signals (and the car's speed) into the
distance the controller acts on. Raw depth is the paper's undefended pipeline; ODCA and
the forecasting baselines implement the same protocol.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

from controllers.ekf import DistanceEKF, EKFConfig
from controllers.perception import PerceptionSample

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
        (ODCA: its gate ``w``); empty when the estimator has nothing to add."""


class RawDepthEstimator:
    """d~ as perception measured it: no defence (NaN without a detection)."""

    name = "raw"

    def reset(self) -> None:
        pass

    def estimate(self, sample: PerceptionSample, speed_mps: float, dt: float, yaw_rate_radps: float = 0.0) -> float:
        return sample.d_meas

    def diagnostics(self) -> dict[str, float]:
        return {}


class EKFEstimator:
    """The EKF baseline: depth and LiDAR fused with odometry (:mod:`controllers.ekf`)."""

    name = "ekf"

    def __init__(self, config: EKFConfig | None = None) -> None:
        self.filter = DistanceEKF(config)

    def reset(self) -> None:
        self.filter.reset()

    def estimate(self, sample: PerceptionSample, speed_mps: float, dt: float, yaw_rate_radps: float = 0.0) -> float:
        return self.filter.step(sample.d_meas, sample.c_meas, sample.lidar_m, speed_mps, dt)

    def diagnostics(self) -> dict[str, float]:
        return {}
