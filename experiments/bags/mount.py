"""Whether a recording's LiDAR mount is declared right: its returns, placed on the body by the
mapping's ``[lidar]`` and projected through the camera's declared intrinsics, must land on the depth
image where the depth camera sees the same surface. A mount turned the wrong way, or placed
elsewhere, never agrees, and silently costs the car its LiDAR witness: the replay says so in one
line (:func:`racf.experiments.bags.replay.replay_bag`'s ``warnings``).

Any surface counts (walls, the sign, the car ahead), so a drive whose LiDAR never tracks its target
is not taken for a bad mount.
"""

from __future__ import annotations

import numpy as np

__all__ = ["LidarMountCheck"]

#: Returns compared before a verdict, the share of them a true mount agrees on (at least), and how
#: near agreeing is: within 5 cm or 5 % of the distance, over a few image rows around the scan plane.
_MIN_POINTS, _MIN_SHARE, _NEAR_M, _NEAR_SHARE, _ROWS = 50, 0.2, 0.05, 0.05, 2


class LidarMountCheck:
    """A replay's step hook: every ``every`` steps, the LiDAR's returns in the camera's view against the
    depth image (the car's own observation and its declared build)."""

    def __init__(self, calibration, scan_above_camera_m: float, every: int = 5) -> None:
        self.calibration = calibration
        self.scan_above_camera_m = scan_above_camera_m
        self.every = every
        self.compared = self.agreed = 0
        self._step = 0

    def __call__(self, env, obs: dict, info: dict, row: dict) -> None:
        self._step += 1
        if (self._step - 1) % self.every:
            return
        ranges = np.asarray(obs["lidar"], np.float64)
        angles = 2 * np.pi * np.arange(ranges.size) / ranges.size  # bin k: k degrees anticlockwise from ahead
        ok = np.isfinite(ranges) & (ranges > 0.2) & (ranges < 8.0)
        lx, ly = self.calibration.lidar_xy_m
        cx_m, cy_m = self.calibration.camera_xy_m
        x = lx + ranges[ok] * np.cos(angles[ok]) - cx_m  # ahead of the camera
        y = ly + ranges[ok] * np.sin(angles[ok]) - cy_m  # left of it
        k = self.calibration.camera
        depth = np.asarray(obs["depth"][..., 0], np.float64)
        height, width = depth.shape
        ahead = x > 0.3
        x, y = x[ahead], y[ahead]
        u = np.rint(k.cx - k.fx * y / x).astype(int)
        fy, cy = k.fy or k.fx, k.cy if k.cy is not None else (height - 1) / 2.0
        v = np.rint(cy - fy * self.scan_above_camera_m / x).astype(int)
        inside = (u >= 0) & (u < width) & (v >= _ROWS) & (v < height - _ROWS)
        x, u, v = x[inside], u[inside], v[inside]
        band = np.stack([depth[v + dv, u] for dv in range(-_ROWS, _ROWS + 1)])
        seen = (band > 0).any(axis=0)
        gap = np.where(band > 0, np.abs(band - x), np.inf).min(axis=0)
        self.compared += int(seen.sum())
        self.agreed += int((seen & (gap <= np.maximum(_NEAR_M, _NEAR_SHARE * x))).sum())

    def warning(self, mapping) -> str | None:
        """One line when the LiDAR and the depth image seldom agree where both see; None otherwise."""
        if self.compared < _MIN_POINTS or self.agreed >= _MIN_SHARE * self.compared:
            return None
        return (f"the LiDAR's returns agree with the depth image on {self.agreed} of {self.compared} points where "
                f"both see ({self.agreed / self.compared:.0%}; a true mount: most): check the mapping's [lidar] "
                f"yaw_deg (now {mapping.lidar_yaw_deg:g}; Quanser's car 180, its virtual car 0) and position_m")
