"""The car's radio receiver trusts nothing it is sent: forged, replayed and stale messages are refused
and counted; a fresh trusted one tells where the car ahead is on the lane, moved on to now."""

from __future__ import annotations

import math

import numpy as np
import pytest
from nacl.signing import SigningKey

from racf.experiments.car.broadcast import MAX_AGE_S, BroadcastReceiver
from racf.sim.radio import RADIO_SLOTS, SIGNED_BYTES, Broadcast, V2VMessage, sign
from racf.sim.world.manager import QCAR2_BOX_M
from racf.sim.world.road_graph import Path
from tests.conftest import TEST_FLEET

#: A straight lane along x; the car at the origin facing along it, its camera 0.1 m ahead of its origin.
LANE = Path(np.column_stack([np.linspace(0, 10, 101), np.zeros(101)]), np.zeros(101), np.zeros(101))
POSE = np.array([0.0, 0.0, 0.0])
CAMERA = (0.1, 0.0)
REAR = QCAR2_BOX_M[0] / 2


def _obs(*raws: bytes, at: float = 0.0) -> dict:
    rows, times = np.zeros(RADIO_SLOTS * SIGNED_BYTES, np.uint8), np.zeros(RADIO_SLOTS)
    for i, raw in enumerate(raws):
        rows[i * SIGNED_BYTES:(i + 1) * SIGNED_BYTES] = np.frombuffer(raw, np.uint8)
        times[i] = at
    return {"radio": rows, "radio_times": times}


def _lead(seq: int, t: float, x: float = 2.0, y: float = 0.0, speed: float = 0.5, accel: float = 0.0,
          key: SigningKey | None = None) -> bytes:
    return sign(V2VMessage(seq, t, Broadcast(1, x, y, 0.0, speed, accel, False)), key or TEST_FLEET.signing_key(1))


def test_a_fresh_trusted_message_is_accepted_and_tells_the_leads_rear_moved_on_to_now():
    car = BroadcastReceiver(TEST_FLEET.trust_store())
    assert len(car.hear(_obs(_lead(1, 1.0)), now_s=1.02)) == 1 and car.accepted == 1
    said = car.witness(1.1, POSE, CAMERA, LANE, progress_m=0.0)
    # 0.1 s old at 0.5 m/s: 5 cm on; the rear is half a car behind its origin; the camera 0.1 m ahead of the car's.
    assert said.distance_m == pytest.approx(2.0 + 0.05 - REAR - 0.1) and said.speed_mps == 0.5
    assert said.age_s == pytest.approx(0.1)
    braking = BroadcastReceiver(TEST_FLEET.trust_store())
    braking.hear(_obs(_lead(1, 1.0, speed=0.5, accel=-5.0)), now_s=1.0)
    # It brakes to a stop in 0.1 s: it goes 2.5 cm, not the 5 cm a constant speed would.
    assert braking.witness(1.2, POSE, CAMERA, LANE, 0.0).distance_m == pytest.approx(2.0 + 0.025 - REAR - 0.1)


def test_forged_replayed_and_stale_messages_are_refused_and_counted_each_by_why():
    car = BroadcastReceiver(TEST_FLEET.trust_store())
    car.hear(_obs(_lead(5, 1.0)), now_s=1.0)
    heard = car.hear(_obs(_lead(6, 1.1, key=SigningKey(bytes(32))),  # forged: a key outside the fleet
                          _lead(5, 1.0),  # replayed: the same message again
                          _lead(3, 0.8),  # replayed: an older one
                          _lead(7, 1.1 - MAX_AGE_S - 0.01),  # numbered past, stamped before the last: replayed
                          _lead(8, 1.2)),  # from the future: stale
                     now_s=1.1)
    assert heard == [] and car.accepted == 1
    assert car.refused == {"malformed": 0, "unknown sender": 0, "bad signature": 1, "replayed": 3, "out of window": 0,
                           "stale": 1}
    assert car.last[1].seq == 5  # nothing refused moved the sender's number on
    assert len(car.hear(_obs(_lead(9, 1.1)), now_s=1.1)) == 1


