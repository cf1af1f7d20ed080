"""``Perception``'s map gating: a detection counts only where the map says the target is."""

import math

import cv2
import numpy as np
import pytest

from racf.controllers import CameraModel, StopSignDetector
from racf.controllers.detector import Detection
from racf.controllers.perception import Perception

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


def test_a_larger_red_shape_off_the_map_bearing_does_not_crowd_out_the_sign(frame):
    """A red car's body at the frame's edge (a red box cut by the border, larger than the sign, passing the
    detector's tests) is the detector's own pick; the map says where the sign is, and perception keeps it."""
    rgb, det, left, right = frame
    crowded = rgb.copy()
    crowded[46:72, 0:30] = (200, 12, 14)  # 30 x 26 px of red body at the left edge, light all round
    raw = StopSignDetector().detect(crowded)
    assert raw is not None and raw.box != det.box and raw.area_px > det.area_px
    perception, sample = _process(crowded, map_bearing=(left + right) / 2)
    _assert_kept(sample, det)
    assert perception.last_raw_detection.box == raw.box  # what the detector alone would have said
    # With the map saying the target is where the red shape is, the shape is what perception reports.
    perception, sample = _process(crowded, map_bearing=CAMERA.bearing(15.0))
    assert sample.detected and sample.detection.box == raw.box


def test_of_two_candidates_the_map_allows_the_one_centred_nearer_its_bearing_is_kept(frame):
    """A red body just below the sign in the image (a car beyond it), larger than the sign: both boxes hold
    the map's bearing, and the sign, centred on it, is the one kept."""
    rgb, det, left, right = frame
    crowded = rgb.copy()
    crowded[82:112, 96:140] = (200, 12, 14)  # 44 x 30 px below the sign, its left edge inside the sign's span
    raw = StopSignDetector().detect(crowded)
    assert raw is not None and raw.box != det.box and raw.area_px > det.area_px
    bearing = CAMERA.bearing(det.centroid[0])
    _assert_kept(_process(crowded, map_bearing=bearing)[1], det)


# -- the camera is slower than the loop: held frames ------------------------------------------
LIDAR_XY = np.array([-0.012, 0.0])  # the tracker's default LiDAR and camera positions, body frame
CAMERA_XY = np.array([0.095, 0.032])
PLATE = np.array([2.0, -0.1])  # the sign's centre in the camera frame at the start, m


class CountingDetector:
    """Finds a 0.07 m sign at ``PLATE`` (box bearings as the camera sees it) and counts its calls."""

    def __init__(self):
        self.calls = 0

    def detect(self, rgb):
        self.calls += 1
        u = CAMERA.cx - CAMERA.fx * PLATE[1] / PLATE[0]
        mask = np.zeros((120, 160), bool)
        mask[57:62, 83:87] = True  # 5 px tall: a 0.1 m plate at 2 m with fx = fy = 100
        return Detection(mask, (83, 57, 87, 62), 0.9, int(mask.sum()), (u, 60.0))


def _plate_scan(ahead: float) -> np.ndarray:
    """Scan of a 0.07 m plate facing the car, its centre ``ahead`` m along the optical axis at PLATE's y."""
    x = ahead + CAMERA_XY[0] - LIDAR_XY[0]  # LiDAR frame
    y0 = PLATE[1] + CAMERA_XY[1] - LIDAR_XY[1]
    angles = 2 * np.pi * np.arange(360) / 360
    with np.errstate(divide="ignore"):
        r = x / np.cos(angles)
    hit = (np.cos(angles) > 0) & (np.abs(r * np.sin(angles) - y0) <= 0.035)
    return np.where(hit, r, np.inf)


def test_held_frames_do_not_run_the_detector_but_the_lidar_follows_odometry():
    detector = CountingDetector()
    perception = Perception(CAMERA, detector=detector)
    first = perception.process(np.zeros((120, 160, 3), np.uint8), DEPTH, _plate_scan(PLATE[0]))
    assert detector.calls == 1 and first.detected and first.d_meas == pytest.approx(2.0)
    assert first.lidar_m == pytest.approx(PLATE[0], abs=0.01)
    raw = perception.last_raw_detection
    lidar = [first.lidar_m]
    for k in range(1, 6):  # the car drives at 1 m/s; camera frames are held, a scan on step 5
        scan = _plate_scan(PLATE[0] - 0.02 * k) if k == 5 else None
        sample = perception.process(None, None, scan, speed=1.0, dt=0.02, new_frame=False)
        assert detector.calls == 1 and perception.last_raw_detection is raw
        assert sample.detection is first.detection and sample.bearing_rad == first.bearing_rad
        assert sample.d_meas == first.d_meas and sample.c_meas == first.c_meas
        lidar.append(sample.lidar_m)
    # Carried by odometry, then measured with the held detection.
    np.testing.assert_allclose(lidar, PLATE[0] - 0.02 * np.arange(6), atol=0.01)
    assert perception.lidar.state.supported and perception.lidar.state.last_support_age_s == 0.0
    # A new frame runs the detector again.
    perception.process(np.zeros((120, 160, 3), np.uint8), DEPTH, None, speed=1.0, dt=0.02)
    assert detector.calls == 2


def test_a_held_frame_before_any_frame_has_no_detection():
    detector = CountingDetector()
    perception = Perception(CAMERA, detector=detector)
    for reset in (False, True):
        if reset:
            perception.process(np.zeros((120, 160, 3), np.uint8), DEPTH, _plate_scan(PLATE[0]))
            perception.reset()
        calls = detector.calls
        sample = perception.process(None, None, _plate_scan(PLATE[0]), new_frame=False)
        assert detector.calls == calls
        assert not sample.detected and math.isnan(sample.d_meas) and sample.c_meas == 0.0
        assert math.isnan(sample.bearing_rad) and math.isnan(sample.lidar_m)  # no detection: no track starts


def test_beam_ages_reach_the_tracker():
    perception = Perception(CAMERA, detector=CountingDetector())
    rgb = np.zeros((120, 160, 3), np.uint8)
    fresh = perception.process(rgb, DEPTH, _plate_scan(PLATE[0]), speed=1.0, beam_age_s=0.0).lidar_m
    perception.reset()
    aged = perception.process(rgb, DEPTH, _plate_scan(PLATE[0]), speed=1.0, beam_age_s=0.05).lidar_m
    assert fresh - aged == pytest.approx(0.05)
    with pytest.raises(ValueError, match="beam_age_s"):
        perception.process(rgb, DEPTH, _plate_scan(PLATE[0]), beam_age_s=-1.0)
