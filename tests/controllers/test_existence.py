"""The existence witnesses and RACF's vote over them (racf.controllers.existence)."""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from racf.controllers import CameraModel
from racf.controllers.existence import (
    NO_WITNESSES,
    ExistenceWitnesses,
    Hypothesis,
    depth_hole,
    depth_witness,
    free_standing,
    lidar_witness,
    vote,
)

CAMERA = CameraModel(width=320, fx=227.6, cx=154.25, fy=229.7, cy=106.8)


def _witnesses(detectors=(False, False), depth=False, lidar=False, blind=False, mapped=False,
               moving=False) -> ExistenceWitnesses:
    return ExistenceWitnesses(detectors, (math.nan, math.nan), detectors, depth, lidar, blind, mapped, math.nan,
                              math.nan, "map" if mapped else "detector", moving=moving)


@given(st.tuples(st.booleans(), st.booleans()), st.booleans(), st.booleans(), st.booleans(), st.booleans(),
       st.booleans())
def test_a_sign_stands_when_a_physical_and_a_semantic_witness_agree(detectors, depth, lidar, blind, mapped, moving):
    w = _witnesses(detectors, depth, lidar, blind, mapped, moving)
    physical = depth or ((blind or moving) and (lidar or mapped))
    assert vote(w) == (physical and (any(detectors) or mapped))


def test_a_depth_caught_moving_does_not_outvote_the_map():
    assert vote(_witnesses(mapped=True, moving=True))  # the frustum attack on a mapped sign
    assert not vote(_witnesses(moving=True))  # nothing says a stop sign stands there
    assert _witnesses(moving=True).columns()["wit_moving"] == 1.0


def test_no_single_witness_decides():
    assert not vote(_witnesses(detectors=(True, True)))  # a phantom: both detectors, nothing standing free
    assert not vote(_witnesses(mapped=True))  # a removed sign: the map alone
    assert not vote(_witnesses(depth=True))  # a plate that no one says is a stop sign
    assert not vote(_witnesses(lidar=True, mapped=True))  # the LiDAR alone stands in only where the depth is blind
    assert vote(_witnesses(depth=True, mapped=True))  # a sticker that blinds both detectors on a mapped sign
    assert vote(_witnesses(blind=True, mapped=True))  # a blinded depth does not outvote the map
    assert not vote(NO_WITNESSES)


def _scene(plate_m=1.5, background_m=5.0, panel=False, width=320, height=240):
    """A depth image: a far background, and a 0.10 m plate centred on the optical axis at ``plate_m``
    at the camera's height (rows around cy), on a thin pole; or the plate on a wall panel."""
    depth = np.full((height, width), background_m, np.float32)
    u = np.arange(width) + 0.5
    v = np.arange(height) + 0.5
    x = (CAMERA.cx - u) / CAMERA.fx * plate_m  # lateral at the plate's depth, m
    y = (CAMERA.cy - v) / CAMERA.fy * plate_m  # height above the camera, m
    half = 0.24 if panel else 0.05
    rows = (np.abs(y) <= (0.15 if panel else 0.05))[:, None]
    depth[rows & (np.abs(x) <= half)[None, :]] = plate_m
    if not panel:  # the pole under the plate
        depth[(y < -0.05)[:, None] & (np.abs(x) <= 0.004)[None, :]] = plate_m + 0.004
    return depth


def _hypothesis(depth_m=1.5, bearing=0.0, tolerance=0.35, half_width=math.radians(6)):
    rows = tuple(int(round(CAMERA.cy - CAMERA.fy * dz / depth_m)) for dz in (0.05, -0.05))
    return Hypothesis(bearing, depth_m, tolerance, half_width, "map", rows)


def test_the_depth_witness_finds_a_free_plate_and_refuses_a_picture_on_a_wall():
    assert depth_witness(_scene(), CAMERA, _hypothesis()) == pytest.approx(1.5, abs=0.01)
    assert math.isnan(depth_witness(_scene(panel=True), CAMERA, _hypothesis()))


def test_the_depth_witness_finds_nothing_away_from_the_expected_range_or_outside_the_view():
    assert math.isnan(depth_witness(_scene(plate_m=2.5), CAMERA, _hypothesis(1.5)))
    assert math.isnan(depth_witness(_scene(), CAMERA, _hypothesis(bearing=math.radians(60))))


def test_a_blinded_place_is_a_hole_and_a_seen_one_is_not():
    depth = _scene()
    assert not depth_hole(depth, CAMERA, _hypothesis())
    depth[:, 140:170] = 0.0  # no return where the plate should show
    assert depth_hole(depth, CAMERA, _hypothesis()) and math.isnan(depth_witness(depth, CAMERA, _hypothesis()))


def _scan(n=360, background=4.0):
    return np.full(n, background)


def test_the_lidar_witness_needs_open_space_it_saw():
    scan = _scan()
    scan[[-1, 0, 1]] = 1.6  # a plate-sized return straight ahead (beam j at j degrees CCW)
    found = lidar_witness(scan, _hypothesis(1.5), (0.095, 0.032), (-0.012, 0.0))
    assert found == pytest.approx(1.6 * math.cos(math.atan2(-0.032, 1.6 + 0.107)) - 0.107, abs=0.05)
    dropped = scan.copy()
    dropped[[-7, -6, 6, 7]] = np.inf  # no return from beside it (0.17-0.2 m off): open space not seen
    assert math.isnan(lidar_witness(dropped, _hypothesis(1.5), (0.095, 0.032), (-0.012, 0.0)))
    wall = _scan()
    wall[-8:] = 1.6
    wall[:9] = 1.6  # a wide surface: not compact
    assert math.isnan(lidar_witness(wall, _hypothesis(1.5), (0.095, 0.032), (-0.012, 0.0)))


@given(st.floats(0.5, 3.0), st.floats(0.0, 0.2))
def test_free_standing_returns_a_range_near_the_object_or_nothing(r, offset):
    lateral = np.linspace(-0.5, 0.5, 201)
    profile = np.full(201, r + 3.0)
    profile[np.abs(lateral * r - offset) <= 0.04] = r
    found = free_standing(profile, lateral, offset / r, 0.1, r, 0.3)
    assert math.isnan(found) or abs(found - r) < 0.01
