"""The supervisor of a static target (the stop sign): vouched by two of the car's own witnesses, carried
down by the car's travel, a stop rule that holds the car short of the line, a served or defended
distance outvoted, and let go once the car has stood."""

import math

import numpy as np
import pytest

from racf.experiments.car.stage import CarView, StageContext, TargetTrack
from racf.experiments.car.supervisor.envelope import Envelope, safe_speed
from racf.experiments.car.supervisor.static import CONFIRM_FRAMES, StaticSupervisor, static_supervisor

NAN = math.nan
DT = 0.02
#: delta 0.1 m: round numbers to work by hand.
ENV = Envelope(witness_error_m=0.05, attack_error_m=0.05)


def _stage(kind: str = "sign") -> StaticSupervisor:
    context = StageContext(None, (0.1, 0.0), 0.17, (0.0, 0.0), 0.1, lambda: None)
    stage = static_supervisor(kind)(context, envelope=ENV)
    stage.reset()
    return stage


def _step(stage, speed, distance=NAN, depth=NAN, lidar=NAN, size=NAN, map_m=NAN, stop_at=0.5, index=0,
          detected=False, kind="sign"):
    track = TargetTrack(kind, distance, math.inf, depth_m=depth, lidar_m=lidar, size_m=size, map_m=map_m,
                        stop_at_m=stop_at, detected=detected, index=index)
    return stage.step(CarView({}, np.zeros(3), None, 0.0, speed, 0.0, 0.0, DT, True, False, tracks={kind: track}))


def test_two_witnesses_that_agree_for_three_frames_vouch_for_the_sign_at_the_nearer():
    stage = _stage()
    said = [_step(stage, 0.5, 3.0, depth=2.0, map_m=2.05) for _ in range(CONFIRM_FRAMES)]
    assert [s.values["sup_sign_vouched"] for s in said] == [False, False, True] and CONFIRM_FRAMES == 3
    # The near end: 2.0 less delta; the far end: 2.0 plus delta.
    assert stage.near_m == pytest.approx(1.9) and stage.far_m == pytest.approx(2.1)


def test_one_witness_alone_vouches_for_nothing_and_limits_nothing():
    stage = _stage()
    for _ in range(10):
        said = _step(stage, 1.0, 0.6, depth=0.6, stop_at=0.5)
    assert not said.values["sup_sign_vouched"] and said.speed_cap_mps == math.inf and not stage.held


def test_the_stop_rule_holds_the_car_short_of_the_line_whatever_the_defence_says():
    stage = _stage()
    for _ in range(3):  # vouched at 1.5 m (depth and the LiDAR on the post agree); the line at 0.5 m
        _step(stage, 0.5, 1.5, depth=1.5, lidar=1.48)
    # Room to the line: 1.48 - 0.1 - 0.5 = 0.88 m, less the travel at the bound (0.51 m/s for 0.02 s).
    room = stage.near_m - 0.5
    fast = safe_speed(room, 0.0, ENV) + 0.1
    said = _step(stage, fast, 4.0)  # a served lie: 4 m; the car far too fast for the room left
    assert said.values["sup_sign_stop"] and said.speed_cap_mps == 0.0
    assert said.values["sup_sign_outvoted"]  # the defended 4 m lies beyond what the vouched place allows


def test_the_near_end_comes_down_by_the_car_s_travel_at_the_bound_on_its_speed():
    stage = _stage()
    for _ in range(3):
        _step(stage, 1.0, 1.5, depth=1.5, lidar=1.5)
    near = stage.near_m
    _step(stage, 1.0)  # no witness this step: carried
    assert stage.near_m == pytest.approx(near - 1.02 * DT)  # the encoder's 1 m/s with its 2 % error


