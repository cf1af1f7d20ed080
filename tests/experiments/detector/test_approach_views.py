"""Approach views for the sticker's expectation over the loop: on the lanes, weighted to the decision band."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from racf.experiments.detector.approach_views import (APPROACH_RANGE_M, DECISION_BAND_M, OUTSIDE_WEIGHT,
                                                      approach_views, draw_approach_view, view_weight)
from racf.sim.world.stop_signs import stop_signs

OFFSET = (0.095, 0.0)


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**31))
def test_a_view_stands_on_an_approach_facing_along_it(seed):
    spec = draw_approach_view(np.random.default_rng(seed), OFFSET)
    sign = stop_signs()[spec.sign]
    s, _ = sign.path.project(np.asarray(spec.camera_xy), s_hint=sign.stop_s - 1.0, window_m=5.0)
    x, y, heading = sign.path.pose_at(s)
    assert math.hypot(spec.camera_xy[0] - x, spec.camera_xy[1] - y) < 0.2  # a few cm off the lane's centre
    # The heading there, give or take the drawn heading error (2 deg std) and the lane's curve
    # between the camera and the body origin: never the other way round or across the lane.
    assert abs((spec.yaw - heading + math.pi) % (2 * math.pi) - math.pi) < math.radians(25)
    s_sign, _ = sign.path.project(np.asarray(sign.position), s_hint=sign.stop_s, window_m=0.6)
    assert APPROACH_RANGE_M[0] - 0.25 <= s_sign - s <= APPROACH_RANGE_M[1] + 0.25


def test_the_decision_band_weighs_fully_and_the_rest_a_quarter():
    lo, hi = DECISION_BAND_M
    assert view_weight(lo) == view_weight((lo + hi) / 2) == view_weight(hi) == 1.0
    assert view_weight(lo - 0.1) == view_weight(hi + 0.1) == view_weight(math.nan) == OUTSIDE_WEIGHT


def test_rendered_views_are_seeded_and_show_the_sign_on_some():
    a, b = approach_views(12, seed=3), approach_views(12, seed=3)
    assert np.array_equal(a["rgb"], b["rgb"]) and np.array_equal(a["weight"], b["weight"])
    assert a["rgb"].shape == (12, 240, 320, 3) and a["target"].any(axis=(1, 2)).any()
    with pytest.raises(ValueError, match="n must be"):
        approach_views(0)
