"""The LiDAR reference's settings (:mod:`racf.controllers.lidar_target`: its geometry, the scan's
segmentation, the association of a cluster to a detection and the keeping of the track) and what
the tracker reports after a step."""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["TARGET_KINDS", "LidarTargetConfig", "LidarTargetState"]

#: Target kinds the tracker knows (``step(target=...)``).
TARGET_KINDS = ("sign", "obstacle", "vehicle")


def _check_pair(name: str, value: tuple[float, float], lo: float, hi: float) -> None:
    ok = (isinstance(value, tuple) and len(value) == 2 and all(isinstance(v, (int, float)) for v in value)
          and lo <= value[0] < value[1] <= hi)
    if not ok:
        raise ValueError(f"{name} must be a (min, max) pair with {lo} <= min < max <= {hi} m, got {value!r}")


def _check_range(name: str, value: float, lo: float, hi: float, unit: str) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not lo <= value <= hi:
        raise ValueError(f"{name} must be in [{lo}, {hi}] {unit}, got {value!r}")


@dataclass(frozen=True)
class LidarTargetConfig:
    """Geometry, segmentation, association and track keeping of the LiDAR reference.

    Attributes:
        lidar_position_m: (x, y) of the RPLIDAR in the body frame, metres (the scan plane's
            origin; the scanner is level and its 0 deg beam points along body +x).
        camera_position_m: (x, y) of the D435's optical centre in the body frame, metres
            (level, optical axis along body +x). l is the depth along that axis.
        eps_m: segmentation link distance (DBSCAN eps, min_samples 1), metres.
        max_range_m: returns farther than this from the LiDAR are ignored, metres.
        sector_half_angle_rad: only beams within +-this of forward are used (LiDAR frame;
            with the LiDAR behind the camera that holds every return ahead of the camera
            within this bearing of its optical axis). The D435 colour camera sees +-35 deg;
            the rest keeps the track while the target passes beside the car, out of the
            camera's view.
        bearing_margin_rad: slack on "the cluster's span holds the detection's bearing".
        sign_width_m: (min, max) width of a stop sign's LiDAR cut across the line of sight:
            0.07 m face on, ~0.04 m at 55 deg, a single return when seen nearly edge on.
        obstacle_width_m: the same for a crate (0.16 m face on, up to ~0.2 m at an angle).
            A cluster fits when [extent, extent + 2 beam spacings] (the widths its returns
            allow) meets (min, max) widened by one beam spacing; beyond ~2 m a sign's cut
            and a crate are hard to tell apart by width alone.
        sign_box_width_m: (min, max) width the detection's box implies at the cluster's
            depth, for a stop sign (0.10 m across flats, narrower when seen obliquely);
            checked when a track starts.
        obstacle_box_width_m: the same for a crate.
        sign_box_height_max_m: the tallest a stop sign's box may be at the cluster's depth
            when a track starts. The plate is 0.10 m across flats, and its red mask's box
            about 0.09 m tall, a height that does not shrink when the sign is seen obliquely,
            as the width does: 0.125 m leaves two pixels of slack at 4 m and rejects a
            return from 1.4 x or more the sign's distance, the background that a sign the
            scan plane misses leaves in its box.
        obstacle_box_height_max_m: the same for a crate.
        vehicle_width_m, vehicle_box_width_m, vehicle_box_height_max_m: the same for a QCar 2 ahead.
            The scan plane (0.193 m up) cuts another QCar 2 only at its own RPLIDAR (0.076 m
            across) and, seen at an angle, its roof's edge; its box spans the car, flank included.
        vehicle_scan_behind_m: how far behind the face the camera sees the scan plane cuts a car
            ahead, m: its RPLIDAR's near side stands 0.16 m behind its rear bumper (its MJCF). The
            tracker moves the camera's depth back by it to start a track, and reports the depth of
            the car's rear (the track's depth less it), the quantity the camera's depth measures.
        gate_radius_m: association gate around the predicted position right after support.
        gate_growth_mps: the gate grows by this per second without support (slowly: odometry
            drifts little in a second, and a wide gate would take in other objects).
        smoothing: weight of a new measurement in the position update, (0, 1]; 1 = none.
        start_depth_tolerance_m: a track starts only on a cluster whose depth agrees with
            the detection's depth distance within this, m (when there is one).
        report_max_age_s: the coasted value is reported (not NaN) for at most this long
            after the last support, seconds (2.5 scan periods: covers the gap between
            scans, not a missing scan).
        drop_after_s: the track is dropped after this long without support, seconds.
    """

    lidar_position_m: tuple[float, float] = (-0.012, 0.0)
    camera_position_m: tuple[float, float] = (0.095, 0.032)
    eps_m: float = 0.06
    max_range_m: float = 4.0
    sector_half_angle_rad: float = math.radians(80.0)
    bearing_margin_rad: float = math.radians(1.0)
    sign_width_m: tuple[float, float] = (0.02, 0.12)
    obstacle_width_m: tuple[float, float] = (0.10, 0.26)
    sign_box_width_m: tuple[float, float] = (0.015, 0.16)
    obstacle_box_width_m: tuple[float, float] = (0.08, 0.32)
    sign_box_height_max_m: float = 0.125
    obstacle_box_height_max_m: float = 0.5
    vehicle_width_m: tuple[float, float] = (0.03, 0.30)
    vehicle_box_width_m: tuple[float, float] = (0.08, 0.60)
    vehicle_box_height_max_m: float = 0.4
    vehicle_scan_behind_m: float = 0.16
    gate_radius_m: float = 0.12
    gate_growth_mps: float = 0.1
    smoothing: float = 0.5
    start_depth_tolerance_m: float = 0.08
    report_max_age_s: float = 0.25
    drop_after_s: float = 1.0

    def __post_init__(self) -> None:
        for name in ("lidar_position_m", "camera_position_m"):
            value = getattr(self, name)
            if not (isinstance(value, tuple) and len(value) == 2
                    and all(isinstance(v, (int, float)) and abs(v) <= 1.0 for v in value)):
                raise ValueError(f"{name} must be an (x, y) pair with |x|, |y| <= 1 m, got {value!r}")
        _check_range("eps_m", self.eps_m, 0.005, 1.0, "m")
        _check_range("max_range_m", self.max_range_m, 0.2, 50.0, "m")
        _check_range("sector_half_angle_rad", self.sector_half_angle_rad, 0.05, math.radians(85.0), "rad")
        _check_range("bearing_margin_rad", self.bearing_margin_rad, 0.0, 0.5, "rad")
        for name in ("sign_width_m", "obstacle_width_m", "sign_box_width_m", "obstacle_box_width_m", "vehicle_width_m",
                     "vehicle_box_width_m"):
            _check_pair(name, getattr(self, name), 0.0, 2.0)
        _check_range("gate_radius_m", self.gate_radius_m, 0.01, 2.0, "m")
        _check_range("gate_growth_mps", self.gate_growth_mps, 0.0, 5.0, "m/s")
        if isinstance(self.smoothing, bool) or not isinstance(self.smoothing, (int, float)) or not 0 < self.smoothing <= 1:
            raise ValueError(f"smoothing must be in (0, 1], got {self.smoothing!r}")
        _check_range("start_depth_tolerance_m", self.start_depth_tolerance_m, 0.0, 5.0, "m")
        _check_range("sign_box_height_max_m", self.sign_box_height_max_m, 0.01, 2.0, "m")
        _check_range("obstacle_box_height_max_m", self.obstacle_box_height_max_m, 0.01, 2.0, "m")
        _check_range("vehicle_box_height_max_m", self.vehicle_box_height_max_m, 0.01, 2.0, "m")
        _check_range("vehicle_scan_behind_m", self.vehicle_scan_behind_m, 0.0, 2.0, "m")
        _check_range("report_max_age_s", self.report_max_age_s, 0.0, 10.0, "s")
        _check_range("drop_after_s", self.drop_after_s, 0.0, 60.0, "s")

    def width_m(self, target: str) -> tuple[float, float]:
        """(min, max) LiDAR width of a target kind, metres."""
        return getattr(self, f"{target}_width_m")

    def box_height_max_m(self, target: str) -> float:
        """The tallest a detection box of a target kind may be at the cluster's depth, metres."""
        return getattr(self, f"{target}_box_height_max_m")

    def box_width_m(self, target: str) -> tuple[float, float]:
        """(min, max) width a detection box of a target kind implies, metres."""
        return getattr(self, f"{target}_box_width_m")

    def scan_behind_m(self, target: str | None) -> float:
        """How far behind the face the camera sees the scan plane cuts a target kind, m."""
        return self.vehicle_scan_behind_m if target == "vehicle" else 0.0


@dataclass(frozen=True)
class LidarTargetState:
    """What the tracker holds after a step (for logs and viewers).

    Attributes:
        has_track: whether a target is tracked (supported recently or coasting).
        target: the tracked kind ("sign" or "obstacle"), None without a track.
        position: (x, y) of the tracked point in the camera frame (x along the optical
            axis, y left), metres; NaN without a track. Coasting tracks are included.
        depth: the value the last step returned (l), metres; NaN when not supported.
        supported: whether ``depth`` is a supported value (finite).
        last_support_age_s: seconds since the last scan that supported the track; inf
            without a track.
        gate_radius_m: the association gate for the next scan, metres; NaN without a track.
        n_points: returns in the cluster that last supported the track (0 without one).
        n_clusters: clusters in the forward sector on the last scan.
    """

    has_track: bool
    target: str | None
    position: tuple[float, float]
    depth: float
    supported: bool
    last_support_age_s: float
    gate_radius_m: float
    n_points: int
    n_clusters: int