def test_no_witness_from_an_old_message_or_a_car_off_the_lane_or_behind():
    car = BroadcastReceiver(TEST_FLEET.trust_store())
    car.hear(_obs(_lead(1, 1.0)), now_s=1.0)
    assert car.witness(1.0 + MAX_AGE_S + 0.01, POSE, CAMERA, LANE, 0.0) is None
    for x, y in ((2.0, 0.5), (-1.0, 0.0)):  # beside the lane; behind the car
        other = BroadcastReceiver(TEST_FLEET.trust_store())
        other.hear(_obs(_lead(1, 1.0, x=x, y=y)), now_s=1.0)
        assert other.witness(1.0, POSE, CAMERA, LANE, 0.0) is None
    assert BroadcastReceiver(TEST_FLEET.trust_store()).hear({}, 0.0) == []  # an env without a radio: nothing heard


def test_in_a_bend_the_witness_is_the_chord_to_the_leads_rear():
    bend = np.linspace(0, math.pi / 2, 200)
    arc = Path(np.column_stack([np.sin(bend), 1 - np.cos(bend)]), bend, np.ones(200))
    car = BroadcastReceiver(TEST_FLEET.trust_store())
    # The lead a quarter-turn on, facing up the y axis; its rear half a car below its origin.
    car.hear(_obs(sign(V2VMessage(1, 0.0, Broadcast(1, 1.0, 1.0, math.pi / 2, 0.0, 0.0, False)), TEST_FLEET.signing_key(1))), 0.0)
    said = car.witness(0.0, POSE, (0.0, 0.0), arc, progress_m=0.0)
    assert said.distance_m == pytest.approx(math.hypot(1.0, 1.0 - REAR))


def test_the_checks_bounds_hold_at_their_edges():
    car = BroadcastReceiver(TEST_FLEET.trust_store(), max_age_s=0.25)  # (times a float holds exactly)
    assert len(car.hear(_obs(_lead(1, 1.0)), now_s=1.25)) == 1  # exactly as old as allowed
    assert len(car.hear(_obs(_lead(2, 1.28125)), now_s=1.25)) == 1  # a little ahead: the clocks' slack
    assert car.refused["stale"] == 0
    assert car.witness(1.28125, POSE, CAMERA, LANE, 0.0).age_s == 0.0  # a message of now
    assert car.witness(1.53125, POSE, CAMERA, LANE, 0.0).age_s == 0.25  # the oldest allowed
    assert BroadcastReceiver(TEST_FLEET.trust_store()).hear({"radio": _obs(_lead(1, 0.0))["radio"]}, 0.0) == []  # no arrival times


def test_the_nearest_of_several_cars_ahead_is_the_witness():
    for order in ((2.0, 3.0), (3.0, 2.0)):
        car = BroadcastReceiver(TEST_FLEET.trust_store())
        for sender, x in zip((1, 2), order):
            car.hear(_obs(sign(V2VMessage(1, 1.0, Broadcast(sender, x, 0.0, 0.0, 0.0, 0.0, False)), TEST_FLEET.signing_key(sender))),
                     now_s=1.0)
        assert car.witness(1.0, POSE, CAMERA, LANE, 0.0).distance_m == pytest.approx(2.0 - REAR - 0.1)


def test_a_standing_or_speeding_lead_is_moved_on_as_it_goes():
    standing, speeding = BroadcastReceiver(TEST_FLEET.trust_store()), BroadcastReceiver(TEST_FLEET.trust_store())
    standing.hear(_obs(_lead(1, 1.0, speed=0.0, accel=0.0)), now_s=1.0)
    assert standing.witness(1.2, POSE, CAMERA, LANE, 0.0).distance_m == pytest.approx(2.0 - REAR - 0.1)
    speeding.hear(_obs(_lead(1, 1.0, speed=0.5, accel=2.0)), now_s=1.0)
    said = speeding.witness(1.2, POSE, CAMERA, LANE, 0.0)
    assert said.distance_m == pytest.approx(2.0 + 0.5 * 0.2 + 0.5 * 2.0 * 0.2 ** 2 - REAR - 0.1)
    assert said.speed_mps == pytest.approx(0.9)


