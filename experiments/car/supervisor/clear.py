"""What the LiDAR sees on the lane: the first thing on it, and whether it is clear where a carried
target could be.

:func:`lane_return` is a range witness that needs no detector: the nearest lane point at which a
beam returns from (within ``AT_POINT_M`` of) that point. The vehicle detector finds a QCar 2 out to
about 1.1 m; the LiDAR sees it on the lane much farther.

A target tracked in the car's lane is dropped only when a range witness sees through where it could
stand: every beam at each lane point from the carried target's near end to its far end (and a car's
length beyond) returns from farther than that point. A beam with no return proves nothing (hiding a
car leaves none), nor does a lane point out of the scan's reach.
"""

from __future__ import annotations

import math

import numpy as np

from racf.vehicle import QCAR2_BOX_M

__all__ = ["along_lane", "lane_clear", "lane_return", "CAR_LENGTH_M", "CAR_HALF_WIDTH_M"]

#: A QCar 2's length and half width, m (its box, :data:`racf.vehicle.QCAR2_BOX_M`).
CAR_LENGTH_M, CAR_HALF_WIDTH_M = QCAR2_BOX_M[0], QCAR2_BOX_M[1] / 2
#: A return must lie this much beyond a lane point to show it clear, m.
_BEYOND_M = 0.05
#: Lane points nearer the LiDAR than this are not judged blind: its beams give nothing under 0.2 m,
#: and a point that near is under the car's own bonnet.
BLIND_FROM_M = 0.3
#: A return this near a lane point (before it) is something standing on the lane there, m.
AT_POINT_M = 0.1


def _beams(scan: np.ndarray, lane: np.ndarray, lidar_in_camera: tuple[float, float],
           half_width_m: float = CAR_HALF_WIDTH_M):
    """Each lane point's range from the LiDAR and the returns of the beams a car there would fill (or,
    with ``half_width_m``, the beams within that of the point either side)."""
    x, w = lane[:, 0] - lidar_in_camera[0], lane[:, 1] - lidar_in_camera[1]
    ranges, bearings = np.hypot(x, w), np.arctan2(w, x)
    step = 2 * math.pi / scan.size
    for r, bearing in zip(ranges, bearings):
        half = math.atan2(half_width_m, r)
        idx = np.arange(math.floor((bearing - half) / step), math.ceil((bearing + half) / step) + 1) % scan.size
        yield r, scan[idx]


def along_lane(axial_m: float, lane: np.ndarray | None) -> float:
    """The straight-line distance of a target on the lane that a witness reads ``axial_m`` along the
    camera's axis, m: the camera's distance to the lane point that lies ``axial_m`` ahead.

    The depth, the LiDAR's track and the box's size read along the camera's axis; the lane return and
    the clear gap are straight-line distances. In a bend the two part by r (1 - cos bearing): 0.15 m
    for a car 0.73 m away at 37 degrees, where the axial witnesses would otherwise put the car's worst
    case that much nearer and the stop rule brake hard for nothing. The conversion reads only the map
    and the car's own pose, and never gives less than ``axial_m``. Where the lane in view does not
    reach that far ahead (or there is no lane: ``lane`` None or empty), the reading itself.
    ``lane``: (N, 2) points as (z ahead, y left) from the camera, in order along the lane."""
    if lane is None or len(lane) < 2 or not math.isfinite(axial_m):
        return axial_m
    z, y = lane[:, 0], lane[:, 1]
    crossing = np.flatnonzero((z[:-1] <= axial_m) & (z[1:] >= axial_m))
    if not crossing.size:
        return axial_m
    i = int(crossing[0])
    share = (axial_m - z[i]) / (z[i + 1] - z[i]) if z[i + 1] > z[i] else 0.0
    return float(math.hypot(axial_m, y[i] + share * (y[i + 1] - y[i])))


def lane_return(scan: np.ndarray, lane: np.ndarray, lidar_in_camera: tuple[float, float]) -> float:
    """The camera's distance to the nearest lane point something stands on, as the LiDAR sees it, m
    (NaN: nothing on the lane in view): the straight-line distance, which in a bend is the clear gap's
    (:mod:`racf.vehicle`: the camera's distance to the rear less the bumper's lead), where the point's
    part along the camera's axis would put a car going round the bend ever nearer. ``lane``: (N, 2) points as (z ahead, y left) from the camera,
    in order along the lane.

    A return is the first thing on the lane only where the LiDAR is not blind at a nearer lane point:
    one where no beam of the middle half of a car's width returns (a car hidden from the LiDAR leaves
    all of its beams without a return; the sensor's own dropouts and bins without a sample are
    scattered) makes it NaN, never the lane behind."""
    scan = np.asarray(scan, np.float64)
    if scan.size == 0 or len(lane) == 0:
        return math.nan
    ahead = lane[lane[:, 0] > 0.05]
    middles = _beams(scan, ahead, lidar_in_camera, CAR_HALF_WIDTH_M / 2)
    for point, (r, beams), (_, middle) in zip(ahead, _beams(scan, ahead, lidar_in_camera), middles):
        seen = np.isfinite(beams) & (beams > 0)
        hit = seen & (beams >= r - AT_POINT_M) & (beams <= r + _BEYOND_M)
        if hit.any():
            return float(np.hypot(point[0], point[1]))
        if r >= BLIND_FROM_M and not np.any(np.isfinite(middle) & (middle > 0)):
            return math.nan  # blind before any return: what lies behind is not the first thing on the lane
    return math.nan


def lane_clear(scan: np.ndarray, lane: np.ndarray, near_m: float, far_m: float,
               lidar_in_camera: tuple[float, float]) -> bool:
    """``scan``: the LiDAR's ranges (beam i at 2 pi i / N, counter-clockwise from ahead); ``lane``:
    (N, 2) lane points as (z ahead, y left) from the camera; ``near_m``, ``far_m``: where the carried
    target's rear can be (the camera's straight-line distance); ``lidar_in_camera``: the LiDAR's place
    in the camera's frame (ahead, left), m. True only when every such lane point is seen clear."""
    scan = np.asarray(scan, np.float64)
    if not (math.isfinite(near_m) and math.isfinite(far_m)) or scan.size == 0 or len(lane) == 0:
        return False
    away = np.hypot(lane[:, 0], lane[:, 1])  # straight-line distances, as near_m and far_m are (in a bend, past z)
    where = (away >= near_m) & (away <= far_m + CAR_LENGTH_M)
    if not where.any() or away.max() < far_m + CAR_LENGTH_M:
        return False  # the lane in view ends before the target's farthest place: nothing to see through
    for r, beams in _beams(scan, lane[where], lidar_in_camera):
        if not (np.all(np.isfinite(beams)) and np.all(beams > r + _BEYOND_M)):
            return False
    return True
