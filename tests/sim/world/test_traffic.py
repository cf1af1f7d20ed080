"""Cross-traffic on the road graph: the conflict points, the timing and the other cars' lane following."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from racf.sim.world.drives import targets_on_path
from racf.sim.world.road_graph import qcar2_road_graph
from racf.sim.world.stop_signs import stop_signs
from racf.sim.world.traffic import (CONFLICT_RADIUS_M, HEADWAY_S, TRAFFIC_BRAKE_MPS2, TrafficCar, conflict_of,
                                    cross_traffic)


def test_each_sign_has_a_conflict_point_past_its_line_on_another_lane():
    kinds = {s.index: conflict_of(s.index).kind for s in stop_signs()}
    # Sign 3's lane is crossed, signs 1 and 2 are joined; no lane meets sign 0's corner.
    assert kinds == {0: "adjacent", 1: "merge", 2: "merge", 3: "crossing"}
    for sign in stop_signs():
        c = conflict_of(sign.index)
        assert c.ego_s > sign.stop_s
        ego_xy = np.asarray(sign.path.pose_at(c.ego_s)[:2])
        assert np.allclose(ego_xy, c.xy, atol=0.011)
        lane_xy = np.asarray(qcar2_road_graph().paths[c.lane].pose_at(c.lane_s)[:2])
        gap = np.linalg.norm(lane_xy - ego_xy)
        assert gap < CONFLICT_RADIUS_M + 0.01 if c.kind != "adjacent" else gap > CONFLICT_RADIUS_M


@settings(max_examples=40, deadline=None)
@given(sign=st.integers(0, 3), t_ego=st.floats(0.5, 6.0), gap=st.floats(-2.0, 3.0), speed=st.floats(0.3, 2.0),
       cars=st.integers(1, 3))
def test_each_car_passes_the_conflict_point_when_its_timing_says(sign, t_ego, gap, speed, cars):
    conflict = conflict_of(sign)
    want = np.asarray(qcar2_road_graph().paths[conflict.lane].pose_at(conflict.lane_s)[:2])
    for k, car in enumerate(cross_traffic(sign, t_ego, gap_s=gap, speed_mps=speed, cars=cars)):
        t_k = max(0.0, t_ego + gap + k * HEADWAY_S)
        # Its body origin is at the lane's conflict point then.
        x, y, _, v = car.state_at(t_k)
        assert np.linalg.norm(np.array([x, y]) - want) < 0.02
        assert v == pytest.approx(speed)
        # It keeps its own right of way: no stop line faces it before the conflict.
        for target_on in targets_on_path(car.path, None, -10.0):
            assert target_on.stop_s >= car.s_at(t_k)[0] - 1e-6


def test_a_car_stops_at_its_end_and_waits_before_it_sets_off():
    car = TrafficCar((7, 14, 16), start_s=0.5, speed_mps=1.0, stop_s=3.0, depart_t_s=1.0)
    assert car.s_at(0.5) == (0.5, 0.0)
    assert car.s_at(1.5) == pytest.approx((1.0, 1.0))
    s_end, v_end = car.s_at(30.0)
    assert s_end == pytest.approx(3.0) and v_end == pytest.approx(0.0)
    # It brakes at TRAFFIC_BRAKE_MPS2, and its speed never jumps up.
    speeds = [car.s_at(t)[1] for t in np.arange(1.0, 5.0, 0.01)]
    assert min(np.diff(speeds)) >= -TRAFFIC_BRAKE_MPS2 * 0.01 - 1e-9


def test_options_round_trip_and_bad_options_name_the_problem():
    car = cross_traffic(3, 2.0)[0]
    assert TrafficCar.from_options(car.to_options()) == car
    with pytest.raises(ValueError, match="route"):
        TrafficCar.from_options({"route": "7-14", "start_s_m": 0.0, "speed_mps": 1.0})
    with pytest.raises(ValueError, match="not in the graph"):
        TrafficCar.from_options({"route": [7, 0], "start_s_m": 0.0, "speed_mps": 1.0})
    with pytest.raises(ValueError, match="colour"):
        TrafficCar.from_options({**car.to_options(), "colour": "green"})
    with pytest.raises(ValueError, match="cars"):
        cross_traffic(3, 2.0, cars=9)
    with pytest.raises(ValueError, match="sign"):
        conflict_of(4)
    assert math.isfinite(car.stop_s)
