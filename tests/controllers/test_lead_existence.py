"""The car ahead's existence check: a car's box stands on something upright at its size's distance;
a picture's does not, and is caught by what stands on the lane staying put or by the LiDAR."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from racf.controllers.detector import Detection
from racf.controllers.distance import CameraModel
from racf.controllers.lead_existence import LeadExistenceCheck, LeadExistenceConfig, box_points, in_lane
from racf.controllers.vehicle_detector import VEHICLE_BOX_HEIGHT_M

CAMERA = CameraModel(width=320, fx=230.0, cx=160.0, fy=230.0, cy=120.0)
HEIGHT_M = 0.172
LANE = np.column_stack([np.linspace(0.1, 4.0, 80), np.zeros(80)])
FRAME_S = 1 / 30


def scene(*cars: float, wall_m: float = 4.0, bias_m: float = 0.0) -> np.ndarray:
    """A depth image of the floor, a wall ``wall_m`` ahead and a car's rear at each distance in
    ``cars`` on the lane's centre; ``bias_m`` reads the cars' depth that much far (a patch)."""
    rows = np.arange(240, dtype=float)[:, None] + 0.5
    with np.errstate(divide="ignore"):
        floor = np.where(rows > CAMERA.cy, CAMERA.fy * HEIGHT_M / (rows - CAMERA.cy), np.inf)
    depth = np.minimum(np.broadcast_to(floor, (240, 320)), wall_m).astype(np.float32)
    for z in sorted(cars, reverse=True):
        x0, y0, x1, y1 = box_at(z).box
        depth[y0:y1, x0:x1] = z + bias_m
    return depth


def box_at(z: float, u_centre: float = 160.0) -> Detection:
    """A car's box at depth ``z``: its height a QCar 2's, its wheels on the floor."""
    h = int(round(CAMERA.fy * VEHICLE_BOX_HEIGHT_M / z))
    w = int(round(CAMERA.fx * 0.19 / z))
    x0, y1 = int(u_centre - w / 2), int(round(CAMERA.cy + CAMERA.fy * HEIGHT_M / z))
    y1 = min(y1, 240)
    mask = np.zeros((240, 320), bool)
    mask[max(y1 - h, 0):y1, x0:x0 + w] = True
    return Detection(mask, (x0, max(y1 - h, 0), x0 + w, y1), 0.9, int(mask.sum()), (u_centre, y1 - h / 2))


def check() -> LeadExistenceCheck:
    return LeadExistenceCheck(CAMERA, HEIGHT_M)


def test_a_car_s_box_is_held_up_by_its_rear_at_its_size_s_distance():
    evidence = check().update(scene(1.2), box_at(1.2), 1.2, LANE, 0.0)
    assert evidence.support > 0.6 and evidence.nearest_m == pytest.approx(1.2, abs=0.01)
    assert not evidence.picture and not evidence.caught


def test_a_picture_seen_from_nowhere_is_not_held_up_but_not_caught_without_a_second_witness():
    # A car's picture 0.5 m ahead over the real car at 1.6 m: nothing upright stands at 0.5 m.
    evidence = check().update(scene(1.6), box_at(0.5), 0.5, LANE, 0.0)
    assert evidence.support == 0.0 and evidence.nearest_m == pytest.approx(1.6, abs=0.01)
    assert not evidence.caught and not evidence.picture  # a depth read far would look the same


def test_a_picture_over_a_car_from_the_first_sight_is_not_caught():
    # Nothing tells it from a depth read far at a first sight (the LiDAR's track follows the depth).
    evidence = check().update(scene(1.6), box_at(0.5), 0.5, LANE, 0.0)
    assert not evidence.caught and not evidence.picture


def test_a_picture_over_the_bare_floor_is_caught_at_once():
    # The real car stands off the lane (on a bend): in the picture's box the depth sees only the floor.
    evidence = check().update(scene(wall_m=6.0), box_at(0.5), 0.5, LANE, 0.0)  # the wall beyond the lane
    assert math.isnan(evidence.nearest_m) and evidence.caught and evidence.picture


def test_a_box_that_leaves_what_stands_on_the_lane_is_a_picture():
    c = check()
    assert not c.update(scene(1.6), box_at(1.6), 1.6, LANE, 0.0).caught
    evidence = c.update(scene(1.6), box_at(0.5), 0.5, LANE, FRAME_S)
    assert evidence.caught and evidence.picture


def test_a_depth_read_far_moves_what_stands_away_from_the_box_and_is_no_picture():
    # The patch on the depth: the box stays, the car's depth jumps 1 m; the LiDAR agrees with the box.
    c = check()
    c.update(scene(1.6), box_at(1.6), 1.6, LANE, 0.0)
    evidence = c.update(scene(1.6, bias_m=1.0), box_at(1.6), 1.6, LANE, FRAME_S)
    assert evidence.support == 0.0 and not evidence.caught and not evidence.picture


def test_once_what_stood_in_the_box_moved_away_no_picture_is_caught_for_the_episode():
    # The frustum attack on both range sensors: the depth and the LiDAR 1 m far, together, the box honest.
    c = check()
    c.update(scene(1.6), box_at(1.6), 1.6, LANE, 0.0)
    moved = scene(1.6, bias_m=1.0)
    assert not c.update(moved, box_at(1.6), 1.6, LANE, FRAME_S).caught
    later = c.config.memory_s + 0.5  # the held-up box long forgotten: the LiDAR still sides with the depth
    assert not c.update(moved, box_at(1.6), 1.6, LANE, later).caught
    c.reset()
    assert not c.update(moved, box_at(1.6), 1.6, LANE, 0.0).caught


def test_a_picture_over_the_bare_floor_after_a_held_up_box_is_still_caught():
    c = check()
    c.update(scene(1.6, wall_m=6.0), box_at(1.6), 1.6, LANE, 0.0)
    assert c.update(scene(wall_m=6.0), box_at(0.5), 0.5, LANE, FRAME_S).caught


def test_a_box_a_row_taller_is_the_size_s_noise_not_a_picture():
    c = check()
    c.update(scene(0.84), box_at(0.84), 0.84, LANE, 0.0)
    # The size witness 0.1 m nearer than the frame before (a box a few rows taller), what stands unmoved.
    evidence = c.update(scene(0.84), box_at(0.74), 0.74, LANE, FRAME_S)
    assert not evidence.caught


def test_a_held_up_box_is_forgotten_after_the_memory():
    c = check()
    c.update(scene(1.6), box_at(1.6), 1.6, LANE, 0.0)
    late = c.config.memory_s + 0.1
    assert not c.update(scene(1.6), box_at(0.5), 0.5, LANE, late).caught


def test_once_caught_a_box_without_a_verdict_is_the_picture_until_a_box_is_held_up_again():
    c = check()
    c.update(scene(1.6), box_at(1.6), 1.6, LANE, 0.0)
    assert c.update(scene(1.6), box_at(0.5), 0.5, LANE, FRAME_S).picture
    assert c.update(scene(1.6), box_at(0.5), math.nan, LANE, 2 * FRAME_S).picture  # its size not measured
    assert not c.update(scene(0.3), box_at(0.5), 0.5, LANE, 2 * FRAME_S).picture  # nearer: errs safe
    assert not c.update(scene(1.6), box_at(1.6), 1.6, LANE, 3 * FRAME_S).picture  # held up: it has gone
    # The next box the depth does not hold up is no picture on its own: the depth read far makes one too.
    later = c.update(scene(1.6, bias_m=1.0), box_at(1.6), math.nan, LANE, 4 * FRAME_S)
    assert not later.picture and not later.caught
    c.reset()
    assert not c.update(scene(1.6), box_at(0.5), 0.5, LANE, 0.0).picture


def test_no_detection_and_no_lane_give_no_verdict():
    c = check()
    assert math.isnan(c.update(scene(1.6), None, 1.6, LANE, 0.0).support)
    evidence = c.update(scene(1.6), box_at(1.6), 1.6, np.empty((0, 2)), 0.0)
    assert math.isnan(evidence.support) and math.isnan(evidence.nearest_m) and not evidence.caught


def test_what_stands_beside_the_lane_is_not_the_car_ahead():
    # The box spans the lane and a post 0.4 m to its left at 0.9 m: the nearest on the lane is the car.
    depth = scene(1.6)
    post = box_at(0.9, u_centre=160.0 + 0.4 * CAMERA.fx / 0.9 * -1)
    x0, y0, x1, y1 = post.box
    depth[y0:y1, x0:x1] = 0.9
    wide = Detection(np.ones((240, 320), bool), (post.box[0], box_at(0.5).box[1], box_at(0.5).box[2],
                                                 box_at(0.5).box[3]), 0.9, 1, (160.0, 120.0))
    assert check().update(depth, wide, 0.5, LANE, 0.0).nearest_m == pytest.approx(1.6, abs=0.01)


@settings(max_examples=40, deadline=None)
@given(height=st.floats(0.1, 0.5), pitch_rows=st.floats(-6.0, 6.0), wall=st.floats(0.3, 5.0))
def test_the_floor_is_never_upright_and_a_wall_always_is(height, pitch_rows, wall):
    rows = np.arange(240, dtype=float)[:, None] + 0.5
    horizon = CAMERA.cy + pitch_rows  # a car pitching moves the horizon, not the floor's slope
    with np.errstate(divide="ignore"):
        floor = np.where(rows > horizon + 1, CAMERA.fy * height / (rows - horizon), 0.0)
    floor = np.broadcast_to(floor, (240, 320)).astype(np.float32)
    low = (100, int(horizon) + 20, 220, 238)
    _, upright = box_points(floor, low, CAMERA, height)
    assert len(upright) and not upright.any()
    points, upright = box_points(np.full((240, 320), wall, np.float32), low, CAMERA, height)
    assert upright.all() and points[:, 0] == pytest.approx(wall)


def test_in_lane_keeps_what_lies_near_the_lane_s_centre():
    points = np.array([[1.0, 0.0], [1.0, 0.1], [1.0, 0.3], [6.0, 0.0]])
    assert in_lane(points, LANE, 0.15).tolist() == [True, True, False, False]
    assert not in_lane(points, np.empty((0, 2)), 0.15).any()


@pytest.mark.parametrize("field, value", [("lane_half_width_m", -0.1), ("min_support", 1.5), ("min_pixels", 0),
                                          ("memory_s", math.nan), ("closing_mps", True)])
def test_the_settings_say_what_is_allowed(field, value):
    with pytest.raises(ValueError, match=field):
        LeadExistenceConfig(**{field: value})


def test_the_nearest_thing_on_the_lane_is_the_car_not_the_wall_behind_it():
    evidence = check().update(scene(1.6, wall_m=3.0), box_at(0.5), 0.5, LANE, 0.0)
    assert evidence.nearest_m == pytest.approx(1.6, abs=0.01)


def test_points_left_of_the_principal_point_lie_left():
    points, upright = box_points(np.full((240, 320), 2.0, np.float32), (0, 100, 320, 110), CAMERA, HEIGHT_M)
    u = np.tile(np.arange(320), 10)
    assert upright.all() and (points[u < 150, 1] > 0).all() and (points[u > 170, 1] < 0).all()


def test_in_lane_is_as_wide_as_its_half_width():
    assert in_lane(np.array([[1.0, 0.14], [1.0, 0.2]]), LANE, 0.15).tolist() == [True, False]


def upper_far(z: float) -> np.ndarray:
    """The scene with a car at ``z`` whose rows but its lowest four read 1 m far: the box not held up,
    what stands nearest still the car."""
    depth = scene(z)
    x0, y0, x1, y1 = box_at(z).box
    depth[y0:y1 - 4, x0:x1] += 1.0
    return depth


def test_a_box_not_held_up_over_a_car_seen_first_is_no_picture():
    evidence = check().update(upper_far(1.6), box_at(1.6), 1.6, LANE, 0.0)
    assert evidence.support < 0.15 and not evidence.caught


def test_a_box_that_stays_while_most_of_what_stood_in_it_reads_far_is_no_picture():
    # Most of the car's rows read 1 m far (a patch on its upper part); its lowest rows and its box stay.
    c = check()
    c.update(scene(1.6), box_at(1.6), 1.6, LANE, 0.0)
    evidence = c.update(upper_far(1.6), box_at(1.6), 1.6, LANE, FRAME_S)
    assert evidence.support < 0.15 and evidence.nearest_m == pytest.approx(1.6, abs=0.01) and not evidence.caught


def test_only_a_box_the_depth_held_up_is_remembered():
    c = check()
    c.update(scene(1.6), box_at(1.6), 1.6, LANE, 0.0)
    c.update(upper_far(1.6), box_at(1.6), 1.6, LANE, c.config.memory_s - 0.1)  # not held up: not remembered
    assert not c.update(scene(1.6), box_at(0.5), 0.5, LANE, c.config.memory_s + 0.05).caught


def test_a_far_box_held_up_long_ago_is_forgotten_even_where_a_car_could_have_come_that_far():
    c = check()
    c.update(scene(4.0, wall_m=6.0), box_at(4.0), 4.0, LANE, 0.0)
    late = c.config.memory_s + 0.05
    assert not c.update(scene(4.0, wall_m=6.0), box_at(0.3), 0.3, LANE, late).caught


def test_a_box_that_jumped_where_nothing_it_held_stayed_does_not_block_a_later_catch():
    # The car ahead gone from the depth (hidden), a picture over the wall behind: neither stayed.
    c = check()
    c.update(scene(1.6, wall_m=3.0), box_at(1.6), 1.6, LANE, 0.0)
    assert not c.update(scene(wall_m=3.0), box_at(0.5), 0.5, LANE, FRAME_S).caught
    assert c.update(scene(wall_m=6.0), box_at(0.5), 0.5, LANE, 2 * FRAME_S).caught  # then over the bare floor


def test_after_the_depth_moved_away_from_a_box_even_a_bare_floor_is_no_picture():
    # The patch on the depth, then the depth of the car's place wiped to the floor behind it: the range
    # sensors were caught lying first, so the box is believed.
    c = check()
    c.update(scene(1.6, wall_m=6.0), box_at(1.6), 1.6, LANE, 0.0)
    assert not c.update(scene(1.6, wall_m=6.0, bias_m=1.0), box_at(1.6), 1.6, LANE, FRAME_S).caught
    assert not c.update(scene(wall_m=6.0), box_at(1.6), 1.6, LANE, 2 * FRAME_S).caught


def test_a_size_that_moved_a_little_more_than_what_stands_is_not_a_jump():
    c = check()
    c.update(scene(0.34), box_at(0.34), 0.34, LANE, 0.0)
    evidence = c.update(scene(0.34), box_at(0.34), 0.22, LANE, FRAME_S)  # 0.12 m nearer: under the margin
    assert evidence.support == 0.0 and not evidence.caught
