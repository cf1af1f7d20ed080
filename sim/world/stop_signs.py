"""The four stop signs, their stop lines and the approach routes that lead to them.

A sign's face normal points along the published yaw (``face_yaw``). Signs 2 and 3 look
straight down the lanes that have official stop lines. Signs 0 and 1 stand between the west
road's two lanes: sign 0 (yaw -35 deg) faces the northbound lane (x = -1.716 m), sign 1
(yaw 35 deg) the southbound one (x = -1.984 m), which it stands on the left of. Both are
seen 55 deg off their normal. Signs 0 and 1 have no published stop line: theirs is placed
where the sign projects onto the lane, the rule the two official stop lines follow.

Sign 1 once served the northbound lane with its face turned by 180 deg; that approach comes
out of a right-hand curve beside the sign, so the camera never saw it. The southbound lane
has a 1.4 m straight in the sign's view, as the published yaw suggests.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from sim.world import map_facts
from sim.world.road_graph import Path, qcar2_road_graph

__all__ = ["StopSign", "stop_signs", "SIGN_FACE_ACROSS_FLATS_M", "SIGN_CENTRE_HEIGHT_M"]

#: Octagon size across flats. A 1/10-scale road sign would be ~0.075 m; Quanser's props
#: are larger, and 0.10 m keeps the sign in the LiDAR's scan plane (z = 0.193 m).
SIGN_FACE_ACROSS_FLATS_M = 0.10
#: Height of the octagon's centre above the floor.
SIGN_CENTRE_HEIGHT_M = 0.23

# sign index -> (route through the road graph, official stop line index or None)
_APPROACHES: dict[int, tuple[tuple[int, ...], int | None]] = {
    0: ((8, 23, 21), None),
    1: ((14, 20, 22, 10), None),
    2: ((0, 2, 4, 14), 0),
    3: ((16, 17, 15, 5), 1),
}


@dataclass(frozen=True)
class StopSign:
    """One stop sign and its approach.

    Attributes:
        index: 0..3, the order of the published list.
        position: (x, y) of the pole in the map frame, metres.
        face_yaw: direction the sign's face looks, radians (map frame).
        route: road-graph nodes of the approach route.
        path: the route's lane-centre path.
        stop_line: (x, y) centre of the stop line, metres.
        stop_s: arclength of the stop line along ``path``, metres.
        earliest_start_s: the first arclength a trial may start at (after any other sign
            that faces the same lane, so the target is the first stop sign the car meets).
    """

    index: int
    position: tuple[float, float]
    face_yaw: float
    route: tuple[int, ...]
    path: Path
    stop_line: tuple[float, float]
    stop_s: float
    earliest_start_s: float

    @property
    def centre(self) -> np.ndarray:
        """(3,) centre of the octagon in the map frame, metres."""
        return np.array([*self.position, SIGN_CENTRE_HEIGHT_M])


@lru_cache(maxsize=1)
def stop_signs() -> tuple[StopSign, ...]:
    """The four stop signs of the map with their approaches."""
    graph = qcar2_road_graph()
    signs = []
    for index, (x, y, yaw_deg) in enumerate(map_facts.STOP_SIGNS):
        route, line_index = _APPROACHES[index]
        path = graph.route_path(list(route))
        if line_index is None:
            s_line, _ = path.project(np.array([x, y]))
            lx, ly, _ = path.pose_at(s_line)
        else:
            lx, ly = map_facts.STOP_LINES[line_index]
            s_line, _ = path.project(np.array([lx, ly]))
        signs.append((index, (x, y), math.radians(yaw_deg),
                      route, path, (lx, ly), s_line))
    out = []
    for index, pos, face, route, path, line, s_line in signs:
        earliest = 0.0
        for other in signs:
            if other[0] == index:
                continue
            s_other, lateral = path.project(np.array(other[1]))
            # A sign showing this lane its back is no stop sign for it.
            faces_lane = math.cos(other[2] - path.pose_at(s_other)[2]) < 0
            if abs(lateral) < 0.5 and faces_lane and s_other < s_line:
                earliest = max(earliest, s_other + 0.15)
        out.append(StopSign(index, pos, face, route, path, line, s_line, earliest))
    return tuple(out)
