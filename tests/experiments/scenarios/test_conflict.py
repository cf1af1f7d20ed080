"""Conflict scoring from a step log: collisions, TTC, PET and the outcome."""

import math

import numpy as np
import pandas as pd
import pytest

from racf.experiments.scenarios.cross_traffic.conflict import NEAR_MISS_S, score_conflict
from racf.sim.world.traffic import MAX_TRAFFIC_CARS

DT = 0.02


def _log(ego_x, ego_y, ego_yaw, ego_v, cars=(), conflict=(0.0, 0.0), touched=None) -> pd.DataFrame:
    """A log over ``len(ego_x)`` steps; each car is (x, y, yaw, speed) arrays."""
    n = len(ego_x)
    cols = {"t": np.arange(n) * DT, "x": ego_x, "y": ego_y, "yaw": np.full(n, ego_yaw), "speed": np.full(n, ego_v),
            "collision_with": touched if touched is not None else [""] * n,
            "conflict_x": np.full(n, conflict[0] if cars else np.nan),
            "conflict_y": np.full(n, conflict[1] if cars else np.nan)}
    for k in range(MAX_TRAFFIC_CARS):
        car = cars[k] if k < len(cars) else None
        for i, field in enumerate(("x", "y", "yaw", "speed")):
            cols[f"traffic{k}_{field}"] = np.full(n, np.nan) if car is None else np.broadcast_to(car[i], (n,))
    return pd.DataFrame(cols)


def _crossing(ego_stops_at: float | None, car_delay_s: float, n: int = 300):
    """The ego car drives east along y = 0 at 1 m/s towards the conflict point (0, 0) from x = -2 (stopping
    at ``ego_stops_at`` when given); another car drives north along x = 0 and reaches it ``car_delay_s`` after
    the ego car would."""
    t = np.arange(n) * DT
    ego_x = -2.0 + t
    if ego_stops_at is not None:
        ego_x = np.minimum(ego_x, ego_stops_at)
    car_y = -(2.0 + car_delay_s) + t
    return ego_x, (np.zeros(n), car_y, np.full(n, math.pi / 2), np.ones(n))


def test_without_traffic_there_is_no_conflict_but_a_crash_still_counts():
    out = score_conflict(_log(np.linspace(0, 1, 50), np.zeros(50), 0.0, 1.0))
    assert out.conflict is None and not out.collision and math.isnan(out.min_ttc_s)
    touched = [""] * 49 + ["wall_north"]
    out = score_conflict(_log(np.linspace(0, 1, 50), np.zeros(50), 0.0, 1.0, touched=touched))
    assert out.collision and out.collision_with == "wall_north" and out.conflict is None


def test_a_car_that_stops_short_of_the_conflict_zone_yielded():
    ego_x, car = _crossing(ego_stops_at=-0.6, car_delay_s=0.0)
    out = score_conflict(_log(ego_x, np.zeros_like(ego_x), 0.0, 1.0, cars=[car]))
    assert out.conflict == "yielded" and math.isnan(out.pet_s) and not out.collision


def test_passing_together_is_a_near_miss_and_apart_is_a_pass():
    ego_x, car = _crossing(None, car_delay_s=0.1)
    near = score_conflict(_log(ego_x, np.zeros_like(ego_x), 0.0, 1.0, cars=[car]))
    assert near.conflict == "near_miss" and near.min_ttc_s < NEAR_MISS_S
    ego_x, car = _crossing(None, car_delay_s=2.5)
    far = score_conflict(_log(ego_x, np.zeros_like(ego_x), 0.0, 1.0, cars=[car]))
    assert far.conflict == "passed" and far.pet_s > NEAR_MISS_S
    # The post-encroachment time is the gap between the ego car leaving the zone and the other entering it:
    # each occupies it while within 0.15 m of its 0.425 x 0.192 m footprint.
    leave_ego = (0.15 + 0.2125) + 2.0  # s
    enter_car = 2.0 + 2.5 - (0.15 + 0.2125)
    assert far.pet_s == pytest.approx(enter_car - leave_ego, abs=2 * DT)


def test_a_contact_with_another_car_is_a_collision_with_ttc_zero():
    ego_x, car = _crossing(None, car_delay_s=0.0, n=110)
    touched = [""] * 109 + ["traffic0"]
    out = score_conflict(_log(ego_x, np.zeros_like(ego_x), 0.0, 1.0, cars=[car], touched=touched))
    assert out.conflict == "collision" and out.collision_with == "traffic0" and out.min_ttc_s == 0.0


def test_time_to_collision_of_two_cars_head_on():
    # 2 m apart bumper-free centres, closing at 2 m/s: the footprints meet after (2 - 0.425) / 2 s.
    n = 5
    log = _log(np.zeros(n), np.zeros(n), 0.0, 1.0, cars=[(np.full(n, 2.0), np.zeros(n), np.full(n, math.pi), np.ones(n))],
               conflict=(1.0, 0.0))
    assert score_conflict(log).min_ttc_s == pytest.approx((2.0 - 0.425) / 2.0, abs=0.021)
