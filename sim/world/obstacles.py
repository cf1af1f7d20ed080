"""Obstacles on the lanes: blue crates that the camera and the LiDAR both see.

They give the dataset approaches to something other than a stop sign (the paper's
benchmark has "other obstacles"). Each stands on a lane that no stop-sign approach uses,
at the end of a straight, with a virtual stop line ``STANDOFF_M`` before its near face.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from racf.sim.world.road_graph import Path, qcar2_road_graph

__all__ = ["Obstacle", "obstacles", "OBSTACLE_SIZE_M", "STANDOFF_M"]

#: Crate size (along the lane, across it, height), metres: tall enough for the LiDAR plane.
OBSTACLE_SIZE_M = (0.12, 0.16, 0.22)
#: The stop line sits this far before the crate's near face.
STANDOFF_M = 0.25

# obstacle index -> (route through the road graph, arclength fraction... given as a point on the lane)
_PLACES: tuple[tuple[tuple[int, ...], tuple[float, float]], ...] = (
    ((20, 22, 9, 7), (0.85, 0.830)),   # eastbound x-road, 1.6 m straight before it
    ((18, 11, 12, 0), (0.0, 0.450)),   # southbound centre road, 1.7 m straight before it
)


@dataclass(frozen=True)
class Obstacle:
    """One crate and its approach (the same fields the env uses of a ``StopSign``).

    Attributes:
        index: 0.. in ``obstacles()``.
        position: (x, y) of the centre of the crate's near face (towards the approach), m.
        yaw: lane heading at the crate, radians.
        body_centre: (x, y) of the crate's centre, m.
        route, path: the approach route and its lane-centre path.
        stop_line: (x, y) of the virtual stop line; ``stop_s`` its arclength.
        earliest_start_s: first arclength a run-up may start at.
    """

    index: int
    position: tuple[float, float]
    yaw: float
    body_centre: tuple[float, float]
    route: tuple[int, ...]
    path: Path
    stop_line: tuple[float, float]
    stop_s: float
    earliest_start_s: float = 0.0

    @property
    def centre(self) -> np.ndarray:
        """(3,) centre of the crate's near face, map frame, metres (what d_true measures to)."""
        return np.array([*self.position, OBSTACLE_SIZE_M[2] / 2])

    def corners(self) -> np.ndarray:
        """(8, 3) corners of the crate, map frame."""
        lx, ly, h = OBSTACLE_SIZE_M
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        out = []
        for dx in (-lx / 2, lx / 2):
            for dy in (-ly / 2, ly / 2):
                for z in (0.0, h):
                    out.append((self.body_centre[0] + c * dx - s * dy, self.body_centre[1] + s * dx + c * dy, z))
        return np.array(out)


@lru_cache(maxsize=1)
def obstacles() -> tuple[Obstacle, ...]:
    """The map's obstacles with their approaches."""
    graph = qcar2_road_graph()
    out = []
    for index, (route, (x, y)) in enumerate(_PLACES):
        path = graph.route_path(list(route))
        s_centre, _ = path.project(np.array([x, y]))
        cx, cy, yaw = path.pose_at(s_centre)
        s_face = s_centre - OBSTACLE_SIZE_M[0] / 2
        fx, fy, _ = path.pose_at(s_face)
        s_line = s_face - STANDOFF_M
        lx, ly, _ = path.pose_at(s_line)
        out.append(Obstacle(index, (fx, fy), yaw, (cx, cy), tuple(route), path, (lx, ly), s_line))
    return tuple(out)
