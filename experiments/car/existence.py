"""The car's existence stage: the witnesses of whether its target stands ahead, each frame.

It runs for a defence that answers ``stands()`` (``existence = True``), on the car's side: it
reads the frame, the scan, the car's own pose and the map, never ``info``. It holds the second
detector (the defence's ``second_detector``; None: only the car's), forms the hypothesis (the
map's entry, else where a detector sees a sign) and reads the physical witnesses there
(:mod:`racf.controllers.existence`). At the map's plate it also carries what the depth shows from
frame to frame by the car's own motion: a depth that runs away from it, as no standing thing's does,
is caught (:mod:`racf.controllers.static_world`) and outvoted there for the rest of the approach.
"""

from __future__ import annotations

import math

import numpy as np

from racf.controllers import DepthDistance, Perception, PerceptionSample
from racf.controllers.existence import (NO_WITNESSES, ExistenceWitnesses, Hypothesis, depth_hole, depth_witness,
                                        detection_hypothesis, lidar_witness)
from racf.controllers.static_world import CameraPose, StaticWorldCheck
from racf.experiments.car.software import CarCalibration, camera_offset, map_bearing, sign_depth_at_line
from racf.sim.world.drives import RouteTarget

__all__ = ["ExistenceStage", "camera_pose", "MAP_TOLERANCE_M", "MAP_LATERAL_M"]

#: How far from the map's depth the object may stand: the car's localisation error along the lane, m.
MAP_TOLERANCE_M = 0.35
#: How far either side of the map's place: the plate's half-width and the lateral localisation error, m.
MAP_LATERAL_M = 0.15
#: Half a plate's height, m (the map's signs: 0.10 m across flats).
_PLATE_HALF_M = 0.05


def camera_pose(calibration: CarCalibration, pose: np.ndarray) -> CameraPose:
    """Where the camera of a car at ``pose`` (x, y, yaw: its own estimate) stands in the map's frame."""
    x, y, yaw = (float(v) for v in pose)
    c, s = math.cos(yaw), math.sin(yaw)
    cam_x, cam_y = calibration.camera_xy_m
    return CameraPose(x + c * cam_x - s * cam_y, y + s * cam_x + c * cam_y, calibration.camera_height_m, yaw)


