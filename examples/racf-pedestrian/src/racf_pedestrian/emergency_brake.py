"""The car's side of the example: automatic emergency braking for something upright in the lane.

A car stage (``racf.car_stages: upright_in_lane``) that the scenario's mission engages. Each new
depth frame it lifts every pixel to the camera's frame (the car's intrinsics and the camera's
height: the car's own build, never ground truth), keeps the points that stand on the lane ahead
(within the car's half width and a margin of the lane's centre line, placed from the map and the
car's own pose estimate; ``MIN_HEIGHT_M`` to ``MAX_HEIGHT_M`` above the floor; nearer than
``LOOK_AHEAD_M``) and, when enough of them make a thing, caps the car's
speed to what stops it ``STOP_SHORT_M`` before the nearest: sqrt(2 a d). A 1/10-scale person is
0.18 m tall, under the LiDAR's scan plane: the depth camera is the witness that sees them.

It publishes what it believes as a typed track (``publishes = "person"``, ``StageLimit.track``), so
``--supervisor`` supervises it as it does the stop sign: the supervisor reads the track, never the
stage. With one witness (the depth) there is nothing to vouch a person by, and the supervisor says so
(``sup_person_vouched`` stays false): it adds no limit of its own.
"""

from __future__ import annotations

import math

import numpy as np

from racf.experiments.car.stage import CarStage, CarView, StageColumn, StageLimit, TargetTrack

__all__ = ["UprightInLane"]

#: The lane ahead the stage watches: the car's half width (0.096 m) and a margin, m.
HALF_CORRIDOR_M = 0.16
#: Heights above the floor of what counts as upright, m (the floor and the camera's own noise below).
MIN_HEIGHT_M, MAX_HEIGHT_M = 0.04, 0.30
#: How far ahead of the camera the stage looks, m.
LOOK_AHEAD_M = 1.5
#: Pixels that make a thing (a 1/10 person at 1.5 m covers about 150).
MIN_PIXELS = 25
#: The deceleration it plans with, and how far short of the thing it stops, m/s^2 and m.
BRAKE_MPS2, STOP_SHORT_M = 1.5, 0.12


class UprightInLane(CarStage):
    """Automatic emergency braking: stop short of anything upright in the lane ahead (from the depth)."""

    name = "upright_in_lane"
    columns = (StageColumn("aeb_nearest_m", "m", "emergency brake: the nearest upright thing in the lane ahead, "
                                                 "from the camera (NaN: none)"),
               StageColumn("aeb_cap", "m/s", "emergency brake: its speed cap (inf: none)"))
    series = {"aeb_nearest_m": ((255, 120, 0), "upright in the lane (depth)")}
    publishes = "person"

    def reset(self) -> None:
        self._nearest = math.nan

    def step(self, view: CarView) -> StageLimit:
        if view.frame_new:
            self._nearest = self.nearest(view.obs["depth"][..., 0], self.lane_ahead(view))
        gap = self._nearest - self.context.bumper_ahead_of_camera_m - STOP_SHORT_M
        cap = math.inf if not math.isfinite(gap) else math.sqrt(2.0 * BRAKE_MPS2 * max(gap, 0.0))
        track = TargetTrack("person", self._nearest, cap, depth_m=self._nearest,
                            stop_at_m=self.context.bumper_ahead_of_camera_m + STOP_SHORT_M,
                            detected=math.isfinite(self._nearest))
        return StageLimit(cap, {"aeb_nearest_m": self._nearest, "aeb_cap": cap}, track=track)

    def lane_ahead(self, view: CarView) -> np.ndarray:
        """(N, 2) the lane's centre line ahead in the camera's frame (forward, left), m, from the map's
        path and the car's own pose estimate."""
        path = view.path
        ahead = (path.arclength >= view.progress_m) & (path.arclength <= view.progress_m + LOOK_AHEAD_M + 0.5)
        x, y, yaw = (float(a) for a in view.pose)
        c, s = math.cos(yaw), math.sin(yaw)
        cx, cy = self.context.camera_xy_m
        rel = path.points[ahead] - np.array([x + c * cx - s * cy, y + s * cx + c * cy])
        return np.column_stack([c * rel[:, 0] + s * rel[:, 1], -s * rel[:, 0] + c * rel[:, 1]])

    def nearest(self, depth: np.ndarray, lane: np.ndarray) -> float:
        """The nearest upright thing on ``lane`` (its centre line in the camera's frame), m along the
        optical axis (NaN: none)."""
        camera = self.context.camera
        fy = camera.fy if camera.fy is not None else camera.fx
        cy = camera.cy if camera.cy is not None else depth.shape[0] / 2
        v, u = np.indices(depth.shape)
        z = np.where(np.isfinite(depth) & (depth > 0.05) & (depth < LOOK_AHEAD_M), depth, np.nan)
        height = self.context.camera_height_m - (v - cy) * z / fy
        upright = (height > MIN_HEIGHT_M) & (height < MAX_HEIGHT_M)
        if int(upright.sum()) < MIN_PIXELS or len(lane) == 0:
            return math.nan
        forward, left = z[upright], -(u[upright] - camera.cx) * z[upright] / camera.fx
        # Each point's distance to the lane's centre line (its nearest sample, every few centimetres).
        off = np.hypot(forward[:, None] - lane[None, :, 0], left[:, None] - lane[None, :, 1]).min(axis=1)
        on_lane = off < HALF_CORRIDOR_M
        if int(on_lane.sum()) < MIN_PIXELS:
            return math.nan
        return float(np.quantile(forward[on_lane], 0.1))