def test_a_lead_the_car_has_passed_on_its_lane_or_that_lies_behind_its_camera_is_no_witness():
    car = BroadcastReceiver(TEST_FLEET.trust_store())
    car.hear(_obs(_lead(1, 1.0, x=2.0)), now_s=1.0)
    assert car.witness(1.0, POSE, CAMERA, LANE, progress_m=3.0) is None  # the lane's 2 m lies behind the car
    assert car.witness(1.0, np.array([0.0, 0.0, math.pi]), CAMERA, LANE, progress_m=0.0) is None  # behind the camera


def test_the_witness_is_found_in_any_frame_as_far_as_the_lane_ahead_reaches_and_within_half_a_lane():
    # The lane along +y, the car facing it, its camera 0.1 m ahead and 0.05 m left of its origin.
    up = Path(np.column_stack([np.zeros(101), np.linspace(0, 10, 101)]), np.full(101, math.pi / 2), np.zeros(101))
    pose, camera = np.array([0.0, 0.0, math.pi / 2]), (0.1, 0.05)

    def told(x, y):
        car = BroadcastReceiver(TEST_FLEET.trust_store())
        car.hear(_obs(sign(V2VMessage(1, 0.0, Broadcast(1, x, y, math.pi / 2, 0.0, 0.0, False)), TEST_FLEET.signing_key(1))), 0.0)
        return car.witness(0.0, pose, camera, up, progress_m=0.0)

    assert told(0.0, 2.0).distance_m == pytest.approx(math.hypot(0.0 - (-0.05), 2.0 - REAR - 0.1))
    assert told(0.0, 5.5) is not None and told(0.0, 7.5) is None  # the lane ahead is 6 m long
    assert told(0.25, 2.0) is not None and told(-0.25, 2.0) is not None  # within half a lane, either side
    assert told(0.35, 2.0) is None and told(-0.35, 2.0) is None


def test_a_number_far_past_the_last_is_out_of_window_and_cannot_lock_the_sender_out():
    # 0.25 s after the last message a sender can have numbered ceil(0.25 x 50) + 8 = 21 more, not 2^32 - 6.
    car = BroadcastReceiver(TEST_FLEET.trust_store())
    car.hear(_obs(_lead(5, 1.0)), now_s=1.0)
    assert car.hear(_obs(_lead(2 ** 32 - 1, 1.25)), now_s=1.25) == [] and car.refused["out of window"] == 1
    assert car.hear(_obs(_lead(27, 1.25)), now_s=1.25) == [] and car.refused["out of window"] == 2  # 22 past 5
    assert len(car.hear(_obs(_lead(26, 1.25)), now_s=1.25)) == 1  # 21 past 5: the genuine sender goes on
    # Such a number as the sender's first is taken, but holds it at most max_age_s: then its next starts it again.
    fresh_car = BroadcastReceiver(TEST_FLEET.trust_store())
    assert len(fresh_car.hear(_obs(_lead(2 ** 32 - 1, 1.0)), now_s=1.0)) == 1
    assert fresh_car.hear(_obs(_lead(6, 1.1)), now_s=1.1) == [] and fresh_car.refused["replayed"] == 1
    assert len(fresh_car.hear(_obs(_lead(7, 1.0 + MAX_AGE_S + 0.01)), now_s=1.0 + MAX_AGE_S + 0.01)) == 1


def test_one_age_check_with_one_bound_where_a_message_is_taken_and_where_it_is_used():
    from racf.experiments.car.broadcast import FUTURE_S, fresh

    assert fresh(-FUTURE_S) and fresh(MAX_AGE_S) and not fresh(-FUTURE_S - 0.001) and not fresh(MAX_AGE_S + 0.001)
    car = BroadcastReceiver(TEST_FLEET.trust_store())
    car.hear(_obs(_lead(1, 1.04)), now_s=1.0)  # 40 ms ahead of the car's clock: taken
    said = car.witness(1.0, POSE, CAMERA, LANE, progress_m=0.0)  # and used, as it stands (never moved back)
    assert car.accepted == 1 and said is not None and said.age_s == 0.0
    assert said.distance_m == pytest.approx(2.0 - REAR - 0.1)
