"""Following: the time-headway policy, the emergency brake and the lead's speed from the car's track."""

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from racf.controllers.following import FollowingConfig, LeadFollower, LeadSpeed


def test_the_policy_allows_the_gap_past_standstill_over_the_headway():
    follower = LeadFollower(FollowingConfig(time_headway_s=1.0, standstill_gap_m=0.25, ttc_brake_s=0.8))
    assert follower.step(math.nan, 1.0).speed_cap_mps == math.inf
    calm = follower.step(1.0, 0.5)
    assert calm.speed_cap_mps == pytest.approx(0.75) and not calm.emergency and calm.ttc_s == pytest.approx(2.0)
    assert follower.step(1.0, -0.5).ttc_s == math.inf  # opening: no collision course


def test_the_emergency_brake_stops_on_a_short_time_to_collision_or_a_gap_under_half_standstill():
    follower = LeadFollower(FollowingConfig(standstill_gap_m=0.25, ttc_brake_s=0.8))
    urgent = follower.step(0.7, 1.0)
    assert urgent.emergency and urgent.speed_cap_mps == 0.0
    assert not follower.step(0.9, 1.0).emergency
    assert follower.step(0.12, 0.0).emergency and not follower.step(0.13, 0.0).emergency


def run(speed: LeadSpeed, lead_mps: float, ego_mps: float, steps: int, depth_bias=0.0, lidar=True, start=1.0):
    d = start
    for k in range(steps):
        d += (lead_mps - ego_mps) * 0.02
        new = k % 2 == 0
        out = speed.update(d + depth_bias, d if lidar else math.nan, math.nan if lidar else d, ego_mps, 0.02, new)
    return out


def test_it_learns_the_lead_speed_while_the_witnesses_agree():
    speed = LeadSpeed()
    assert speed.lead_mps == 0.0  # unknown: a target standing still
    assert run(speed, 0.6, 1.0, 150) == pytest.approx(0.6, abs=0.05)
    # The size witness stands in where the scan plane misses the car.
    assert run(LeadSpeed(), 0.4, 0.8, 150, lidar=False) == pytest.approx(0.4, abs=0.05)


def test_it_carries_its_estimate_while_the_witnesses_disagree():
    speed = LeadSpeed()
    learnt = run(speed, 0.6, 1.0, 150)
    # The depth read 1 m far: a lead that runs away, if it were believed.
    before = speed.range_m
    assert run(speed, 0.6, 1.0, 100, depth_bias=1.0, start=speed.range_m) == pytest.approx(learnt)
    # Its range is carried at the lead's speed against the car's, not at the car's alone.
    assert speed.range_m - before == pytest.approx((learnt - 1.0) * 2.0, abs=0.03)


def test_a_range_off_its_track_starts_it_again_and_waits_to_confirm():
    speed = LeadSpeed(FollowingConfig(gate_m=0.25, confirm_frames=6))
    run(speed, 0.6, 1.0, 150)
    speed.update(3.0, 3.0, math.nan, 1.0, 0.02, True)  # another car, or the same one seen again
    assert speed.frames == 1 and speed.lead_mps == 0.0


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.floats(-5, 5), st.floats(-5, 5), st.floats(0, 3), st.booleans()), min_size=1, max_size=40))
def test_its_estimate_stays_a_plausible_speed(readings):
    speed = LeadSpeed()
    for depth, lidar, ego, new in readings:
        out = speed.update(depth, lidar, math.nan, ego, 0.02, new)
        assert 0.0 <= out <= speed.config.max_lead_mps


def test_bad_settings_are_refused():
    with pytest.raises(ValueError, match="time_headway_s"):
        FollowingConfig(time_headway_s=0.0)
    with pytest.raises(ValueError, match="confirm_frames"):
        FollowingConfig(confirm_frames=-1)


def test_the_lead_speed_is_used_only_once_confirmed_and_never_past_a_plausible_one():
    speed = LeadSpeed(FollowingConfig(confirm_frames=6))
    assert run(speed, 0.6, 1.0, 10) == 0.0 and speed.frames == 5  # five agreeing frames: not yet
    assert run(speed, 0.6, 1.0, 2, start=speed.range_m) > 0.1
    runaway = LeadSpeed(FollowingConfig(confirm_frames=0, max_lead_mps=3.0))
    for k in range(200):  # the range grows 0.08 m a frame (within the gate): 4 m/s faster than the car
        runaway.update(1.0 + 0.08 * k, 1.0 + 0.08 * k, math.nan, 0.0, 0.02, True)
    assert runaway.lead_mps == 3.0
