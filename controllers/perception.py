"""One control step of perception: detector -> depth distance d~, confidence c~; LiDAR target reference l.

The camera runs slower than the control loop (30 Hz on 50 Hz): the detector and the depth
stage run on new frames only, and between frames their sample is held while the LiDAR
tracker steps every control step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from racf.controllers.detector import BlobDetector, Detection, StopSignDetector
from racf.controllers.distance import CameraModel, DepthDistance
from racf.controllers.lidar_target import TARGET_KINDS, LidarTargetTracker
from racf.controllers.size_distance import SizeDistance

__all__ = ["Perception", "PerceptionSample"]


@dataclass(frozen=True)
class PerceptionSample:
    """What perception makes of one control step (the protocol's per-step signals).

    The camera's part (``detection``, ``d_meas``, ``c_meas``, ``bearing_rad``) is that of the
    last frame, held between frames; ``lidar_m`` is this step's.

    Attributes:
        detection: the detector's output after the map check, or None.
        d_meas: median valid depth inside the detection's mask, m (NaN: none).
        c_meas: its confidence in [0, 1].
        lidar_m: the LiDAR target reference: the tracked target's depth along the
            camera's optical axis, m (NaN: nothing fits the track).
        bearing_rad: bearing of the detection's centre, left positive (NaN: none).
        lidar_confirmed: whether the camera's depth has agreed with the LiDAR's track since it
            started (``LidarTargetTracker.depth_confirmed``).
        d_size: the size witness: the distance the detection's box implies from the target's
            known size, m (NaN: no size stage, no detection, or a box too broken or cut to
            measure; :class:`~racf.controllers.size_distance.SizeDistance`).
        size_std: its std, m.
        witnesses: the existence stage's witnesses (``racf.controllers.existence``), for a defence
            that answers whether its target stands; None otherwise.
    """

    detection: Detection | None
    d_meas: float
    c_meas: float
    lidar_m: float
    bearing_rad: float
    lidar_confirmed: bool = True
    d_size: float = math.nan
    size_std: float = math.nan
    witnesses: Any = None

    @property
    def detected(self) -> bool:
        return self.detection is not None

    @property
    def detection_confidence(self) -> float:
        return self.detection.confidence if self.detection is not None else 0.0


class Perception:
    """The perception pipeline of the paper for one camera, one LiDAR and one kind of target.

    The camera runs slower than the control loop, so :meth:`process` runs the (costly)
    detector and depth stages only on a new frame and holds their sample in between; the
    LiDAR tracker steps on every call.

    Args:
        camera: the camera's intrinsics.
        detector, depth, lidar: the stages; defaults are built when omitted.
        target: the kind of target the detector finds, ``"sign"`` or ``"obstacle"`` (the
            LiDAR tracker fits cluster widths to it).
        map_margin_rad: with a map bearing (``process(map_bearing=...)``), a detection
            counts only if its box, widened by this margin, holds that bearing.
        size: the size witness's stage (the target's known size; None: no size witness).
    """

    def __init__(self, camera: CameraModel, detector: BlobDetector | None = None,
                 depth: DepthDistance | None = None, lidar: LidarTargetTracker | None = None,
                 target: str = "sign", map_margin_rad: float = math.radians(3.0),
                 size: SizeDistance | None = None) -> None:
        if target not in TARGET_KINDS:
            raise ValueError(f"target must be one of {TARGET_KINDS}, got {target!r}")
        self.camera = camera
        self.detector = detector or StopSignDetector()
        self.depth = depth or DepthDistance()
        self.lidar = lidar or LidarTargetTracker()
        self.target = target
        self.map_margin_rad = float(map_margin_rad)
        self.size = size
        #: The detector's output on the last image processed (the last new frame), before the
        #: map check (for evaluation).
        self.last_raw_detection: Detection | None = None
        self._held: _Held | None = None  # the last frame's camera part; None: no frame since reset

    def reset(self) -> None:
        """Forget the tracked target and the held frame (a new target or episode)."""
        self.lidar.reset()
        self._held = None

    def process(self, rgb: np.ndarray | None, depth: np.ndarray | None, scan: np.ndarray | None, *,
                speed: float = 0.0, yaw_rate: float = 0.0, dt: float = 0.02, lateral_speed: float = 0.0,
                map_bearing: float | None = None, new_frame: bool = True,
                beam_age_s: np.ndarray | float | None = None) -> PerceptionSample:
        """Runs the pipeline on one control step.

        Args:
            rgb: (H, W, 3) uint8 image. depth: (H, W) metres. Both unused (may be None) when
                ``new_frame`` is False.
            scan: (N,) LiDAR ranges, m, on the step a new scan arrived; None otherwise (the
                tracker carries the reference forward with odometry).
            speed, yaw_rate, lateral_speed: odometry (m/s, rad/s, m/s) over the last ``dt`` s.
            map_bearing: where the map says the current target is, rad from the optical
                axis (left positive), from the car's localisation; NaN = the map says the
                target's face cannot be seen from here; None = no map. A real
                route passes stop signs that serve other lanes: this keeps perception on
                the one the car must stop at, as a map-aided stack does. Checked on new
                frames only (a held detection keeps its frame's verdict).
            new_frame: whether ``rgb``/``depth`` are a frame not processed yet. False (the
                camera is slower than the loop): the detector and depth stage do not run and
                the last frame's detection, d~, c~ and bearings are held (no detection
                before any frame since :meth:`reset`); the LiDAR tracker still steps, with
                the held detection.
            beam_age_s: how long before this step each beam of ``scan`` was taken, s (see
                :meth:`LidarTargetTracker.step`); None = all now.
        """
        if new_frame:
            detection = self._detect(rgb, map_bearing)
            span = self._span(detection) if detection is not None else None
            d_meas, c_meas = self.depth.estimate(depth, detection)
            bearing = self.camera.bearing(detection.centroid[0]) if detection is not None else math.nan
            height = self.camera.height_per_metre(detection.box[1], detection.box[3]) if detection is not None \
                else math.nan
            d_size, size_std = self.size.estimate(detection) if self.size is not None else (math.nan, math.nan)
            self._held = _Held(detection, d_meas, c_meas, bearing, span, height, d_size, size_std)
        held = self._held or _NO_FRAME
        lidar_m = self.lidar.step(scan=scan, detection_bearing=held.bearing, detection_span=held.span,
                                  target=self.target, speed=speed, yaw_rate=yaw_rate, dt=dt,
                                  lateral_speed=lateral_speed, detection_depth=held.d_meas, beam_age_s=beam_age_s,
                                  detection_height=held.height)
        return PerceptionSample(held.detection, held.d_meas, held.c_meas, lidar_m, held.bearing,
                                self.lidar.depth_confirmed, held.d_size, held.size_std)

    def detect(self, rgb: np.ndarray, map_bearing: float | None = None) -> Detection | None:
        """The detector's pick of the target on one frame after the map check (see :meth:`process`),
        without the depth and LiDAR stages: what a second detector beside the car's reports."""
        return self._detect(np.asarray(rgb), map_bearing)

    def _detect(self, rgb: np.ndarray, map_bearing: float | None) -> Detection | None:
        """The frame's detection of the target. Without a map, the detector's own pick. With one, the
        passing candidate whose box (widened by the margin) holds the map's bearing, the one centred
        nearest it: a red car, a traffic light or a sign for another lane elsewhere in the frame must not
        crowd out the sign the map says is there (the detector's own pick, the largest, may be one of
        them). A detector that lists no
        ``candidates`` (a plug-in's ``detect`` only) has its pick kept only if it holds the bearing."""
        # Only where ``detect`` is the largest passing candidate (``BlobDetector``'s) is a choice among them its equal.
        blob = type(self.detector).detect is BlobDetector.detect
        if map_bearing is None or not blob:
            detection = self.last_raw_detection = self.detector.detect(rgb)
            if detection is not None and map_bearing is not None and not (
                    math.isfinite(map_bearing) and self._on_map(self._span(detection), map_bearing)):
                return None
            return detection
        passing = self.detector.passing(rgb)
        self.last_raw_detection = self.detector.largest(passing)
        on_map = [d for d in passing if math.isfinite(map_bearing) and self._on_map(self._span(d), map_bearing)]
        # The one centred nearest the map's bearing: a red car just beside (or below) the sign in the
        # image is within the margin too, and may be the larger.
        return min(on_map, key=lambda d: (abs(self.camera.bearing(d.centroid[0]) - map_bearing), -d.area_px)) \
            if on_map else None

    def _span(self, detection: Detection) -> tuple[float, float]:
        """(left, right) bearings of the detection box's outer edges, rad."""
        x0, _, x1, _ = detection.box
        return self.camera.bearing(x0 - 0.5), self.camera.bearing(x1 - 0.5)

    def _on_map(self, span: tuple[float, float], map_bearing: float) -> bool:
        left, right = span
        return right - self.map_margin_rad <= map_bearing <= left + self.map_margin_rad


@dataclass(frozen=True)
class _Held:
    """The camera's part of a sample, from the last frame (held until the next)."""

    detection: Detection | None
    d_meas: float
    c_meas: float
    bearing: float
    span: tuple[float, float] | None
    height: float = math.nan  # the box's height per metre of depth (CameraModel.height_per_metre)
    d_size: float = math.nan
    size_std: float = math.nan


_NO_FRAME = _Held(None, math.nan, 0.0, math.nan, None)
