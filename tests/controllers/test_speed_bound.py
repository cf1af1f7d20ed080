"""A bound on the car's own true speed that an encoder spinning up or locking cannot pull below the
body's (the braker and the supervisor plan on it)."""

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from racf.controllers.speed import GRIP_MPS2, SpeedBound

DT = 0.02


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


def test_a_reading_that_is_no_number_tells_nothing_and_the_bound_falls_at_the_grip():
    bound = SpeedBound(error=0.0)
    bound.step(1.0, DT)
    assert bound.step(math.nan, DT) == pytest.approx(1.0 - 7.3575 * DT)
    bound.reset()
    assert bound.step(math.nan, DT) == 0.0
