"""The LiDAR on the lane: the first thing standing on it, and whether it is seen clear where a
carried target could be (a beam with no return proves nothing)."""

import math

import numpy as np

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


def test_the_lane_is_clear_only_when_seen_through_where_the_target_could_be():
    assert lane_clear(_scan(9.0), LANE, 1.0, 1.5, LIDAR)
    # The car is still there: not clear.
    assert not lane_clear(_car_at(_scan(9.0), 1.2), LANE, 1.0, 1.5, LIDAR)
    # Beams with no return (hiding a car leaves none): not clear.
    assert not lane_clear(np.full(N, np.inf), LANE, 1.0, 1.5, LIDAR)
    # The lane in view ends before where the target could be: nothing to see through.
    assert not lane_clear(_scan(9.0), LANE, 1.0, 3.8, LIDAR)
    assert not lane_clear(_scan(9.0), LANE, math.nan, 1.5, LIDAR)