def test_once_the_car_has_stood_before_the_line_the_sign_lets_it_go_and_the_next_is_new():
    stage = _stage()
    for _ in range(3):
        _step(stage, 0.2, 0.8, depth=0.8, lidar=0.8)
    speed = 0.2
    for _ in range(10):  # the braker brings the car to rest before the line
        speed = max(speed - 2.0 * DT, 0.0)
        said = _step(stage, speed)
    assert stage.done and said.speed_cap_mps == math.inf and not said.values["sup_sign_carried"]
    said = _step(stage, 0.5, 2.0, index=1)  # the car's next target: nothing carried yet
    assert not stage.done and not stage.held and said.speed_cap_mps == math.inf


def test_a_sign_the_map_does_not_list_needs_two_range_witnesses_until_one_was_detected():
    stage = _stage()
    for _ in range(5):  # the depth and the size agree on a picture of a sign: not enough, unlisted
        said = _step(stage, 0.5, 1.0, depth=1.0, size=1.02)
    assert not said.values["sup_sign_vouched"]
    for _ in range(3):  # the LiDAR on its post agrees too: two range witnesses
        said = _step(stage, 0.5, 1.0, depth=1.0, lidar=1.01, size=1.02)
    assert said.values["sup_sign_vouched"]


def test_each_kind_has_its_own_columns_and_nothing_published_limits_nothing():
    person = static_supervisor("person")
    assert person.supervises == "person" and all(c.name.startswith("sup_person_") for c in person.columns)
    assert static_supervisor("person") is person  # one class a kind
    stage = _stage()
    said = stage.step(CarView({}, np.zeros(3), None, 0.0, 1.0, 0.0, 0.0, DT, True, False))
    assert said.speed_cap_mps == math.inf and set(said.values) == {c.name for c in StaticSupervisor.columns}


def test_where_the_map_lists_the_sign_the_room_is_the_car_s_distance_along_its_route_to_the_line():
    stage = _stage()
    for _ in range(3):  # vouched at 1.5 m; in a bend its camera distance says little of the road left
        _step(stage, 0.5, 1.5, depth=1.5, lidar=1.5)
    track = TargetTrack("sign", 1.5, math.inf, depth_m=1.5, lidar_m=1.5, stop_at_m=0.5, line_m=0.3)
    view = CarView({}, np.zeros(3), None, 0.0, 1.0, 0.0, 0.0, DT, True, False, tracks={"sign": track})
    # 0.3 m of road to the line: 1 m/s (1.02 with the encoder's error) is faster than safe_speed(0.3) allows.
    assert safe_speed(0.3, 0.0, ENV) < 1.02
    assert stage.step(view).values["sup_sign_stop"]
    slow = CarView({}, np.zeros(3), None, 0.0, 0.05, 0.0, 0.0, DT, True, False,
                   tracks={"sign": TargetTrack("sign", 1.5, math.inf, stop_at_m=0.5, line_m=3.0)})
    assert not _stage().step(slow).values["sup_sign_stop"]



def test_what_it_says_when_it_holds_nothing_is_false_nan_and_no_limit():
    stage = _stage()
    quiet = {"sup_sign_vouched": False, "sup_sign_carried": False, "sup_sign_outvoted": False,
             "sup_sign_stop": False, "sup_sign_cap": math.inf}
    for said in (stage.idle(), stage.step(CarView({}, np.zeros(3), None, 0.0, 1.0, 0.0, 0.0, DT, True, False)),
                 _step(stage, 1.0, 0.9, depth=0.9)):
        assert {k: v for k, v in said.values.items() if k != "sup_sign_near"} == quiet
        assert math.isnan(said.values["sup_sign_near"]) and said.speed_cap_mps == math.inf


def test_a_defended_distance_that_agrees_is_not_outvoted_and_none_with_a_vouch_is():
    stage = _stage()
    for _ in range(3):
        said = _step(stage, 0.5, 1.5, depth=1.5, lidar=1.5)
    assert said.values["sup_sign_vouched"] and not said.values["sup_sign_outvoted"]
    assert _step(stage, 0.5, NAN, depth=1.49, lidar=1.49).values["sup_sign_outvoted"]  # "no target": outvoted
    assert not _step(stage, 0.5, NAN).values["sup_sign_outvoted"]  # nothing to outvote it with


