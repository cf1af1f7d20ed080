"""The LiDAR on the lane: the first thing standing on it, and whether it is seen clear where a
carried target could be (a beam with no return proves nothing)."""

import math

import numpy as np
import pytest

from racf.experiments.car.supervisor.clear import lane_clear, lane_return

N = 720
LIDAR = (-0.1, 0.0)  # 0.1 m behind the camera
LANE = np.column_stack([np.arange(0.0, 4.0, 0.02), np.zeros(200)])


def _scan(wall_m: float = 5.0) -> np.ndarray:
    return np.full(N, wall_m)


def _car_at(scan: np.ndarray, rear_m: float) -> np.ndarray:
    """A car's rear ``rear_m`` ahead of the camera, across the beams it fills."""
    r = rear_m - LIDAR[0]
    half = math.atan2(0.096, r)
    beams = np.arange(N) * 2 * math.pi / N
    ahead = (np.abs((beams + math.pi) % (2 * math.pi) - math.pi) <= half)
    out = scan.copy()
    out[ahead] = r
    return out


def test_the_first_return_on_the_lane_is_the_car_ahead():
    # Read at the first lane point the return reaches, 0.05 m short at most: on the safe side.
    assert -0.05 <= lane_return(_car_at(_scan(), 1.7), LANE, LIDAR) - 1.7 <= 0.0
    # Nothing on the lane in its 4 m: no reading.
    assert math.isnan(lane_return(_scan(9.0), LANE, LIDAR))
    # A hidden car (its beams no return) is no reading either.
    hidden = _car_at(_scan(9.0), 1.7)
    hidden[hidden < 5] = np.inf
    assert math.isnan(lane_return(hidden, LANE, LIDAR))


def test_the_lane_behind_a_hidden_car_is_no_reading_and_a_few_beams_dropped_are_no_blindness():
    # A car at 2.5 m behind one hidden at 1.7 m (no return from its beams): the LiDAR is blind on the
    # lane at 1.7 m, so 2.5 m is not the first thing on the lane. NaN, not 2.5.
    behind = _car_at(_scan(9.0), 2.5)
    hidden = _car_at(behind, 1.7)
    hidden[np.isclose(hidden, 1.7 - LIDAR[0])] = np.inf
    assert math.isnan(lane_return(hidden, LANE, LIDAR))
    assert -0.05 <= lane_return(behind, LANE, LIDAR) - 2.5 <= 0.0  # seen, it is read
    # Two beams of every three dropped, scattered (the sensor's dropouts and its bins without a sample):
    # the LiDAR still sees the lane, the car at 1.7 m read (to the lane's 2 cm grid, 0.05 m short at most).
    noisy = _car_at(_scan(9.0), 1.7)
    noisy[np.arange(N) % 3 != 0] = np.inf
    assert -0.05 <= lane_return(noisy, LANE, LIDAR) - 1.7 <= 0.0
    # A run of no returns 0.1 m wide at 1.2 m (more than the middle half of a car's width, 0.096 m), the
    # car at 1.7 m behind it: blind at 1.2 m, no reading.
    blind = _car_at(_scan(9.0), 1.7)
    beams = np.arange(N) * 2 * math.pi / N
    blind[np.abs((beams + math.pi) % (2 * math.pi) - math.pi) <= math.atan2(0.05, 1.3)] = np.inf
    assert math.isnan(lane_return(blind, LANE, LIDAR))


def test_the_lane_is_clear_only_when_seen_through_where_the_target_could_be():
    assert lane_clear(_scan(9.0), LANE, 1.0, 1.5, LIDAR)
    # The car is still there: not clear.
    assert not lane_clear(_car_at(_scan(9.0), 1.2), LANE, 1.0, 1.5, LIDAR)
    # Beams with no return (hiding a car leaves none): not clear.
    assert not lane_clear(np.full(N, np.inf), LANE, 1.0, 1.5, LIDAR)
    # The lane in view ends before where the target could be: nothing to see through.
    assert not lane_clear(_scan(9.0), LANE, 1.0, 3.8, LIDAR)
    assert not lane_clear(_scan(9.0), LANE, math.nan, 1.5, LIDAR)


