"""Speeds the supervisor relies on: the target's from the car's own range rate and odometry, and a bound
on the car's own true speed that an encoder spinning up or locking cannot pull below the body's."""

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from racf.experiments.car.supervisor.speed import GRIP_MPS2, RangeRate, SpeedBound

DT = 0.02


def test_a_lead_pulling_away_is_measured_by_its_range_rate_plus_the_car_s_own_travel():
    rate = RangeRate(window_s=0.6, span_s=0.3, max_std_mps=0.1)
    # The car at 0.5 m/s, the lead at 0.8 m/s: the range grows 0.3 m/s from 1.0 m.
    for k in range(20):
        rate.step(0.5, DT, 1.0 + 0.3 * (k + 1) * DT)
    mps, measured = rate.estimate()
    assert measured and mps == pytest.approx(0.8)


def test_too_few_or_too_short_a_span_of_readings_measures_nothing():
    rate = RangeRate(span_s=0.3)
    for k in range(3):
        rate.step(0.0, DT, 1.0)
    assert rate.estimate() == (rate.estimate()[0], False) and math.isnan(rate.estimate()[0])
    for k in range(10):  # 13 readings over 0.24 s: short of the span
        rate.step(0.0, DT, 1.0)
    assert not rate.estimate()[1]
    for k in range(5):  # 0.34 s: measured, standing
        rate.step(0.0, DT, 1.0)
    assert rate.estimate() == (0.0, True)


def test_readings_that_scatter_measure_nothing_and_a_new_chain_starts_again():
    rate = RangeRate(max_std_mps=0.1)
    for k in range(30):
        rate.step(0.0, DT, 1.0 + (0.3 if k % 2 else -0.3))
    assert not rate.estimate()[1]
    rate.restart()
    assert math.isnan(rate.estimate()[0])


def test_only_the_window_counts_and_a_target_never_reverses():
    rate = RangeRate(window_s=0.6)
    for k in range(100):  # a target coming back towards the car at 0.5 m/s (a phantom, or a reversing one)
        rate.step(0.0, DT, 3.0 - 0.5 * (k + 1) * DT)
    assert rate.estimate() == (0.0, True)
    times = [t for t, _ in rate._points]
    assert 0.58 - 1e-9 <= times[-1] - times[0] <= 0.6 + 1e-9  # the last 0.6 s only


def test_the_speed_bound_is_the_encoder_s_with_its_error_or_falls_no_faster_than_the_grip():
    bound = SpeedBound(error=0.02)
    assert bound.step(1.0, DT) == pytest.approx(1.02)
    # The wheels lock: the encoder says 0, the body cannot have lost more than the grip allows in a step.
    assert bound.step(0.0, DT) == pytest.approx(1.02 - GRIP_MPS2 * DT)
    assert GRIP_MPS2 == pytest.approx(7.3575)
    # Spinning up: the encoder's own reading, however high (on the safe side).
    assert bound.step(2.0, DT) == pytest.approx(2.04)
    bound.reset()
    assert bound.step(-0.3, DT) == 0.0  # rolling back counts as standing


@given(st.lists(st.floats(0.0, 3.0), min_size=2, max_size=60), st.floats(0.5, 2.0))
def test_the_bound_never_falls_below_a_body_that_slows_no_faster_than_the_grip(readings, start):
    """A body at ``start`` slowing at the grip: whatever the encoder reads, the bound stays above it."""
    bound = SpeedBound(error=0.0)
    body = start
    bound.step(start, DT)
    for reading in readings:
        body = max(body - GRIP_MPS2 * DT, 0.0)
        assert bound.step(reading, DT) >= body - 1e-9


def test_the_default_bound_takes_the_encoder_s_2_percent_and_the_tyres_grip():
    bound = SpeedBound()
    assert bound.step(1.0, DT) == pytest.approx(1.02)
    assert bound.step(0.0, DT) == pytest.approx(1.02 - 0.75 * 9.81 * DT)
