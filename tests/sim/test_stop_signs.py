"""The four stop signs: published poses, stop lines on the route, sign placement relative to the lane."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sim.world import map_facts
from sim.world.road_graph import qcar2_road_graph
from sim.world.stop_signs import SIGN_CENTRE_HEIGHT_M, SIGN_FACE_ACROSS_FLATS_M, stop_signs

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