def test_a_witness_that_is_no_range_vouches_for_nothing():
    stage = _stage()
    for _ in range(5):
        said = _step(stage, 0.5, 1.0, depth=-1.0, lidar=-1.0, map_m=-1.0)
    assert not said.values["sup_sign_vouched"] and not stage.held


def test_agreement_must_run_unbroken_for_three_frames():
    stage = _stage()
    said = [_step(stage, 0.5, 1.5, depth=d, lidar=1.5).values["sup_sign_vouched"] for d in (1.5, 3.0, 1.5, 1.5)]
    assert said == [False, False, False, False]  # 1, broken, 1, 2 frames running
    assert _step(stage, 0.5, 1.5, depth=1.5, lidar=1.5).values["sup_sign_vouched"]


def test_an_unlisted_sign_once_detected_is_vouched_by_the_depth_and_its_size():
    stage = _stage()
    _step(stage, 0.5, 1.0, depth=1.0, detected=True)  # detected, one witness
    said = [_step(stage, 0.5, 1.0, depth=1.0, size=1.02).values["sup_sign_vouched"] for _ in range(3)]
    assert said == [False, False, True]
    stage.reset()  # forgotten: an unlisted sign first seen again needs two range witnesses
    assert not any(_step(stage, 0.5, 1.0, depth=1.0, size=1.02).values["sup_sign_vouched"] for _ in range(4))


def test_the_stop_rule_s_edge_by_hand_on_the_route_distance():
    room = 0.4
    # The fastest the car may go with 0.4 m of road to the line, less what its route distance may be off (A6).
    edge = safe_speed(room - ENV.route_error_m, 0.0, ENV)
    for speed, stops in ((edge / 1.02 + 0.005, True), (edge / 1.02 - 0.005, False)):
        stage = _stage()
        for _ in range(3):
            _step(stage, speed, 1.5, depth=1.5, lidar=1.5, stop_at=0.5)
        track = TargetTrack("sign", 1.5, math.inf, depth_m=1.5, lidar_m=1.5, stop_at_m=0.5, line_m=room)
        view = CarView({}, np.zeros(3), None, 0.0, speed, 0.0, 0.0, DT, True, False, tracks={"sign": track})
        assert stage.step(view).values["sup_sign_stop"] is stops


def test_a_carried_sign_shows_its_near_end_and_only_adds_a_limit():
    assert StaticSupervisor.stands_in is False and static_supervisor("sign").stands_in is False
    stage = _stage()
    for _ in range(3):
        said = _step(stage, 0.5, 1.5, depth=1.5, lidar=1.5)
    assert said.values["sup_sign_carried"] and said.values["sup_sign_near"] == pytest.approx(1.4)
    # A later reading where the carried sign is narrows the far end: at most the reading plus delta.
    _step(stage, 0.0, 1.45, depth=1.45, lidar=1.45)
    assert stage.far_m == pytest.approx(1.55)


def test_a_witness_that_reads_zero_is_no_return_and_agrees_with_nothing():
    # The depth's 0 is "no return": beside the LiDAR's 0.05 m (within the 0.15 m agreement of a 0 m
    # reading) it would vouch a sign at the camera and stop the car where the map puts it 2 m away.
    stage = _stage()
    for _ in range(2 * CONFIRM_FRAMES):
        said = _step(stage, 1.0, 2.0, depth=0.0, lidar=0.05, map_m=2.0)
    assert not said.values["sup_sign_vouched"] and not stage.held and said.speed_cap_mps == math.inf