def _beams_at(scan: np.ndarray, lidar: tuple[float, float], z: float, y: float, r: float | None = None) -> np.ndarray:
    """A car's rear at (z ahead, y left) of the camera, seen from a LiDAR at ``lidar``: its beams return ``r``."""
    x, w = z - lidar[0], y - lidar[1]
    rng, bearing = math.hypot(x, w), math.atan2(w, x)
    half = math.atan2(0.096, rng)
    beams = np.arange(N) * 2 * math.pi / N
    on = np.abs((beams - bearing + math.pi) % (2 * math.pi) - math.pi) <= half
    out = scan.copy()
    out[on] = rng if r is None else r
    return out


def test_the_lidar_is_placed_where_it_is_on_the_car():
    # A LiDAR 0.2 m left of the camera sees the car ahead of the camera to its right, not straight ahead.
    side = (-0.1, 0.2)
    scan = _beams_at(_scan(9.0), side, 1.5, 0.0)
    assert -0.05 <= lane_return(scan, LANE, side) - 1.5 <= 0.0
    assert math.isnan(lane_return(scan, LANE, (-0.1, 0.0)))
    assert not lane_clear(scan, LANE, 1.2, 1.8, side) and lane_clear(_scan(9.0), LANE, 1.2, 1.8, side)


def test_a_car_on_a_lane_that_bends_is_found_at_its_bearing():
    bend = np.column_stack([np.arange(0.0, 4.0, 0.02), 0.15 * np.arange(0.0, 4.0, 0.02) ** 2])
    z = 1.2
    scan = _beams_at(_scan(9.0), LIDAR, z, 0.15 * z ** 2)
    assert -0.05 <= lane_return(scan, bend, LIDAR) - z <= 0.0


