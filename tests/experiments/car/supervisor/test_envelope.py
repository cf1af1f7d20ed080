"""The envelope's arithmetic: RSS's safe gap and the speed it allows are each other's inverse, and
behave as a gap should (more speed, more gap; a faster lead, less)."""

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from racf.experiments.car.supervisor.envelope import Envelope, safe_gap, safe_speed

ENV = Envelope()
speeds = st.floats(0.0, 3.0)


@given(speeds, speeds)
def test_the_speed_a_safe_gap_allows_is_the_speed_it_was_made_for(v, lead):
    assert safe_speed(safe_gap(v, lead, ENV), lead, ENV) == pytest.approx(v, abs=1e-9)


@given(speeds, speeds, st.floats(0.0, 1.0))
def test_more_speed_needs_more_gap_and_a_faster_lead_less(v, lead, more):
    assert safe_gap(v + more, lead, ENV) >= safe_gap(v, lead, ENV)
    assert safe_gap(v, lead + more, ENV) <= safe_gap(v, lead, ENV)


def test_the_gap_is_rss_by_hand():
    # 1 m/s, a standing lead: 0.1 s at 1 m/s, 0.1 s of 7.36 m/s^2, then 1.736 m/s braked at 4 m/s^2, + 0.05 m.
    expected = 0.1 + 0.5 * 7.36 * 0.01 + 1.736 ** 2 / 8 + 0.05
    assert safe_gap(1.0, 0.0, ENV) == pytest.approx(expected)
    # A lead at 0.6 m/s braking at 6 m/s^2 goes 0.03 m further.
    assert safe_gap(1.0, 0.6, ENV) == pytest.approx(expected - 0.03)
    # Planned at a comfortable 1.5 m/s^2 the car needs more.
    assert safe_gap(1.0, 0.0, ENV, ENV.comfort_brake_mps2) > expected


def test_no_speed_is_safe_in_no_gap():
    assert safe_speed(0.0, 0.0, ENV) < 0.0 and safe_speed(-1.0, 0.0, ENV) == -math.inf
    assert safe_speed(math.inf, 0.0, ENV) == math.inf


@pytest.mark.parametrize("field, value, words", [("witness_error_m", -0.1, "witness_error_m must be"),
                                                 ("car_brake_mps2", 0.0, "car_brake_mps2 must be > 0"),
                                                 ("comfort_brake_mps2", 5.0, "must not exceed"),
                                                 ("reaction_s", math.nan, "reaction_s must be"),
                                                 ("margin_m", True, "margin_m must be")])
def test_a_bad_envelope_is_refused_by_name(field, value, words):
    with pytest.raises(ValueError, match=words):
        Envelope(**{field: value})


def test_the_envelope_is_the_one_the_guarantee_page_states():
    import dataclasses

    stated = {"witness_error_m": 0.12, "attack_error_m": 0.05, "lead_speed_error_mps": 0.25, "target_decel_mps2": 6.0, "target_accel_mps2": 7.36,
              "target_max_mps": 3.0, "car_brake_mps2": 4.0, "car_accel_mps2": 7.36, "reaction_s": 0.1,
              "margin_m": 0.05, "odometry_error": 0.02, "route_error_m": 0.1, "comfort_brake_mps2": 1.5}
    assert dataclasses.asdict(ENV) == stated and ENV.delta_m == pytest.approx(0.17)  # each error once, summed
    with pytest.raises(dataclasses.FrozenInstanceError):
        ENV.witness_error_m = 0.2
    # Small brakes are brakes; comfort may be all the car has.
    assert Envelope(car_brake_mps2=0.5, comfort_brake_mps2=0.5).car_brake_mps2 == 0.5


def test_a_lead_reversing_counts_as_standing_and_a_gap_too_small_for_any_speed_says_brake():
    assert safe_gap(1.0, -1.0, ENV) == safe_gap(1.0, 0.0, ENV)
    assert safe_speed(0.5, -1.0, ENV) == safe_speed(0.5, 0.0, ENV)
    # Gaps that leave no room: no speed is safe (never NaN).
    assert safe_speed(-0.5, 0.0, ENV) == -math.inf and safe_speed(0.01, 0.0, ENV) < 0


def test_the_stopping_distance_by_hand_and_gaps_beyond_any_number():
    from racf.experiments.car.supervisor.envelope import stopping_m

    env = Envelope()  # rho 0.1 s, a 7.36 m/s^2, b 4 m/s^2, margin 0.05 m
    # From 1 m/s: 1 x 0.1 + 7.36 x 0.1^2 / 2 + (1 + 0.736)^2 / (2 x 4) = 0.1 + 0.0368 + 0.376712 (no margin).
    assert stopping_m(1.0, env) == pytest.approx(0.513512)
    assert safe_gap(-0.5, 0.0, env) == safe_gap(0.0, 0.0, env)  # rolling back is standing
    assert safe_speed(math.inf, 0.0, env) == math.inf
    assert safe_speed(-math.inf, 0.0, env) == -math.inf and safe_speed(math.nan, 0.0, env) == -math.inf
