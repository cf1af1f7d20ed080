"""One frame of perception: detector -> depth distance d~, confidence c~ -> LiDAR reference l."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from controllers.detector import Detection, StopSignDetector
from controllers.distance import CameraModel, DepthDistance, LidarReference

__all__ = ["PerceptionSample", "Perception"]


@dataclass(frozen=True)
class PerceptionSample:
    """What perception makes of one frame (the protocol's per-step signals).

    Attributes:
        detection: the detector's output, or None.
        d_meas: median valid depth inside the detection's mask, m (NaN: none).
        c_meas: its confidence in [0, 1].
        lidar_m: range of the selected LiDAR cluster, m (NaN: none).
        bearing_rad: bearing of the detection's centre, left positive (NaN: none).
    """

    detection: Detection | None
    d_meas: float
    c_meas: float
    lidar_m: float
    bearing_rad: float

    @property
    def detected(self) -> bool:
        return self.detection is not None

    @property
    def detection_confidence(self) -> float:
        return self.detection.confidence if self.detection is not None else 0.0


class Perception:
    """The perception pipeline of the paper for one camera and one LiDAR.

    Args:
        camera: the camera's intrinsics.
        detector, depth, lidar: the stages; defaults are built when omitted.
    """

    def __init__(self, camera: CameraModel, detector: StopSignDetector | None = None,
                 depth: DepthDistance | None = None, lidar: LidarReference | None = None) -> None:
        self.camera = camera
        self.detector = detector or StopSignDetector()
        self.depth = depth or DepthDistance()
        self.lidar = lidar or LidarReference(camera)

    def process(self, rgb: np.ndarray, depth: np.ndarray, lidar_ranges: np.ndarray) -> PerceptionSample:
        """Runs the pipeline on one synchronized frame (rgb (H, W, 3) uint8, depth (H, W) m, scan (N,) m)."""
        detection = self.detector.detect(rgb)
        d_meas, c_meas = self.depth.estimate(depth, detection)
        lidar_m = self.lidar.estimate(lidar_ranges, detection)
        bearing = self.camera.bearing(detection.centroid[0]) if detection is not None else math.nan
        return PerceptionSample(detection, d_meas, c_meas, lidar_m, bearing)
