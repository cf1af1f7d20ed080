"""``Perception``'s map gating: a detection counts only where the map says the target is."""

import math

import cv2
import numpy as np
import pytest

from controllers import CameraModel, StopSignDetector
from controllers.perception import Perception

CAMERA = CameraModel(width=160, fx=100.0, cx=80.0)
MARGIN = math.radians(3.0)
DEPTH = np.full((120, 160), 2.0)


def _sign_at(u: int) -> np.ndarray:
    """A 120 x 160 frame with a 30 px stop sign (red octagon, white border) centred on column ``u``."""
    img = np.full((120, 160, 3), 175, np.uint8)
    angles = np.pi / 8 + np.arange(8) * np.pi / 4
    for radius, colour in ((15 / np.cos(np.pi / 8), (245, 245, 245)), (0.88 * 15 / np.cos(np.pi / 8), (200, 12, 14))):
        poly = np.column_stack([u + radius * np.cos(angles), 60 + radius * np.sin(angles)]).round().astype(np.int32)
        cv2.fillPoly(img, [poly], colour)
    return img


@pytest.fixture(scope="module")
def frame():
    """(rgb, the detector's detection on it, bearing of the box's left edge, of its right edge), rad."""
    rgb = _sign_at(100)  # right of centre: every bearing on the box is negative
    det = StopSignDetector().detect(rgb)
    assert det is not None
    x0, _, x1, _ = det.box
    return rgb, det, CAMERA.bearing(x0 - 0.5), CAMERA.bearing(x1 - 0.5)


def _process(rgb, map_bearing="absent", margin=MARGIN):
    perception = Perception(CAMERA, map_margin_rad=margin)
    if map_bearing == "absent":
        return perception, perception.process(rgb, DEPTH, None)
    return perception, perception.process(rgb, DEPTH, None, map_bearing=map_bearing)


def _assert_kept(sample, det):
    assert sample.detected and sample.detection.box == det.box
    assert sample.d_meas == pytest.approx(2.0) and sample.c_meas == pytest.approx(det.confidence)
    assert math.isfinite(sample.bearing_rad)


def _assert_dropped(perception, sample, det):
    assert not sample.detected and sample.detection is None
    assert math.isnan(sample.d_meas) and sample.c_meas == 0.0 and math.isnan(sample.bearing_rad)
    # The detector did see it: the map check dropped it.
    assert perception.last_raw_detection is not None and perception.last_raw_detection.box == det.box


def test_a_detection_at_the_map_bearing_is_kept(frame):
    rgb, det, left, right = frame
    assert right < left < 0
    _, sample = _process(rgb, map_bearing=0.5 * (left + right))
    _assert_kept(sample, det)
    assert right < sample.bearing_rad < left


def test_a_detection_far_off_the_map_bearing_is_dropped(frame):
    rgb, det, left, right = frame
    for map_bearing in (0.0, left + 0.2, right - 0.2, -0.5 * (left + right)):
        perception, sample = _process(rgb, map_bearing=map_bearing)
        _assert_dropped(perception, sample, det)


def test_the_box_widened_by_the_margin_is_kept_and_just_beyond_is_dropped(frame):
    rgb, det, left, right = frame
    for edge in (left + MARGIN, right - MARGIN):
        _, sample = _process(rgb, map_bearing=edge)
        _assert_kept(sample, det)
    for beyond in (left + MARGIN + 1e-6, right - MARGIN - 1e-6):
        perception, sample = _process(rgb, map_bearing=beyond)
        _assert_dropped(perception, sample, det)


def test_the_margin_decides_a_bearing_just_outside_the_box(frame):
    rgb, det, left, _ = frame
    outside = left + 0.5 * MARGIN
    _assert_kept(_process(rgb, map_bearing=outside)[1], det)
    perception, sample = _process(rgb, map_bearing=outside, margin=0.0)
    _assert_dropped(perception, sample, det)
    _assert_kept(_process(rgb, map_bearing=left, margin=0.0)[1], det)


def test_nan_map_bearing_drops_every_detection(frame):
    rgb, det, _, _ = frame
    perception, sample = _process(rgb, map_bearing=math.nan)
    _assert_dropped(perception, sample, det)
    # Even a sign dead ahead, whichever margin.
    centred = _sign_at(80)
    perception, sample = _process(centred, map_bearing=math.nan, margin=math.pi)
    assert perception.last_raw_detection is not None and not sample.detected and math.isnan(sample.d_meas)


def test_no_map_bearing_keeps_every_detection(frame):
    rgb, det, _, _ = frame
    _, default = _process(rgb)
    _, none = _process(rgb, map_bearing=None)
    for sample in (default, none):
        _assert_kept(sample, det)
    assert none.bearing_rad == default.bearing_rad and none.d_meas == default.d_meas
    assert none.c_meas == default.c_meas
