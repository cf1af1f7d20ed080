"""Official facts of the Quanser Self-Driving Car Studio indoor map (large mat).

Numbers are copied from Quanser's public material (see ``shared/reference/qcar2.md``):
road-graph node poses, edge radii, sign, light and stop-line poses. Everything else in
the map (road surface, markings, walls, props) is generated from these facts.

Frame: the map frame, x east, y north, z up, metres; headings and yaws in degrees here
(the facts' own unit) and converted to radians by the code that uses them.
"""

from __future__ import annotations

__all__ = [
    "NODES",
    "EDGES",
    "ARC_RADII_M",
    "STOP_SIGNS",
    "STOP_LINES",
    "TRAFFIC_LIGHTS",
    "YIELD_SIGNS",
    "WALL_BOUNDS_M",
    "WALL_HEIGHT_M",
    "MAT_SIZE_M",
    "LANE_WIDTH_M",
    "ROUNDABOUT_CENTRE_M",
    "ROUNDABOUT_RADIUS_M",
]

#: Road-graph nodes: id -> (x m, y m, heading deg). Right-hand traffic.
NODES: dict[int, tuple[float, float, float]] = {
    0: (0.0, 0.130, -90.0),
    1: (0.269, 0.081, 90.0),
    2: (1.127, -1.085, 0.0),
    3: (1.127, -0.814, 180.0),
    4: (2.255, 0.081, 90.0),
    5: (1.984, 0.081, -90.0),
    6: (1.013, 1.101, 180.0),
    7: (1.235, 0.830, 0.0),
    8: (-0.749, 1.101, 180.0),
    9: (-0.749, 0.830, 0.0),
    10: (-1.282, -0.460, -42.0),
    11: (0.0, 2.163, -90.0),
    12: (0.0, 1.850, -90.0),
    13: (0.269, 1.850, 90.0),
    14: (2.255, 2.967, 90.0),
    15: (1.984, 1.850, -90.0),
    16: (0.908, 3.710, -80.6),
    17: (1.466, 3.151, -9.4),
    18: (0.623, 3.067, -138.0),
    19: (0.792, 2.859, 42.0),
    20: (0.0, 4.497, 180.0),
    21: (0.0, 4.227, 0.0),
    22: (-1.984, 2.967, -90.0),
    23: (-1.716, 2.967, 90.0),
}

#: Arc radius per edge letter, metres; "s" is a straight edge.
ARC_RADII_M: dict[str, float | None] = {
    "s": None,
    "i": 0.6217,
    "o": 0.8913,
    "c": 0.6777,
    "w": 0.7122,
    "k": 0.7631,
}

_EDGE_SPEC = (
    "0-2o 1-7i 1-8o 2-4o 3-1i 4-6o 5-3i 6-0o 6-8s 7-5i 8-10w 9-0i 9-7s 10-1i 10-2i "
    "1-13s 4-14s 6-13i 7-14o 8-23i 9-13o 11-12s 12-0s 12-7o 12-8i 13-19i 14-16c 14-20c "
    "15-5o 15-6i 16-17c 16-18i 17-15i 17-16c 17-20c 18-11k 19-17i 20-22o 21-16i 22-9o 22-10o 23-21i"
)


def _parse_edges(spec: str) -> tuple[tuple[int, int, str], ...]:
    edges = []
    for token in spec.split():
        start, rest = token.split("-")
        edges.append((int(start), int(rest[:-1]), rest[-1]))
    return tuple(edges)


#: Directed edges: (start node, end node, radius letter).
EDGES: tuple[tuple[int, int, str], ...] = _parse_edges(_EDGE_SPEC)

#: Stop signs: (x m, y m, yaw deg). Index = the sign number used by the env and CLI.
STOP_SIGNS: tuple[tuple[float, float, float], ...] = (
    (-1.5, 3.6, -35.0),
    (-1.5, 2.2, 35.0),
    (2.410, 0.206, -90.0),
    (1.766, 1.697, 90.0),
)

#: Stop lines, 0.27 m across the lane and 0.02 m along it: centre (x m, y m).
STOP_LINES: tuple[tuple[float, float], ...] = ((2.21, 0.2), (1.951, 1.68))

#: Traffic lights: (x m, y m, yaw deg). Static props.
TRAFFIC_LIGHTS: tuple[tuple[float, float, float], ...] = (
    (0.6, 1.55, 0.0),
    (-0.6, 1.28, 90.0),
    (-0.37, 0.3, 180.0),
    (0.75, 0.48, -90.0),
)

#: Yield signs: (x m, y m, yaw deg). Static props.
YIELD_SIGNS: tuple[tuple[float, float, float], ...] = (
    (0.0, -1.3, 180.0),
    (2.4, 3.2, -90.0),
    (1.1, 2.8, -145.0),
    (0.49, 3.8, 135.0),
)

#: Inner faces of the walls: (x_min, x_max, y_min, y_max), metres.
WALL_BOUNDS_M: tuple[float, float, float, float] = (-2.27, 2.53, -1.38, 4.72)
WALL_HEIGHT_M = 0.25
MAT_SIZE_M: tuple[float, float] = (4.8, 6.1)
LANE_WIDTH_M = 0.27
ROUNDABOUT_CENTRE_M: tuple[float, float] = (1.577, 3.82)
ROUNDABOUT_RADIUS_M = 0.678