def test_at_exactly_the_speed_that_stops_it_at_the_line_the_car_is_not_told_to_stop():
    # No reaction time, no acceleration, no margin, b = 4 m/s^2, an exact encoder: from 2 m/s the car
    # stops in 2^2 / (2 x 4) = 0.5 m, the room it has to the mapped line. At that speed it may go on;
    # the stop rule fires only when the car is faster than that.
    for route_error, edge in ((0.0, 2.0), (0.1, math.sqrt(2 * 4.0 * 0.4))):
        # An exact localisation: 0.5 m of room. Off by up to 0.1 m (A6): 0.4 m, from 1.789 m/s.
        env = Envelope(reaction_s=0.0, car_accel_mps2=0.0, margin_m=0.0, car_brake_mps2=4.0, odometry_error=0.0,
                       route_error_m=route_error)
        context = StageContext(None, (0.1, 0.0), 0.17, (0.0, 0.0), 0.1, lambda: None)
        stage = static_supervisor("sign")(context, envelope=env)
        stage.reset()

        def step(speed, stage=stage):
            track = TargetTrack("sign", 1.0, math.inf, depth_m=1.0, lidar_m=1.0, map_m=1.0, stop_at_m=0.5, line_m=0.5)
            return stage.step(CarView({}, np.zeros(3), None, 0.0, speed, 0.0, 0.0, DT, True, False,
                                      tracks={"sign": track}))

        said = [step(edge) for _ in range(CONFIRM_FRAMES)][-1]
        assert said.values["sup_sign_vouched"] and not said.values["sup_sign_stop"] and said.speed_cap_mps == math.inf
        said = step(edge + 0.001)
        assert said.values["sup_sign_stop"] and said.speed_cap_mps == 0.0


def test_a_carried_sign_is_vouched_again_by_one_range_witness_where_it_stands_and_the_near_end_never_jumps_on():
    stage = _stage()
    for _ in range(3):
        _step(stage, 0.5, 2.0, depth=2.0, map_m=2.05)  # vouched at 2.0: near 1.9
    # One step on at 0.5 m/s (the bound 0.51 m/s): the near end 1.9 - 0.0102. The depth alone reads 1.80 m,
    # 0.09 m short of it (within the 0.15 m agreement): the same sign, vouched; the near end the nearer of
    # the carried one and the reading's (1.80 - 0.1 = 1.70).
    said = _step(stage, 0.5, 2.0, depth=1.80)
    assert said.values["sup_sign_vouched"] and stage.near_m == pytest.approx(1.9 - 0.51 * DT)
    # A depth alone 0.5 m off the carried place is no witness of it (and one witness confirms nothing new).
    assert not _step(stage, 0.5, 2.0, depth=1.2).values["sup_sign_vouched"]


def test_a_zero_reading_vouches_nothing_even_where_the_carried_sign_is_within_a_hand_of_the_camera():
    stage = _stage()
    for _ in range(3):
        _step(stage, 0.5, 0.2, depth=0.2, lidar=0.2, map_m=0.2)  # near 0.1 m
    assert not _step(stage, 0.5, 0.2, depth=0.0).values["sup_sign_vouched"]


def test_the_step_the_car_stood_outvotes_nothing():
    stage = _stage()
    for _ in range(3):
        _step(stage, 0.2, 0.8, depth=0.8, lidar=0.8)
    for _ in range(5):  # at rest before the line (the bound falls at the grip); the defence says 4 m
        said = _step(stage, 0.0, 4.0)
        if stage.done:
            break
    assert stage.done and not said.values["sup_sign_outvoted"] and not said.values["sup_sign_stop"]


def _line_step(stage, speed, line_m, **witnesses):
    track = TargetTrack("sign", 1.0, math.inf, stop_at_m=0.5, line_m=line_m, **witnesses)
    return stage.step(CarView({}, np.zeros(3), None, 0.0, speed, 0.0, 0.0, DT, True, False, tracks={"sign": track}))


def test_the_car_stood_with_its_bumper_on_the_line_and_its_near_end_is_no_longer_shown():
    stage = _stage()
    for _ in range(3):
        _line_step(stage, 0.2, 0.3, depth_m=1.0, lidar_m=1.0, map_m=1.0)
    for _ in range(10):  # at rest, the route's 0 m to the line: stood (within the 0.05 m margin)
        said = _line_step(stage, 0.0, 0.0)
        if stage.done:
            break
    assert stage.done and math.isnan(said.values["sup_sign_near"]) and not said.values["sup_sign_carried"]


