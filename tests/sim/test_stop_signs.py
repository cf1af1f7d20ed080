"""The four stop signs: published poses, stop lines on the route, sign placement relative to the lane,
and their build (``SignGeometry``)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from racf.sim.world import map_facts
from racf.sim.world.road_graph import qcar2_road_graph
from racf.sim.world.stop_signs import (
    PLATE_IN_SCAN,
    POLE_ONLY,
    SIGN_CENTRE_HEIGHT_M,
    SIGN_FACE_ACROSS_FLATS_M,
    SIGN_GEOMETRIES,
    SignGeometry,
    stop_signs,
)

# Published facts (shared/reference/qcar2.md).
PUBLISHED_SIGNS = [(-1.5, 3.6, -35.0), (-1.5, 2.2, 35.0), (2.410, 0.206, -90.0), (1.766, 1.697, 90.0)]
PUBLISHED_STOP_LINES = {2: (2.21, 0.2), 3: (1.951, 1.68)}
SIGNS = stop_signs()


def _wrap(a: float) -> float:
    return (a + math.pi) % (2 * math.pi) - math.pi


def test_four_signs_at_published_positions():
    assert len(SIGNS) == 4
    assert [s.index for s in SIGNS] == [0, 1, 2, 3]
    for sign, (x, y, yaw) in zip(SIGNS, PUBLISHED_SIGNS):
        assert sign.position == pytest.approx((x, y), abs=1e-9)
        # The face is in the published plane (the published yaw or its reverse).
        assert abs(math.sin(sign.face_yaw - math.radians(yaw))) < 1e-9
        assert sign.centre == pytest.approx([x, y, SIGN_CENTRE_HEIGHT_M])
    assert map_facts.STOP_SIGNS == tuple(PUBLISHED_SIGNS)


def test_sign_size_plausible_and_in_lidar_plane():
    assert 0.075 <= SIGN_FACE_ACROSS_FLATS_M <= 0.2
    lidar_z = 0.193
    half_height = SIGN_FACE_ACROSS_FLATS_M / 2
    assert SIGN_CENTRE_HEIGHT_M - half_height <= lidar_z <= SIGN_CENTRE_HEIGHT_M + half_height


@pytest.mark.parametrize("index, line", sorted(PUBLISHED_STOP_LINES.items()))
def test_official_stop_lines_at_published_positions(index, line):
    assert SIGNS[index].stop_line == pytest.approx(line, abs=1e-9)
    assert map_facts.STOP_LINES[index - 2] == line


@pytest.mark.parametrize("sign", SIGNS, ids=lambda s: f"sign{s.index}")
def test_stop_line_lies_on_the_route(sign):
    path = sign.path
    s, lateral = path.project(np.asarray(sign.stop_line))
    assert abs(lateral) < 0.05
    assert s == pytest.approx(sign.stop_s, abs=0.01)
    x, y, _ = path.pose_at(sign.stop_s)
    assert math.dist((x, y), sign.stop_line) < 0.05
    # The route is connected and follows the road graph.
    graph = qcar2_road_graph()
    for a, b in zip(sign.route, sign.route[1:]):
        assert (a, b) in graph.paths
    assert path.length == pytest.approx(sum(graph.paths[e].length for e in zip(sign.route, sign.route[1:])), abs=1e-6)
    # There is room to approach: the stop line is well inside the route.
    assert 0.5 < sign.stop_s < path.length
    assert 0.0 <= sign.earliest_start_s < sign.stop_s - 1.0


@pytest.mark.parametrize("sign", SIGNS, ids=lambda s: f"sign{s.index}")
def test_sign_beside_the_stop_line(sign):
    x, y, heading = sign.path.pose_at(sign.stop_s)
    rel = np.asarray(sign.position) - (x, y)
    lateral = -math.sin(heading) * rel[0] + math.cos(heading) * rel[1]  # left positive
    along = math.cos(heading) * rel[0] + math.sin(heading) * rel[1]
    # Sign 1 stands across the northbound lane, on the left of its southbound approach.
    if sign.index == 1:
        assert 0.4 < lateral < 0.55
    else:
        assert -0.4 < lateral < -0.1, "sign is not on the right of the lane"
    assert abs(along) < 0.1, "sign is not beside the stop line"


@pytest.mark.parametrize("sign", SIGNS, ids=lambda s: f"sign{s.index}")
def test_sign_ahead_and_facing_the_approaching_car(sign):
    # Sign 1 stands 0.48 m to the side at 55 deg; its face turns away 0.6 m before the line.
    for before in (1.5, 1.0) if sign.index == 1 else (1.5, 1.0, 0.5):
        x, y, heading = sign.path.pose_at(sign.stop_s - before)
        rel = np.asarray(sign.position) - (x, y)
        depth = math.cos(heading) * rel[0] + math.sin(heading) * rel[1]
        assert depth > 0, f"sign behind the car {before} m before the stop line"
        # The face normal points towards the car.
        normal = np.array([math.cos(sign.face_yaw), math.sin(sign.face_yaw)])
        assert float(normal @ -rel) > 0, f"the car sees the back of sign {sign.index}"
    # At the stop line the face looks roughly back down the lane.
    _, _, heading = sign.path.pose_at(sign.stop_s)
    assert abs(_wrap(sign.face_yaw - (heading + math.pi))) < math.radians(60)


def test_no_other_sign_between_start_and_target():
    for sign in SIGNS:
        for other in SIGNS:
            if other.index == sign.index:
                continue
            s, lateral = sign.path.project(np.asarray(other.position))
            faces_lane = math.cos(other.face_yaw - sign.path.pose_at(s)[2]) < 0
            if abs(lateral) < 0.5 and faces_lane and s < sign.stop_s:
                assert s < sign.earliest_start_s


# -- SignGeometry: the plate's height and the pole's diameter, a scenario parameter ------


def test_default_geometry_is_the_old_build():
    assert SignGeometry() == PLATE_IN_SCAN == SIGN_GEOMETRIES["plate"]
    assert PLATE_IN_SCAN.plate_bottom_m == 0.18 and PLATE_IN_SCAN.pole_diameter_m == 0.008
    assert PLATE_IN_SCAN.centre_height_m == SIGN_CENTRE_HEIGHT_M == 0.23  # exactly: the MJCF text is unchanged
    assert PLATE_IN_SCAN.pole_radius_m == 0.004
    assert stop_signs() is stop_signs(PLATE_IN_SCAN) is stop_signs(SignGeometry(0.18, 0.008))
    assert all(s.geometry == PLATE_IN_SCAN for s in SIGNS)


def test_pole_only_preset_puts_the_plate_above_the_scan_plane():
    lidar_z = 0.193
    assert POLE_ONLY is SIGN_GEOMETRIES["pole"]
    assert (POLE_ONLY.plate_bottom_m, POLE_ONLY.pole_diameter_m) == (0.21, 0.006)
    assert POLE_ONLY.plate_bottom_m > lidar_z
    assert POLE_ONLY.centre_height_m == 0.26 and POLE_ONLY.plate_top_m == pytest.approx(0.31)
    assert PLATE_IN_SCAN.plate_bottom_m < lidar_z < PLATE_IN_SCAN.plate_top_m


def test_stop_signs_carry_their_geometry():
    signs = stop_signs(POLE_ONLY)
    assert signs is stop_signs(POLE_ONLY)  # cached per geometry
    for sign, default in zip(signs, SIGNS):
        assert sign.geometry == POLE_ONLY
        assert sign.centre == pytest.approx([*default.position, 0.26])
        # Everything but the build is the default's.
        assert (sign.index, sign.position, sign.face_yaw, sign.route, sign.stop_line, sign.stop_s,
                sign.earliest_start_s) == (default.index, default.position, default.face_yaw, default.route,
                                           default.stop_line, default.stop_s, default.earliest_start_s)
    with pytest.raises(TypeError, match="SignGeometry"):
        stop_signs(0.21)


def test_geometry_is_hashable_and_keeps_numbers_as_floats():
    g = SignGeometry(plate_bottom_m=np.float64(0.3), pole_diameter_m=0.01)
    assert type(g.plate_bottom_m) is float
    assert hash(g) == hash(SignGeometry(0.3, 0.01)) and g == SignGeometry(0.3, 0.01)
    assert {PLATE_IN_SCAN: 1, POLE_ONLY: 2}[SignGeometry(0.21, 0.006)] == 2
    # The ends of the ranges are allowed.
    SignGeometry(0.05, 0.002)
    SignGeometry(0.6, 0.05)


@pytest.mark.parametrize("field, value", [
    ("plate_bottom_m", 0.049), ("plate_bottom_m", 0.61), ("plate_bottom_m", -0.2), ("plate_bottom_m", math.nan),
    ("plate_bottom_m", math.inf), ("plate_bottom_m", True), ("plate_bottom_m", "0.2"), ("plate_bottom_m", None),
    ("pole_diameter_m", 0.0019), ("pole_diameter_m", 0.051), ("pole_diameter_m", 0.0), ("pole_diameter_m", math.nan),
    ("pole_diameter_m", False), ("pole_diameter_m", [0.006]),
])
def test_bad_geometry_is_named_with_its_range(field, value):
    low, high = {"plate_bottom_m": (0.05, 0.6), "pole_diameter_m": (0.002, 0.05)}[field]
    with pytest.raises(ValueError, match=rf"SignGeometry\.{field} must be .*in \[{low}, {high}\]"):
        SignGeometry(**{field: value})


def test_geometry_is_frozen():
    with pytest.raises(AttributeError):
        PLATE_IN_SCAN.plate_bottom_m = 0.3  # type: ignore[misc]
