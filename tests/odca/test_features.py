"""The delta head's input conventions (racf.odca.features)."""

import math

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from racf.odca.features import sanitize

_ANY = st.floats(allow_nan=True, allow_infinity=True)


@given(st.lists(st.tuples(_ANY, _ANY, _ANY), min_size=1, max_size=20))
def test_confidence_speed_and_yaw_rate_are_what_nan_to_num_then_clip_gives(rows):
    # The cheap form must equal the documented rule bit for bit: NaN -> 0, an infinity to its bound.
    c, v, w = (np.array(col, float) for col in zip(*rows))
    _, c_out, _, v_out, w_out, _ = sanitize(np.ones(len(rows)), c, np.ones(len(rows)), v, w)
    expected = (np.clip(np.nan_to_num(c, nan=0.0, posinf=1.0, neginf=0.0), 0.0, 1.0),
                np.clip(np.nan_to_num(v, nan=0.0, posinf=10.0, neginf=-10.0), -10.0, 10.0),
                np.clip(np.nan_to_num(w, nan=0.0, posinf=10.0, neginf=-10.0), -10.0, 10.0))
    for got, want in zip((c_out, v_out, w_out), expected):
        assert got.tobytes() == want.tobytes()


@given(_ANY, _ANY)
def test_one_step_scalars_stay_scalars_within_bounds(confidence, speed):
    _, c, _, v, _, _ = sanitize(1.0, confidence, 1.0, speed)
    assert np.ndim(c) == 0 and 0.0 <= float(c) <= 1.0
    assert np.ndim(v) == 0 and -10.0 <= float(v) <= 10.0
    assert not math.isnan(float(c)) and not math.isnan(float(v))