def test_a_single_range_witness_just_past_the_carried_far_end_is_the_same_sign():
    stage = _stage()
    for _ in range(3):
        _step(stage, 0.0, 2.0, depth=2.0, map_m=2.05)  # near 1.9, far 2.1 (at rest: they stay)
    # The depth alone at 2.2 m: 0.1 m past the far end, within its 0.33 m agreement: vouched.
    assert _step(stage, 0.0, 2.0, depth=2.2).values["sup_sign_vouched"]


def _bend_view(speed: float, track: TargetTrack, progress: float = 0.0) -> CarView:
    """A route that runs 1 m east from the origin, then turns north (a right angle); the car's body
    origin at (progress, 0) heading east (its arclength measured from there)."""
    from racf.sim.world.road_graph import Path

    east = np.column_stack([np.arange(0.0, 1.0, 0.01), np.zeros(100)])
    north = np.column_stack([np.ones(300), np.arange(0.0, 3.0, 0.01)])
    points = np.vstack([east, north])
    headings = np.where(np.arange(len(points)) < 100, 0.0, math.pi / 2)
    path = Path(points, headings, np.zeros(len(points)))
    return CarView({}, np.array([progress, 0.0, 0.0]), path, progress, speed, 0.0, 0.0, DT, True, False,
                   tracks={"sign": track})


def test_an_unlisted_sign_is_placed_on_the_route_by_the_car_itself_not_along_the_camera_s_axis():
    stage = _stage()
    # The sign stands 1 m past the bend, beside the road: at (1.2, 1.0). From the camera at (0.1, 0) it
    # lies at bearing atan2(1.0, 1.1) = 42.3 degrees, 1.1 m along the camera's axis (the depth). The
    # map lists no line: the line is where the sign projects on the route (stop_at 0.1 = the bumper's
    # lead on the camera, 0 past the line), arclength 1.0 + 1.0 = 2.0 m. Depth and LiDAR agree on it.
    bearing = math.atan2(1.0, 1.1)
    for _ in range(3):  # vouched while moving at 0.3 m/s (a car at rest before the line has made its stop)
        said = stage.step(_bend_view(0.3, TargetTrack("sign", 1.1, math.inf, depth_m=1.1, lidar_m=1.1, stop_at_m=0.1,
                                                      detected=True, bearing_rad=bearing)))
    assert said.values["sup_sign_vouched"] and said.values["sup_sign_carried"]
    # Placed from 1.1 - 0.1 (delta) = 1.0 m along the axis at that bearing: (0.1 + 1.0, 1.0 x tan(42.3 deg)) =
    # (1.1, 0.909), on the route at 1.0 + 0.909 = 1.909 m (to the path's 1 cm grid). The bumper at (0.2, 0):
    # 0.2 m. Room 1.709 m, where the camera's axis would say 1.0 - 0.1 = 0.9 m.
    assert stage.line_s == pytest.approx(1.909, abs=0.011)
    fast = safe_speed(0.9, 0.0, ENV) + 0.05  # too fast for 0.9 m of room, slow enough for 1.7 m
    assert fast * 1.02 < safe_speed(1.70, 0.0, ENV)  # (the bound on its speed: the encoder's, +2 %)
    said = stage.step(_bend_view(fast, TargetTrack("sign", 1.1, math.inf, depth_m=1.1, lidar_m=1.1, stop_at_m=0.1,
                                                   detected=True, bearing_rad=bearing)))
    assert not said.values["sup_sign_stop"]
    # Without a bearing, the camera's axis: the same speed is told to stop.
    other = _stage()
    for _ in range(3):
        other.step(_bend_view(0.3, TargetTrack("sign", 1.1, math.inf, depth_m=1.1, lidar_m=1.1, stop_at_m=0.1,
                                               detected=True)))
    said = other.step(_bend_view(fast, TargetTrack("sign", 1.1, math.inf, depth_m=1.1, lidar_m=1.1, stop_at_m=0.1,
                                                   detected=True)))
    assert said.values["sup_sign_stop"] and math.isnan(other.line_s)
