"""The carried target's bounds hold the truth: a lead that brakes no harder than a_max and pulls away
no harder than the envelope says stays between them, however long it goes unseen."""

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from racf.experiments.car.supervisor.envelope import Envelope
from racf.experiments.car.supervisor.track import CarriedTarget

#: delta 0.1 m: round numbers to work by hand (the default budget is 0.12 + 0.05).
ENV = Envelope(witness_error_m=0.05, attack_error_m=0.05)
DT = 0.02


@settings(max_examples=60, deadline=None)
@given(st.floats(0.3, 2.0), st.floats(0.0, 1.5), st.floats(-0.1, 0.1), st.floats(-0.25, 0.25),
       st.lists(st.floats(-ENV.target_decel_mps2, ENV.target_accel_mps2), min_size=1, max_size=20),
       st.lists(st.floats(0.0, 1.5), min_size=1, max_size=20))
def test_a_lead_within_the_envelope_stays_between_the_bounds(gap, lead, error, speed_error, accels, ego):
    carried = CarriedTarget(ENV)
    carried.vouch(gap + error, lead + speed_error, lead_known=True)
    truth, v = gap, lead
    for step in range(300):  # 6 s unseen
        a = accels[step * len(accels) // 300]
        own = ego[step * len(ego) // 300]
        new_v = min(max(v + a * DT, 0.0), ENV.target_max_mps)
        truth += 0.5 * (v + new_v) * DT - own * DT
        v = new_v
        carried.predict(own, DT)
        assert carried.near_m <= truth + 1e-9 <= carried.far_m + 2e-9


def test_an_unknown_lead_speed_is_taken_from_standing_to_top_speed():
    carried = CarriedTarget(ENV)
    carried.vouch(1.0, 0.0, lead_known=False)
    assert (carried.slow_mps, carried.fast_mps) == (0.0, ENV.target_max_mps)
    carried.predict(0.0, 1.0)
    # Standing still at worst, gone 3 m at best (from its top speed).
    assert carried.near_m == 1.0 - ENV.delta_m and carried.far_m > 3.9


def test_the_car_closing_in_shrinks_the_near_end_by_its_travel_and_odometry_error():
    carried = CarriedTarget(ENV)
    carried.vouch(1.0, 0.0, lead_known=True)
    carried.predict(1.0, 0.1)
    assert math.isclose(carried.near_m, 0.9 - 0.1 * (1 + ENV.odometry_error))
    assert carried.holds(0.85, 0.0) and not carried.holds(0.7, 0.05)


def test_nothing_carried_holds_nothing():
    carried = CarriedTarget(ENV)
    carried.predict(1.0, 0.1)
    assert not carried.held and not carried.holds(1.0, 10.0)


def test_one_step_of_the_bounds_by_hand():
    carried = CarriedTarget(ENV)
    carried.vouch(1.0, 0.6, lead_known=True)  # speed bounds 0.35 .. 0.85 m/s
    carried.predict(0.5, 0.1)
    # Braking at 6 m/s^2 from 0.35 m/s it stops within the step: 0.35^2 / 12 m; the car went 0.05 m (+2 %).
    assert math.isclose(carried.near_m, 0.9 + 0.35 ** 2 / 12 - 0.05 * 1.02)
    # The far end pulls away from 0.85 m/s at 7.36 m/s^2 (1.586 m/s after the step); the car went 0.05 m (-2 %).
    assert math.isclose(carried.far_m, 1.1 + 1.586 * 0.1 - 0.05 * 0.98)
    # The reach keeps the vouched 0.85 m/s.
    assert math.isclose(carried.reach_m, 1.1 + 0.85 * 0.1 - 0.05 * 0.98)
    assert (carried.slow_mps, carried.unvouched_s) == (0.0, 0.1) and math.isclose(carried.fast_mps, 1.586)
    moving = CarriedTarget(ENV)
    moving.vouch(1.0, 2.0, lead_known=True)  # 1.75 m/s at least: still moving after the step
    moving.predict(0.0, 0.1)
    assert math.isclose(moving.near_m, 0.9 + 1.75 * 0.1 - 0.5 * 6.0 * 0.01)


def test_a_vouch_narrows_the_far_end_and_the_reach_but_a_reading_beyond_them_starts_afresh():
    carried = CarriedTarget(ENV)
    carried.vouch(1.0, 0.0, lead_known=False)
    carried.predict(0.0, 0.5)  # the far end has grown well past 1.2 m
    carried.vouch(1.05, 0.0, lead_known=False)
    assert math.isclose(carried.far_m, 1.15) and math.isclose(carried.reach_m, 1.15)
    far, reach = carried.far_m, carried.reach_m
    carried.vouch(far, 0.0, lead_known=False)  # at the far end itself: still narrowed (it is no farther)
    assert carried.far_m == far and carried.reach_m == reach
    carried.vouch(3.0, 0.0, lead_known=False)  # beyond them: the bounds start from it
    assert math.isclose(carried.far_m, 3.1) and math.isclose(carried.reach_m, 3.1)
    # A speed the car has lost keeps the bounds carried so far; a first sight of unknown speed does not.
    assert carried.fast_mps > 0.0 and carried.slow_mps == 0.0
    fresh = CarriedTarget(ENV)
    fresh.vouch(1.0, 0.0, lead_known=False)
    assert (fresh.slow_mps, fresh.fast_mps) == (0.0, ENV.target_max_mps)


def test_a_reset_forgets_everything_and_a_car_rolling_back_counts_as_standing():
    carried = CarriedTarget(ENV)
    carried.vouch(1.0, 0.6, lead_known=True)
    carried.predict(1.0, 0.1)
    carried.reset()
    assert not carried.held and (carried.slow_mps, carried.fast_mps, carried.unvouched_s) == (0.0, 0.0, 0.0)
    back, still = CarriedTarget(ENV), CarriedTarget(ENV)
    for c, ego in ((back, -1.0), (still, 0.0)):
        c.vouch(1.0, 0.0, lead_known=True)
        c.predict(ego, 0.1)
    assert (back.near_m, back.far_m, back.reach_m) == (still.near_m, still.far_m, still.reach_m)
    # Each vouch starts the unvouched clock again.
    back.vouch(1.0, 0.0, lead_known=True)
    assert back.unvouched_s == 0.0


def test_the_bounds_are_inclusive():
    carried = CarriedTarget(ENV)
    carried.vouch(1.0, 0.0, lead_known=True)
    assert carried.holds(0.9 - 0.05, 0.05) and carried.holds(1.1 + 0.05, 0.05)
    assert not carried.holds(0.84, 0.05) and not carried.holds(1.16, 0.05)


def test_a_speed_is_measured_only_once_told_and_kept_only_while_the_same_target_is_held():
    carried = CarriedTarget(Envelope())
    assert not carried.speed_measured  # nothing carried: nothing measured
    carried.vouch(1.0, 0.0, lead_known=False)
    assert not carried.speed_measured  # first seen, speed unknown
    carried.vouch(1.0, 0.5, lead_known=True)
    carried.vouch(1.0, 0.0, lead_known=False)
    assert carried.speed_measured  # held on: the measured speed is kept
    carried.reset()
    carried.vouch(1.0, 0.0, lead_known=False)
    assert not carried.speed_measured  # a new target: nothing measured of it


def test_a_vouch_of_lost_speed_keeps_the_reach_at_the_last_measured_speed_not_the_grown_far_end():
    carried = CarriedTarget(ENV)
    carried.vouch(1.0, 0.6, lead_known=True)  # fast bound 0.6 + 0.25 = 0.85 m/s
    for _ in range(20):  # 0.4 s: the far end's speed grows at 7.36 m/s^2 to its 3 m/s top
        carried.predict(0.0, 0.02)
    assert carried.fast_mps == 3.0
    carried.vouch(1.2, math.nan, lead_known=False)  # the chain restarted: its speed is not measured now
    # Reach from the vouch: 1.2 + 0.1 = 1.3 m, then 0.85 m/s (the last measured), not 3 m/s, for 0.1 s.
    for _ in range(5):
        carried.predict(0.0, 0.02)
    assert carried.reach_m == pytest.approx(1.3 + 0.85 * 0.1)