class ExistenceStage:
    """Per frame: the witnesses of the target's existence (:class:`ExistenceWitnesses`).

    Args:
        calibration: the car's build.
        second: the second detector (None: none).
    """

    def __init__(self, calibration: CarCalibration, second=None) -> None:
        self.calibration = calibration
        self.second = Perception(calibration.camera, detector=second) if second is not None else None
        self.depth = DepthDistance()
        self.witnesses = NO_WITNESSES
        self.static = StaticWorldCheck()
        self._target = None

    def reset(self) -> None:
        self.witnesses = NO_WITNESSES
        self.static.reset()
        self._target = None

    def observe(self, rgb: np.ndarray, depth: np.ndarray, scan: np.ndarray, target: RouteTarget, pose: np.ndarray,
                to_line_m: float, primary: Perception, sample: PerceptionSample,
                t_s: float = math.nan) -> ExistenceWitnesses:
        """The witnesses on a new frame (``sample``: the car's perception of it; ``to_line_m``: how far
        the car's own localisation puts its bumper before the target's line along the route; ``t_s``:
        the frame's time on the car's clock, NaN: no static-world check)."""
        if target is not self._target:  # a new approach: nothing has been caught moving yet
            self.static.reset()
            self._target = target
        mapped = target.mapped
        bearing = map_bearing(self.calibration, target, pose) if mapped else None
        second = self.second.detect(rgb, bearing) if self.second is not None else None
        seen = (sample.detection, second)
        seen_depth = tuple(self.depth.estimate(depth, d)[0] for d in seen)
        # The map's sign as the route brings it: its camera depth at the line, plus the route's distance to it.
        map_depth = to_line_m + sign_depth_at_line(self.calibration, target) if mapped and to_line_m > -0.5 \
            else math.nan
        found = None
        ahead, _ = camera_offset(self.calibration, target, pose)
        half_fov = self.calibration.camera.half_hfov_rad
        if mapped and math.isfinite(bearing) and abs(bearing) < half_fov and ahead > 0 and math.isfinite(map_depth):
            # Where the camera could see the map's sign: are the plate and its witnesses there?
            place = self._map_hypothesis(target, bearing, ahead)
            found = self._at(place, depth, scan, seen)
            self._check_static(t_s, depth, pose, place)
        if found is None:  # nothing where the map says (or it says nothing): where a detector sees a sign
            raw = (primary.last_raw_detection, self.second.last_raw_detection if self.second else None)
            for detection in (d for d in raw if d is not None):
                at = self.depth.estimate(depth, detection)[0]
                if math.isfinite(at):
                    hypothesis = detection_hypothesis(detection, at, self.calibration.camera, self._rows(target, at))
                    found = self._at(hypothesis, depth, scan, raw, keep_empty=True)
                    break
        if found is None:
            found = (tuple(d is not None for d in seen), False, False, False, math.nan, "map" if mapped else "")
        detectors, by_depth, by_lidar, blind, depth_m, source = found
        self.witnesses = ExistenceWitnesses(tuple(d is not None for d in seen), seen_depth, detectors, by_depth,
                                            by_lidar, blind, source == "map", depth_m, map_depth, source,
                                            moving=mapped and self.static.moving)
        return self.witnesses

    def _check_static(self, t_s: float, depth: np.ndarray, pose: np.ndarray, place: Hypothesis) -> None:
        """Hands the static-world check this frame's pixels at the map's plate, and where the camera stood."""
        camera = self.calibration.camera
        top, bottom = place.rows
        quarter = (bottom - top) / 5  # the plate's middle rows, as its witness reads them
        rows = np.arange(max(int(round(top + quarter)), 0), min(int(round(bottom - quarter)), depth.shape[0] - 1) + 1)
        centre = camera.cx - camera.fx * math.tan(place.bearing_rad) - 0.5
        half = camera.fx * _PLATE_HALF_M / max(place.depth_m, 0.1)
        cols = np.arange(max(int(math.ceil(centre - half)), 0), min(int(math.floor(centre + half)), depth.shape[1] - 1) + 1)
        rr, cc = (g.ravel() for g in np.meshgrid(rows, cols, indexing="ij"))
        self.static.observe(t_s, depth, camera, camera_pose(self.calibration, pose), rr, cc)

    def _at(self, hypothesis: Hypothesis, depth: np.ndarray, scan: np.ndarray, detections,
            keep_empty: bool = False):
        """The witnesses at ``hypothesis`` (None when no physical witness finds anything there and
        ``keep_empty`` is False: the caller tries the next place)."""
        calib = self.calibration
        by_depth = depth_witness(depth, calib.camera, hypothesis)
        by_lidar = lidar_witness(scan, hypothesis, calib.camera_xy_m, calib.lidar_xy_m)
        blind = not math.isfinite(by_depth) and depth_hole(depth, calib.camera, hypothesis)
        if not (math.isfinite(by_depth) or blind or keep_empty):
            return None
        at = [d is not None and self._holds(d, hypothesis) for d in detections]
        depth_m = by_depth if math.isfinite(by_depth) else by_lidar if blind else math.nan
        return tuple(at), math.isfinite(by_depth), math.isfinite(by_lidar), blind, depth_m, hypothesis.source

    def _holds(self, detection, hypothesis: Hypothesis) -> bool:
        camera = self.calibration.camera
        x0, _, x1, _ = detection.box
        left, right = camera.bearing(x0 - 0.5), camera.bearing(x1 - 0.5)
        return right - hypothesis.half_width_rad <= hypothesis.bearing_rad <= left + hypothesis.half_width_rad

    def _map_hypothesis(self, target: RouteTarget, bearing: float, depth_m: float) -> Hypothesis:
        return Hypothesis(bearing, depth_m, MAP_TOLERANCE_M, math.atan2(MAP_LATERAL_M, depth_m), "map",
                          self._rows(target, depth_m))

    def _rows(self, target: RouteTarget, depth_m: float) -> tuple[int, int]:
        """The image rows (top, bottom) a plate of the map's sign build spans at ``depth_m`` (every sign,
        a temporary one too, is built to the map's standard: its centre height is the map's)."""
        calib, camera = self.calibration, self.calibration.camera
        fy = camera.fy if camera.fy is not None else camera.fx
        cy = camera.cy if camera.cy is not None else 0.0
        height = float(target.target.geometry.centre_height_m) - calib.camera_height_m
        top, bottom = (int(round(cy - fy * (height + dz) / depth_m)) for dz in (_PLATE_HALF_M, -_PLATE_HALF_M))
        return top, bottom
