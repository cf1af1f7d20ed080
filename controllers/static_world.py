"""Whether what the depth shows at a sign's place stands still: a sign does not move.

The car knows how it moved between two frames (its own localisation). The points the depth showed
at the map's place on one frame, carried into the next camera by that motion, must read there at
the depth they are predicted to have, whatever they are: the plate, the wall behind it, a grazing
wall. A depth that reads them steadily further (or nearer) than that, frame after frame, shows
something no static world shows: a range moved along the camera's rays (the frustum attack on
depth and LiDAR together, Hallyburton et al., USENIX Security 2022, which no cross-check of the
two sensors sees). The check adds up the median misfit frame by frame and fits its rate over a
short window; a static world can make it jump (a localisation fix, an edge's parallax) but not run
in a line, so a fit with a small residual is asked for. Once caught, the depth stays outvoted for
the rest of the approach: an attacker who stops the ramp does not earn trust back.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from racf.controllers.distance import CameraModel

__all__ = ["StaticWorldConfig", "StaticWorldCheck", "CameraPose", "pixels_to_world", "world_to_camera"]


@dataclass(frozen=True)
class StaticWorldConfig:
    """The static-world check's settings.

    Attributes:
        window_s: the frames a rate is fitted over, s back from the newest.
        min_frames: the fewest frames a rate is fitted on.
        min_span_s: the shortest time those frames span, s.
        rate_mps: a depth that runs from its prediction faster than this moves, m/s (the car's
            odometry between two frames errs by millimetres).
        residual_m: the fit's largest RMS residual, m (a jump leaves a residual of half the jump).
        min_points: the fewest carried points seen again for a frame's misfit to count.
    """

    window_s: float = 0.4
    min_frames: int = 5
    min_span_s: float = 0.12
    rate_mps: float = 1.0
    residual_m: float = 0.05
    min_points: int = 6

    def __post_init__(self) -> None:
        for name, lo, hi in (("window_s", 0.05, 5.0), ("min_span_s", 0.0, 5.0), ("rate_mps", 0.05, 20.0),
                             ("residual_m", 0.0, 1.0)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not lo <= value <= hi:
                raise ValueError(f"{name} must be in [{lo}, {hi}], got {value!r}")
        for name, lo in (("min_frames", 3), ("min_points", 1)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < lo:
                raise ValueError(f"{name} must be an int >= {lo}, got {value!r}")
        if self.min_span_s > self.window_s:
            raise ValueError(f"min_span_s must be at most window_s ({self.window_s}), got {self.min_span_s!r}")


@dataclass(frozen=True)
class CameraPose:
    """Where the camera stands in the map's frame: its place and height, m, and its yaw, rad (it
    looks level, along the car's heading)."""

    x_m: float
    y_m: float
    height_m: float
    yaw_rad: float


def pixels_to_world(rows: np.ndarray, cols: np.ndarray, depth_m: np.ndarray, camera: CameraModel,
                    pose: CameraPose) -> np.ndarray:
    """(N, 3) the map-frame points that pixels (``rows``, ``cols``) at ``depth_m`` along the optical
    axis show."""
    fy = camera.fy if camera.fy is not None else camera.fx
    cy = camera.cy if camera.cy is not None else 0.0
    ahead = depth_m
    left = (camera.cx - (cols + 0.5)) / camera.fx * depth_m
    up = (cy - (rows + 0.5)) / fy * depth_m
    c, s = math.cos(pose.yaw_rad), math.sin(pose.yaw_rad)
    return np.column_stack([pose.x_m + c * ahead - s * left, pose.y_m + s * ahead + c * left, pose.height_m + up])


def world_to_camera(points: np.ndarray, camera: CameraModel, pose: CameraPose) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Map-frame points seen from ``pose``: (rows, cols, depth along the optical axis), pixels as floats."""
    fy = camera.fy if camera.fy is not None else camera.fx
    cy = camera.cy if camera.cy is not None else 0.0
    dx, dy = points[:, 0] - pose.x_m, points[:, 1] - pose.y_m
    c, s = math.cos(pose.yaw_rad), math.sin(pose.yaw_rad)
    ahead, left, up = c * dx + s * dy, -s * dx + c * dy, points[:, 2] - pose.height_m
    with np.errstate(divide="ignore", invalid="ignore"):
        cols = camera.cx - camera.fx * left / ahead - 0.5
        rows = cy - fy * up / ahead - 0.5
    return rows, cols, ahead


class StaticWorldCheck:
    """Carries what the depth shows at a place from frame to frame by the car's own motion; says
    when the depth runs away from it.

    Feed it each new frame (:meth:`observe`); :attr:`moving` latches True once caught, until
    :meth:`reset` (a new target).
    """

    def __init__(self, config: StaticWorldConfig | None = None) -> None:
        self.config = config or StaticWorldConfig()
        self.reset()

    def reset(self) -> None:
        self._frames: deque[tuple[float, float]] = deque()
        self._points = np.empty((0, 3))
        self.receded_m = 0.0  # the misfits added up, m (positive: further than predicted)
        self.moving = False
        self.rate_mps = math.nan

    def observe(self, t_s: float, depth: np.ndarray, camera: CameraModel, pose: CameraPose, rows: np.ndarray,
                cols: np.ndarray) -> bool:
        """A new frame at ``t_s`` from ``pose``, with the pixels of the place to watch. Returns :attr:`moving`."""
        depth = np.asarray(depth)  # only the place's pixels are read (as float64), not the whole frame copied
        h, w = depth.shape
        if self._points.size and math.isfinite(t_s):
            r, c, ahead = world_to_camera(self._points, camera, pose)
            inside = np.isfinite(r) & np.isfinite(c) & (ahead > 0.05)
            ri, ci = np.round(r[inside]).astype(int), np.round(c[inside]).astype(int)
            on = (ri >= 0) & (ri < h) & (ci >= 0) & (ci < w)
            now = depth[ri[on], ci[on]].astype(np.float64)
            seen = np.isfinite(now) & (now > 0.05)
            if np.count_nonzero(seen) >= self.config.min_points:
                self.receded_m += float(np.median(now[seen] - ahead[inside][on][seen]))
                self._judge(t_s)
        rows, cols = np.asarray(rows, int), np.asarray(cols, int)
        inside = (rows >= 0) & (rows < h) & (cols >= 0) & (cols < w)  # a place at the picture's edge
        rows, cols = rows[inside], cols[inside]
        d = depth[rows, cols].astype(np.float64)
        keep = np.isfinite(d) & (d > 0.05)
        self._points = pixels_to_world(rows[keep], cols[keep], d[keep], camera, pose)
        return self.moving

    def _judge(self, t_s: float) -> None:
        cfg = self.config
        self._frames.append((t_s, self.receded_m))
        while self._frames[0][0] < t_s - cfg.window_s:
            self._frames.popleft()
        if len(self._frames) < cfg.min_frames or self._frames[-1][0] - self._frames[0][0] < cfg.min_span_s:
            return
        t, x = (np.array(v) for v in zip(*self._frames))
        slope, offset = np.polyfit(t - t[0], x, 1)
        residual = float(np.sqrt(np.mean((x - offset - slope * (t - t[0])) ** 2)))
        self.rate_mps = float(slope)
        if abs(slope) > cfg.rate_mps and residual <= cfg.residual_m:
            self.moving = True
