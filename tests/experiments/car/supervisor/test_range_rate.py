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


def test_rolling_back_is_no_travel():
    rate = RangeRate()
    for k in range(20):  # the encoder reads -0.5 m/s (rolling back); the range grows 0.3 m/s
        rate.step(-0.5, DT, 1.0 + 0.3 * (k + 1) * DT)
    assert rate.estimate()[0] == pytest.approx(0.3)


def test_four_readings_spanning_the_span_measure_and_three_never():
    four = RangeRate(window_s=1.0, span_s=0.3)
    for k in range(4):  # at 0.1 s apart: 0.1 to 0.4 s
        four.step(0.0, 0.1, 1.0 + 0.2 * k * 0.1)
    assert four.estimate() == (pytest.approx(0.2), True)
    three = RangeRate(window_s=1.0, span_s=0.3)
    for k in range(3):  # 0.16 s apart: they span 0.32 s, but three are too few
        three.step(0.0, 0.16, 1.0)
    assert not three.estimate()[1]
    five = RangeRate(window_s=1.0, span_s=0.35)
    for k in range(5):  # 0.1 to 0.5 s: the first to the last span 0.4 s
        five.step(0.0, 0.1, 1.0)
    assert five.estimate() == (0.0, True)


@pytest.mark.parametrize("scatter, measured", [(0.015, True), (0.02, False)])
def test_the_slope_s_standard_error_by_hand(scatter, measured):
    # Four readings 0.1 s apart, off a line by +a, -a, -a, +a (no part along the line or its mean): the
    # residuals' sum of squares 4 a^2, the times' spread 0.05 s^2, so the slope's standard error is
    # sqrt(4 a^2 / (4 - 2) / 0.05) = 6.32 a: 0.095 m/s for a = 1.5 cm (known to 0.1), 0.126 for 2 cm.
    rate = RangeRate(window_s=1.0, span_s=0.3, max_std_mps=0.1)
    for k, e in enumerate((1, -1, -1, 1)):
        rate.step(0.0, 0.1, 1.0 + 0.5 * k * 0.1 + e * scatter)
    mps, known = rate.estimate()
    assert known is measured and mps == pytest.approx(0.5)


def test_the_default_range_rate_is_the_one_documented():
    rate = RangeRate()
    assert (rate.window_s, rate.span_s, rate.max_std_mps) == (0.6, 0.3, 0.1)


def test_late_readings_that_span_less_than_the_span_measure_nothing():
    rate = RangeRate(window_s=1.0, span_s=0.3)
    for _ in range(20):  # 1 s of no reading
        rate.step(0.0, 0.05, math.nan)
    for _ in range(4):  # then four readings over 0.15 s
        rate.step(0.0, 0.05, 1.0)
    assert not rate.estimate()[1]
