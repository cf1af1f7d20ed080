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

How high the plate stands and how thick its pole is are a scenario parameter
(``SignGeometry``): the car's 2D LiDAR scans at z = 0.193 m, so with ``PLATE_IN_SCAN`` (the
default) it meets the plate, and with ``POLE_ONLY`` it meets only the thin pole.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np

from racf.sim.world import map_facts
from racf.sim.world.road_graph import Path, qcar2_road_graph

__all__ = ["PLATE_IN_SCAN", "POLE_ONLY", "SIGN_CENTRE_HEIGHT_M", "SIGN_FACE_ACROSS_FLATS_M", "SIGN_GEOMETRIES",
           "SIGN_RED_FACE_ACROSS_FLATS_M",
           "SignGeometry", "StopSign", "stop_signs"]

#: Octagon size across flats. A 1/10-scale road sign would be ~0.075 m; Quanser's props
#: are larger, and 0.10 m keeps the sign in the LiDAR's scan plane (z = 0.193 m) with the
#: default geometry. The same for every geometry.
SIGN_FACE_ACROSS_FLATS_M = 0.10
#: The red octagon inside the plate's white border, across flats: what a detector outlines,
#: and the known size the car's size witness measures against (``SizeDistance``).
SIGN_RED_FACE_ACROSS_FLATS_M = 0.088
#: Height of the octagon's centre above the floor with the default geometry
#: (``PLATE_IN_SCAN.centre_height_m``); a sign's own is ``StopSign.centre``.
SIGN_CENTRE_HEIGHT_M = 0.23

_PLATE_BOTTOM_RANGE_M = (0.05, 0.6)
_POLE_DIAMETER_RANGE_M = (0.002, 0.05)


def _checked_length(name: str, value: object, low: float, high: float) -> float:
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        # A ValueError, not a TypeError: configs built from flags and files catch one kind.
        message = (f"SignGeometry.{name} must be a number of metres in [{low}, {high}], "
                   f"got {value!r} ({type(value).__name__})")
        raise ValueError(message)  # noqa: TRY004
    value = float(value)
    if math.isnan(value) or not low <= value <= high:
        raise ValueError(f"SignGeometry.{name} must be in [{low}, {high}] m, got {value!r}")
    return value


@dataclass(frozen=True)
class SignGeometry:
    """How a stop sign is built: where its plate starts and how thick its pole is.

    The plate (``SIGN_FACE_ACROSS_FLATS_M`` across flats) sits on a round pole that stands
    just behind it and reaches up to the plate's centre. Hashable: models and sign lists
    are cached per geometry.

    Attributes:
        plate_bottom_m: height of the plate's lowest edge above the floor, in [0.05, 0.6] m.
        pole_diameter_m: the pole's diameter, in [0.002, 0.05] m.

    Raises:
        ValueError: a value that is not a real number (bools included), NaN, or out of its
            range; the message names the field and the range.
    """

    plate_bottom_m: float = 0.18
    pole_diameter_m: float = 0.008

    def __post_init__(self) -> None:
        object.__setattr__(self, "plate_bottom_m",
                           _checked_length("plate_bottom_m", self.plate_bottom_m, *_PLATE_BOTTOM_RANGE_M))
        object.__setattr__(self, "pole_diameter_m",
                           _checked_length("pole_diameter_m", self.pole_diameter_m, *_POLE_DIAMETER_RANGE_M))

    @property
    def centre_height_m(self) -> float:
        """Height of the plate's centre above the floor, m (rounded to the nanometre, so
        the default's is exactly ``SIGN_CENTRE_HEIGHT_M``)."""
        return round(self.plate_bottom_m + SIGN_FACE_ACROSS_FLATS_M / 2, 9)

    @property
    def plate_top_m(self) -> float:
        """Height of the plate's top edge above the floor, m."""
        return round(self.plate_bottom_m + SIGN_FACE_ACROSS_FLATS_M, 9)

    @property
    def pole_radius_m(self) -> float:
        """The pole's radius, m."""
        return self.pole_diameter_m / 2


#: The default: plate 0.18-0.28 m on an 8 mm pole. The LiDAR's scan plane (z = 0.193 m)
#: meets the plate 13 mm above its bottom edge, where the octagon is 67 mm wide.
PLATE_IN_SCAN = SignGeometry()
#: The US urban rule (MUTCD: plate bottom >= 7 ft = 2.13 m, a 30 in = 0.76 m plate) at
#: 1/10 scale: plate bottom 0.21 m (we keep our 0.10 m plate, not the rule's 76 mm) on a
#: 6 mm pole. The scan plane (z = 0.193 m) passes 17 mm under the plate: it meets only
#: the pole.
POLE_ONLY = SignGeometry(plate_bottom_m=0.21, pole_diameter_m=0.006)
#: The named geometries, by the name scenarios use.
SIGN_GEOMETRIES: dict[str, SignGeometry] = {"plate": PLATE_IN_SCAN, "pole": POLE_ONLY}

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
        geometry: the plate's height and the pole's diameter.
    """

    index: int
    position: tuple[float, float]
    face_yaw: float
    route: tuple[int, ...]
    path: Path
    stop_line: tuple[float, float]
    stop_s: float
    earliest_start_s: float
    geometry: SignGeometry = PLATE_IN_SCAN

    @property
    def centre(self) -> np.ndarray:
        """(3,) centre of the octagon in the map frame, metres."""
        return np.array([*self.position, self.geometry.centre_height_m])


def stop_signs(geometry: SignGeometry = PLATE_IN_SCAN) -> tuple[StopSign, ...]:
    """The four stop signs of the map with their approaches, built to ``geometry``.

    Cached per geometry: equal geometries give the same tuple. Only ``centre`` (and the
    ``geometry`` field) depend on the geometry; positions, routes and stop lines do not.
    """
    if not isinstance(geometry, SignGeometry):
        raise TypeError(f"geometry must be a SignGeometry, got {type(geometry).__name__}")
    return _signs_built(geometry)


@lru_cache(maxsize=8)
def _signs_built(geometry: SignGeometry) -> tuple[StopSign, ...]:
    return tuple(replace(sign, geometry=geometry) for sign in _signs())


@lru_cache(maxsize=1)
def _signs() -> tuple[StopSign, ...]:
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
