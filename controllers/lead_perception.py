"""Perception of the car ahead: the vehicle detector kept to the car's own lane, the depth in its
mask, the LiDAR's track of it and the size witness from its known height.

The same pipeline as for a stop sign (:class:`~racf.controllers.perception.Perception`); only the
check of a detection against the map differs. A sign stands where the map says; a car ahead stands
somewhere on the car's lane, which the map and the car's own pose place in the image: a candidate
is the car ahead when its box spans the bearing of a point of the lane whose distance agrees with
the box's size (``range_slack``), the nearest if several do. A car on the other lane, parked beside
it or crossing further on spans no such point.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from racf.controllers.detector import Detection
from racf.controllers.distance import CameraModel
from racf.controllers.lead_existence import NO_EVIDENCE, LeadExistenceCheck
from racf.controllers.lidar_target import LidarTargetTracker
from racf.controllers.perception import Perception, PerceptionSample
from racf.controllers.size_distance import SizeDistance
from racf.controllers.vehicle_detector import VEHICLE_BOX_HEIGHT_M

__all__ = ["LeadPerception", "lane_in_camera"]


def lane_in_camera(points: np.ndarray, pose: np.ndarray, camera_xy: tuple[float, float]) -> np.ndarray:
    """(N, 2) map points as (z ahead along the optical axis, y left) from the camera of a car at ``pose``."""
    x, y, yaw = (float(v) for v in pose)
    c, s = math.cos(yaw), math.sin(yaw)
    cx, cy = camera_xy
    dx = points[:, 0] - (x + c * cx - s * cy)
    dy = points[:, 1] - (y + s * cx + c * cy)
    return np.column_stack([c * dx + s * dy, -s * dx + c * dy])


class LeadPerception(Perception):
    """:class:`Perception` of the car ahead (``target="vehicle"``), checked against the lane.

    Args:
        camera: the camera's intrinsics.
        detector: a vehicle detector (``candidates``/``passing``, e.g. ``LearnedVehicleDetector``).
        lidar: the LiDAR tracker.
        range_slack: a lane point agrees with a box when its distance is within this share of the
            distance the box's height implies.
        existence: the check of whether the box is a car or a picture of one (None: none); its
            evidence reaches the defence as the sample's ``witnesses``.
    """

    def __init__(self, camera: CameraModel, detector, lidar: LidarTargetTracker | None = None,
                 range_slack: float = 0.5, existence: LeadExistenceCheck | None = None) -> None:
        # The car's height, not its width, is the same from any side: a box at an angle is wider, never taller.
        size = SizeDistance(camera, VEHICLE_BOX_HEIGHT_M, wider_than_tall=5.0)
        super().__init__(camera, detector=detector, lidar=lidar, target="vehicle", size=size)
        self.range_slack = float(range_slack)
        self.existence = existence
        self._lane = np.empty((0, 2))
        self._clock_s = 0.0

    def reset(self) -> None:
        super().reset()
        self.lose()

    def lose(self) -> None:
        """The car ahead is lost (out of sight): the existence check starts afresh with the next one."""
        if self.existence is not None:
            self.existence.reset()

    def process(self, rgb, depth, scan, *, lane: np.ndarray | None = None, **kwargs) -> PerceptionSample:
        """:meth:`Perception.process`, with ``lane``: the lane's centre ahead in the camera frame ((N, 2)
        z, y, m; :func:`lane_in_camera`) for the new frame's check (None: no lane known, no car found)."""
        new_frame = kwargs.get("new_frame", True)
        self._clock_s += float(kwargs.get("dt", 0.02))
        if new_frame:
            self._lane = np.empty((0, 2)) if lane is None else np.asarray(lane, float)
        sample = super().process(rgb, depth, scan, map_bearing=None, **kwargs)
        if self.existence is None:
            return sample
        if new_frame:
            self.existence.update(np.asarray(depth), sample.detection, sample.d_size, self._lane, self._clock_s)
        evidence = self.existence.last if sample.detected else NO_EVIDENCE
        return replace(sample, witnesses=evidence)

    def _detect(self, rgb: np.ndarray, map_bearing: float | None) -> Detection | None:
        passing = self.detector.passing(rgb)
        self.last_raw_detection = self.detector.largest(passing)
        ahead = [d for d in passing if self._in_lane(d)]
        return max(ahead, key=lambda d: d.box[3]) if ahead else None  # the nearest: its bottom lowest

    def _in_lane(self, detection: Detection) -> bool:
        lane = self._lane[self._lane[:, 0] > 0.05]
        if not len(lane):
            return False
        left, right = self._span(detection)
        bearings = np.arctan2(lane[:, 1], lane[:, 0])
        fy = self.camera.fy if self.camera.fy is not None else self.camera.fx
        implied = fy * VEHICLE_BOX_HEIGHT_M / max(detection.box[3] - detection.box[1], 1)
        near = np.abs(lane[:, 0] - implied) <= self.range_slack * implied
        within = (bearings <= left + self.map_margin_rad) & (bearings >= right - self.map_margin_rad)
        return bool(np.any(near & within))
