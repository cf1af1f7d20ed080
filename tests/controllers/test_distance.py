"""Depth distance and the camera model on known geometry (the LiDAR reference: test_lidar_target.py)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from racf.controllers import CameraModel, DepthDistance, Detection

CAM = CameraModel(width=320, fx=227.6, cx=160.0)


def _detection(mask: np.ndarray, confidence: float = 0.9) -> Detection:
    rows, cols = np.nonzero(mask)
    return Detection(mask, (int(cols.min()), int(rows.min()), int(cols.max()) + 1, int(rows.max()) + 1),
                     confidence, int(mask.sum()), (float(cols.mean()), float(rows.mean())))


def _box_mask(x0=150, y0=100, x1=170, y1=120, shape=(240, 320)):
    m = np.zeros(shape, bool)
    m[y0:y1, x0:x1] = True
    return m


def test_depth_is_the_median_of_valid_pixels_and_confidence_scales_with_the_valid_share():
    mask = _box_mask()
    depth = np.full(mask.shape, 5.0, np.float32)
    depth[mask] = 1.25
    depth[100:105, 150:170] = 0.0  # a quarter of the sign without a return
    d, c = DepthDistance().estimate(depth, _detection(mask, 0.8))
    assert d == pytest.approx(1.25)
    assert c == pytest.approx(0.8 * 0.75)


def test_depth_without_detection_or_valid_pixels_is_nan_with_zero_confidence():
    mask = _box_mask()
    assert math.isnan(DepthDistance().estimate(np.ones(mask.shape), None)[0])
    d, c = DepthDistance().estimate(np.zeros(mask.shape), _detection(mask))
    assert math.isnan(d) and c == 0.0
    with pytest.raises(ValueError, match="does not match"):
        DepthDistance().estimate(np.ones((10, 10)), _detection(mask))


@settings(max_examples=50, deadline=None)
@given(st.floats(0.2, 8.0), st.floats(0.0, 0.5))
def test_depth_median_ignores_a_minority_of_outliers(true_d, outlier_share):
    mask = _box_mask()
    depth = np.zeros(mask.shape, np.float32)
    depth[mask] = true_d
    n_out = int(outlier_share * 0.9 * mask.sum())
    rows, cols = np.nonzero(mask)
    depth[rows[:n_out], cols[:n_out]] = 0.05
    d, _ = DepthDistance().estimate(depth, _detection(mask))
    assert d == pytest.approx(true_d, rel=1e-6)


def test_camera_model_rejects_bad_intrinsics():
    with pytest.raises(ValueError, match="fx > 0"):
        CameraModel(width=320, fx=-1.0, cx=160.0)


def test_camera_bearing_is_left_positive():
    assert CAM.bearing(CAM.cx) == 0.0
    assert CAM.bearing(0.0) > 0 > CAM.bearing(319.0)
    assert CAM.half_hfov_rad == pytest.approx(math.atan(160 / 227.6))
