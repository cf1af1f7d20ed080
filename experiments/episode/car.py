"""The car's side of an episode: what a real car's software is told.

The controllers see observations; this module hands them the map knowledge a real stack
has (the route, where the stop line is relative to the sign), the camera intrinsics and
the car's own geometry. Ground truth is the referee's (``info``), never read here.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np

from controllers import CameraModel, RouteFollower
from sim.world.drives import RouteTarget
from sim.world.road_graph import Path

__all__ = ["camera_model", "sign_depth_at_line", "route_follower", "map_bearing"]


def camera_model(env: gym.Env) -> CameraModel:
    """The perception stack's camera model from the env's camera intrinsics."""
    k = env.unwrapped.rig.intrinsics
    return CameraModel(width=k.width, fx=k.fx, cx=k.cx)


def sign_depth_at_line(env: gym.Env, target: RouteTarget) -> float:
    """The target's camera depth when the front bumper is on its stop line, m (from the map and the car's geometry)."""
    model = env.unwrapped.model
    camera_to_bumper = float(model.site("front_bumper").pos[0] - model.camera("d435").pos[0])
    return camera_to_bumper + (target.target_s - target.stop_s)


def route_follower(path: Path, cruise_mps: float, start_s: float = 0.0) -> RouteFollower:
    """Lane following along ``path`` (an approach's or a drive's), starting ``start_s`` m along it."""
    follower = RouteFollower(path.points, path.headings, path.arclength, path.curvature, cruise_mps)
    follower.reset(start_s)
    return follower


def map_bearing(env: gym.Env, target: RouteTarget, pose: np.ndarray) -> float:
    """Bearing of ``target`` from the camera's optical axis (rad, left positive), from the map and the car's pose.

    NaN when the map says the camera cannot see the target's face (a stop sign showing
    the car its back): no detection is its then.
    """
    model = env.unwrapped.model
    cx, cy = (float(v) for v in model.camera("d435").pos[:2])
    x, y, yaw = (float(v) for v in pose)
    c, s = np.cos(yaw), np.sin(yaw)
    tx, ty = target.target.centre[:2]
    dx, dy = tx - (x + c * cx - s * cy), ty - (y + s * cx + c * cy)
    face = getattr(target.target, "face_yaw", None)
    if face is not None and -(dx * np.cos(face) + dy * np.sin(face)) < 0.0:
        return float("nan")
    return float(np.arctan2(-s * dx + c * dy, c * dx + s * dy))
