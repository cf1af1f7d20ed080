"""Whether the LiDAR sees the lane clear where a carried target could be.

A target tracked in the car's lane is dropped only when a range witness sees through where it could
stand: every beam at each lane point from the carried target's near end to its far end (and a car's
length beyond) returns from farther than that point. A beam with no return proves nothing (hiding a
car leaves none), nor does a lane point out of the scan's reach.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["lane_clear", "CAR_LENGTH_M", "CAR_HALF_WIDTH_M"]

#: A QCar 2's length and half width, m (``racf.sim.world.manager.QCAR2_BOX_M``, as the car's software knows it).
CAR_LENGTH_M, CAR_HALF_WIDTH_M = 0.425, 0.096
#: A return must lie this much beyond a lane point to show it clear, m.
_BEYOND_M = 0.05


def lane_clear(scan: np.ndarray, lane: np.ndarray, near_m: float, far_m: float,
               lidar_in_camera: tuple[float, float]) -> bool:
    """``scan``: the LiDAR's ranges (beam i at 2 pi i / N, counter-clockwise from ahead); ``lane``:
    (N, 2) lane points as (z ahead, y left) from the camera; ``near_m``, ``far_m``: where the carried
    target's rear can be (camera distance); ``lidar_in_camera``: the LiDAR's place in the camera's
    frame (ahead, left), m. True only when every such lane point is seen clear."""
    scan = np.asarray(scan, np.float64)
    if not (math.isfinite(near_m) and math.isfinite(far_m)) or scan.size == 0 or len(lane) == 0:
        return False
    z, y = lane[:, 0], lane[:, 1]
    where = (z >= near_m) & (z <= far_m + CAR_LENGTH_M)
    if not where.any() or z.max() < far_m + CAR_LENGTH_M:
        return False  # the lane in view ends before the target's farthest place: nothing to see through
    x, w = z[where] - lidar_in_camera[0], y[where] - lidar_in_camera[1]
    ranges, bearings = np.hypot(x, w), np.arctan2(w, x)
    step = 2 * math.pi / scan.size
    for r, bearing in zip(ranges, bearings):
        half = math.atan2(CAR_HALF_WIDTH_M, r)
        idx = np.arange(math.floor((bearing - half) / step), math.ceil((bearing + half) / step) + 1) % scan.size
        beams = scan[idx]
        if not (np.all(np.isfinite(beams)) and np.all(beams > r + _BEYOND_M)):
            return False
    return True
