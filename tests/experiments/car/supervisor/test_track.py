"""The carried target's bounds hold the truth: a lead that brakes no harder than a_max and pulls away
no harder than the envelope says stays between them, however long it goes unseen."""

import math

from hypothesis import given, settings
from hypothesis import strategies as st

from racf.experiments.car.supervisor.envelope import Envelope
from racf.experiments.car.supervisor.track import CarriedTarget

ENV = Envelope()
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
