"""The size witness: d_size = f * H / h on known boxes, and what it refuses to measure."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from racf.controllers import CameraModel, Detection, SizeDistance

CAM = CameraModel(width=320, fx=227.6, cx=160.0, fy=229.7)
FACE = 0.088
SIZE = SizeDistance(CAM, FACE)


def _detection(x0, y0, x1, y1, confidence=0.9, shape=(240, 320)) -> Detection:
    mask = np.zeros(shape, bool)
    mask[y0:y1, x0:x1] = True
    return Detection(mask, (x0, y0, x1, y1), confidence, int(mask.sum()), ((x0 + x1) / 2, (y0 + y1) / 2))


@settings(max_examples=200, deadline=None)
@given(st.integers(3, 100), st.floats(0.5, 1.0))
def test_a_box_of_the_faces_height_gives_its_depth(rows, confidence):
    d, std = SIZE.estimate(_detection(100, 60, 100 + rows, 60 + rows, confidence))
    assert d == pytest.approx(CAM.fy * FACE / rows)
    assert std > 0


def test_the_std_grows_as_the_box_shrinks_and_as_the_confidence_falls():
    near = SIZE.estimate(_detection(100, 60, 140, 100))
    far = SIZE.estimate(_detection(100, 60, 108, 68))
    assert near[1] / near[0] < far[1] / far[0]
    unsure = SIZE.estimate(_detection(100, 60, 140, 100, confidence=0.6))
    assert unsure[1] > near[1] and unsure[0] == near[0]


def test_yaw_narrows_the_box_but_the_height_speaks():
    upright = SIZE.estimate(_detection(100, 60, 120, 80))
    turned = SIZE.estimate(_detection(100, 60, 110, 80))  # seen 60 deg off its normal
    assert turned[0] == upright[0]


def test_a_box_clearly_wider_than_tall_has_lost_rows_and_its_width_speaks():
    """An occluder over the top half: the width still spans the whole face. A whole octagon's box
    a pixel or two wider than tall (its slanted edges) is still measured by its height."""
    whole = SIZE.estimate(_detection(100, 60, 120, 80))
    half = SIZE.estimate(_detection(100, 70, 120, 80))
    assert half[0] == pytest.approx(CAM.fy * FACE / (20 * CAM.fy / CAM.fx))
    assert half[0] == pytest.approx(whole[0], rel=0.02)
    slanted = SIZE.estimate(_detection(100, 60, 112, 70))  # 10 rows, 12 columns
    assert slanted[0] == pytest.approx(CAM.fy * FACE / 10)


def test_no_witness_without_a_detection_on_the_edge_or_when_too_broken():
    assert all(math.isnan(x) for x in SIZE.estimate(None))
    assert all(math.isnan(x) for x in SIZE.estimate(_detection(0, 60, 20, 80)))  # cut by the left edge
    assert all(math.isnan(x) for x in SIZE.estimate(_detection(300, 225, 320, 240)))  # the corner
    assert all(math.isnan(x) for x in SIZE.estimate(_detection(100, 60, 120, 80, confidence=0.3)))


def test_bad_settings_are_clear_errors():
    with pytest.raises(ValueError, match="face_m"):
        SizeDistance(CAM, 0.0)
    with pytest.raises(ValueError, match="floor"):
        SizeDistance(CAM, FACE, floor=2.0)