def test_what_stands_off_the_lane_or_behind_the_camera_is_no_reading():
    # The lane begins 1 m ahead; something 0.7 m away along it is no car on it.
    ahead = LANE[LANE[:, 0] >= 1.0]
    assert math.isnan(lane_return(_beams_at(_scan(9.0), LIDAR, 0.7, 0.0), ahead, LIDAR))
    # The lane behind the camera (a car following ours) is not the lane ahead.
    behind = np.column_stack([np.arange(-1.0, 4.0, 0.02), np.zeros(250)])
    scan = _scan(9.0)
    scan[N // 2 - 3: N // 2 + 4] = 0.5  # a return 0.5 m behind the LiDAR
    assert math.isnan(lane_return(scan, behind, LIDAR))
    # A beam reading 0 is no return.
    assert math.isnan(lane_return(np.zeros(N), LANE, LIDAR))


def test_nothing_to_read_is_no_reading_and_never_a_clear_lane():
    assert math.isnan(lane_return(np.empty(0), LANE, LIDAR)) and math.isnan(lane_return(_scan(), LANE[:0], LIDAR))
    assert math.isnan(lane_return(_scan(), LANE[:1], LIDAR))
    assert not lane_clear(np.empty(0), LANE, 1.0, 1.5, LIDAR) and not lane_clear(_scan(9.0), LANE[:0], 1.0, 1.5, LIDAR)
    one = np.array([[1.2, 0.0]])
    assert not lane_clear(_scan(9.0), one, 1.0, 1.5, LIDAR)  # the lane in view ends too soon


def test_clear_means_every_return_from_beyond_the_point_and_the_car_s_length_too():
    # A return just behind where the target's rear could be (0.02 m past the lane point): not seen through.
    assert not lane_clear(_beams_at(_scan(9.0), LIDAR, 1.5, 0.0, r=1.5 + 0.1 + 0.02), LANE, 1.0, 1.5, LIDAR)
    # The target may stand a car's length beyond its far end: the lane must be seen clear out to 3.425 m,
    # which a lane to 4 m allows; a far end at 3.3 m would need 3.725 m... within 4 m still.
    assert lane_clear(_scan(9.0), LANE, 2.5, 3.5, LIDAR)
    assert not lane_clear(_scan(9.0), LANE, 2.5, 3.6, LIDAR)
    # A wall 0.3 rad off the lane is no car on it.
    wall = _scan(9.0)
    wall[round(0.3 / (2 * math.pi / N))] = 0.8
    assert lane_clear(wall, LANE, 1.0, 1.5, LIDAR)


AT_CAMERA = (0.0, 0.0)  # the LiDAR at the camera: bearings by hand
STEP_DEG = 360 / N  # 0.5 degrees a beam


def _one_beam(index: int, range_m: float) -> np.ndarray:
    scan = _scan(9.0)
    scan[index % N] = range_m
    return scan


def test_a_car_fills_the_beams_of_its_width_and_no_more():
    # The nearest place the target could be is 1.0 m straight ahead: a car there (0.192 m wide) fills
    # the beams within atan(0.096 / 1.0) = 5.48 degrees of ahead. A return at 1.0 m on the beam at 4.5
    # degrees (0.079 m to the side) is within its width: not clear; one at 6.0 degrees (0.105 m to the
    # side) is beside it: clear.
    assert not lane_clear(_one_beam(round(4.5 / STEP_DEG), 1.0), LANE, 1.0, 1.0, AT_CAMERA)
    assert not lane_clear(_one_beam(-round(4.5 / STEP_DEG), 1.0), LANE, 1.0, 1.0, AT_CAMERA)
    assert lane_clear(_one_beam(round(6.0 / STEP_DEG), 1.0), LANE, 1.0, 1.0, AT_CAMERA)
    assert lane_clear(_one_beam(-round(6.0 / STEP_DEG), 1.0), LANE, 1.0, 1.0, AT_CAMERA)


def test_a_lane_seen_exactly_to_the_target_s_farthest_place_is_enough():
    # The far end at 0.575 m and a car's 0.425 m beyond it: the lane must be seen to 1.0 m, and it is.
    lane = np.column_stack([np.linspace(0.0, 1.0, 51), np.zeros(51)])
    assert lane.max() == 1.0 and lane_clear(_scan(9.0), lane, 0.5, 0.575, AT_CAMERA)
    assert not lane_clear(_scan(9.0), lane, 0.5, 0.6, AT_CAMERA)


def test_a_return_just_beyond_the_farthest_place_does_not_show_it_clear():
    # The farthest lane point the target's rear could be at is 1.42 m (the lane's points every 0.02 m,
    # up to the far end 1.0 m plus a car's length); a wall straight ahead at 1.44 m lies 0.02 m beyond
    # it, short of the 0.05 m a return must lie beyond to show the point clear.
    scan = _scan(9.0)
    scan[np.r_[0:13, N - 12:N]] = 1.44
    assert not lane_clear(scan, LANE, 1.0, 1.0, AT_CAMERA)
    scan[np.r_[0:13, N - 12:N]] = 1.48
    assert lane_clear(scan, LANE, 1.0, 1.0, AT_CAMERA)


def test_a_lane_of_one_point_is_read_and_can_be_seen_clear():
    one = np.array([[1.0, 0.0]])
    assert lane_return(_beams_at(_scan(9.0), AT_CAMERA, 1.0, 0.0), one, AT_CAMERA) == 1.0
    # Its one point at exactly the far end 0.575 m plus a car's 0.425 m: seen clear.
    assert lane_clear(_scan(9.0), one, 0.5, 0.575, AT_CAMERA)


def test_what_lies_within_5_cm_of_the_camera_or_reads_0_is_no_car_on_the_lane():
    at_5cm = np.array([[0.05, 0.0], [2.0, 0.0]])
    assert math.isnan(lane_return(_beams_at(_scan(9.0), AT_CAMERA, 0.05, 0.0), at_5cm, AT_CAMERA))
    # A beam that reads 0 (no return) at a lane point 6 cm ahead is no return from it.
    near = np.array([[0.06, 0.0]])
    assert math.isnan(lane_return(np.zeros(N), near, AT_CAMERA))


def test_a_car_to_the_left_fills_the_beams_to_the_left():
    # A return 1.0 m away at 3 degrees left of ahead: within the width of a car on the lane point 1.0 m
    # ahead (5.48 degrees each side), and of nothing 20 degrees off.
    assert not lane_clear(_one_beam(round(3.0 / STEP_DEG), 1.0), LANE, 1.0, 1.0, AT_CAMERA)
    assert lane_clear(_one_beam(round(20.0 / STEP_DEG), 1.0), LANE, 1.0, 1.0, AT_CAMERA)
    assert 0.95 <= lane_return(_one_beam(round(3.0 / STEP_DEG), 1.0), LANE, AT_CAMERA) <= 1.0  # the first point it reaches


def test_a_car_s_sector_is_rounded_out_to_whole_beams_alike_on_both_sides():
    # At 1.0 m a car spans 5.48 degrees each side; the beams at +-5.5 degrees (the 11th each way) are the
    # first whole beams past it, and a return on either one keeps the lane from being seen clear.
    for beam in (11, -11):
        assert not lane_clear(_one_beam(beam, 1.0), LANE, 1.0, 1.0, AT_CAMERA), beam
    assert lane_clear(_one_beam(12, 1.0), LANE, 1.0, 1.0, AT_CAMERA)


def test_an_axial_reading_on_a_bending_lane_is_taken_to_the_lane_point_s_straight_line():
    from racf.experiments.car.supervisor.clear import along_lane

    # A lane that runs ahead and bends left at 45 degrees: points (z, y) = (t, 0) to z = 0.4, then (0.4 + u, u).
    bend = np.array([[0.0, 0.0], [0.4, 0.0], [0.8, 0.4], [1.2, 0.8]])
    # 0.6 m along the axis lies on the second leg at y = 0.2: sqrt(0.36 + 0.04) = 0.632 m.
    assert along_lane(0.6, bend) == pytest.approx(math.sqrt(0.4))
    # Before the bend the axis and the straight line are one.
    assert along_lane(0.3, bend) == pytest.approx(0.3)
    # Beyond the lane in view, or with no lane: the reading itself, never less.
    assert along_lane(1.5, bend) == 1.5 and along_lane(0.6, None) == 0.6 and along_lane(0.6, bend[:1]) == 0.6
    assert math.isnan(along_lane(math.nan, bend))


def test_a_bending_lane_is_judged_clear_by_its_points_straight_line_distances():
    # The lane bends away: at z 0.6 a point lies 0.8 to the left, 1.0 m away in a straight line.
    bend = np.array([[z, 0.0] for z in np.arange(0.0, 0.6, 0.02)] + [[0.6, 0.8], [0.6, 1.0], [0.6, 2.0],
                                                                        [0.6, 3.0]])
    clear = _scan(5.0)
    # Where the target can be (1.0 - 1.2 m, straight line): the points at 1.0 m and beyond, on the bend.
    assert lane_clear(clear, bend, 1.0, 1.2, LIDAR)
    # Something 1.05 m away on the bend (beam at atan2(0.8, 0.7)): not clear. Taken by z (0.6) alone,
    # no point would lie in 1.0 - 1.2 m and the lane's z ends at 0.6: never judged at all.
    beam = int(round(math.atan2(0.8, 0.7) / (2 * math.pi / N)))
    blocked = clear.copy()
    blocked[beam - 2:beam + 3] = math.hypot(0.7, 0.8)
    assert not lane_clear(blocked, bend, 1.0, 1.2, LIDAR)


def test_along_the_lane_by_hand_on_lanes_of_every_shape():
    from racf.experiments.car.supervisor.clear import along_lane

    # Two points: the lane's one segment, (0, 0) to (1, 1): 0.5 m along the axis lies at y 0.5.
    assert along_lane(0.5, np.array([[0.0, 0.0], [1.0, 1.0]])) == pytest.approx(math.hypot(0.5, 0.5))
    # Irregular points: 0.7 m lies halfway from (0.5, 0.1) to (0.9, 0.5), at y 0.3.
    irregular = np.array([[0.0, 0.0], [0.5, 0.1], [0.9, 0.5], [1.0, 1.0]])
    assert along_lane(0.7, irregular) == pytest.approx(math.hypot(0.7, 0.3))
    # Exactly at the lane's first and last points.
    assert along_lane(0.0, irregular) == 0.0 and along_lane(1.0, irregular) == pytest.approx(math.hypot(1.0, 1.0))
    start_aside = np.array([[0.3, 0.4], [1.0, 0.4]])
    assert along_lane(0.3, start_aside) == pytest.approx(0.5)
    # A segment across the axis (z stands still): the point where it begins, not where it ends.
    across = np.array([[0.5, 0.0], [0.5, 0.6], [1.0, 0.6]])
    assert along_lane(0.5, across) == pytest.approx(0.5)
    # A lane that turns back and out again (a chicane seen from its start): 0.7 m ahead is met first at y 0,
    # then again at y 0.6 on the second way out: the lane's first pass is the car's.
    chicane = np.array([[0.0, 0.0], [1.0, 0.0], [0.5, 0.5], [1.5, 1.0]])
    assert along_lane(0.7, chicane) == pytest.approx(0.7)
    # A lane that begins beyond the reading (it doubles back first): met on its way out again, at y 0.45.
    back_first = np.array([[1.0, 0.0], [0.2, 0.3], [1.2, 0.8]])
    assert along_lane(0.5, back_first) == pytest.approx(math.hypot(0.5, 0.45))
