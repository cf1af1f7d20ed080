"""The target's speed the supervisor relies on: measured from the car's own range rate and odometry."""

import math

import pytest

from racf.experiments.car.supervisor.speed import RangeRate

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
