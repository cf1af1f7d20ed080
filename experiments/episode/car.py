"""The car's side of an episode: what a real car's software is told, and what it works out from it.

The car's software knows its own build (:class:`CarCalibration`: the camera's intrinsics and
where the camera and the front bumper sit on the body) and the map (the route, the targets
and their stop lines). Nothing here reads the simulator: the runner builds the calibration
once from the car's model (:func:`experiments.episode.stack.calibration`) and hands it in.
Ground truth is the referee's. (The pose the runner passes to :func:`map_bearing` is still
the simulator's; the car's own localisation replaces it in env v2.)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from controllers import CameraModel, RouteFollower
from sim.world.drives import RouteTarget
from sim.world.road_graph import Path

__all__ = ["CarCalibration", "sign_depth_at_line", "route_follower", "map_bearing"]


@dataclass(frozen=True)
class CarCalibration:
    """The car's build as its software knows it (body frame: x forward, y left).

    Attributes:
        camera: the camera's horizontal intrinsics.
        camera_xy_m: the camera's position on the body, m.
        bumper_x_m: the front bumper's position ahead of the body origin, m.
    """

    camera: CameraModel
    camera_xy_m: tuple[float, float]
    bumper_x_m: float


def sign_depth_at_line(calibration: CarCalibration, target: RouteTarget) -> float:
    """The target's camera depth when the front bumper is on its stop line, m (from the map and the car's build)."""
    camera_to_bumper = float(calibration.bumper_x_m - calibration.camera_xy_m[0])
    return camera_to_bumper + (target.target_s - target.stop_s)


def route_follower(path: Path, cruise_mps: float, start_s: float = 0.0) -> RouteFollower:
    """Lane following along ``path`` (an approach's or a drive's), starting ``start_s`` m along it."""
    follower = RouteFollower(path.points, path.headings, path.arclength, path.curvature, cruise_mps)
    follower.reset(start_s)
    return follower


def map_bearing(calibration: CarCalibration, target: RouteTarget, pose: np.ndarray) -> float:
    """Bearing of ``target`` from the camera's optical axis (rad, left positive), from the map and the car's pose.

    NaN when the map says the camera cannot see the target's face (a stop sign showing
    the car its back): no detection is its then.
    """
    cx, cy = calibration.camera_xy_m
    x, y, yaw = (float(v) for v in pose)
    c, s = np.cos(yaw), np.sin(yaw)
    tx, ty = target.target.centre[:2]
    dx, dy = tx - (x + c * cx - s * cy), ty - (y + s * cx + c * cy)
    face = getattr(target.target, "face_yaw", None)
    if face is not None and -(dx * np.cos(face) + dy * np.sin(face)) < 0.0:
        return float("nan")
    return float(np.arctan2(-s * dx + c * dy, c * dx + s * dy))
