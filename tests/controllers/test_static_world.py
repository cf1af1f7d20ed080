"""The static-world check: a depth that runs from what the car's own motion predicts is caught
(racf.controllers.static_world), on depth images ray-cast from a small scene: a wall, and a
0.10 m plate standing in front of it."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from racf.controllers import CameraModel
from racf.controllers.static_world import (CameraPose, StaticWorldCheck, StaticWorldConfig, pixels_to_world,
                                           world_to_camera)

CAMERA = CameraModel(width=320, fx=227.6, cx=154.25, fy=229.7, cy=106.8)
SHAPE = (240, 320)
FRAME_S = 1 / 30
WALL_X, PLATE = 6.0, np.array([3.0, 0.0, 0.25])  # the wall's plane x = 6; the plate's centre


def _render(pose: CameraPose, plate_bias_m: float = 0.0) -> np.ndarray:
    """The depth along the optical axis of the wall x = WALL_X and the plate (plane x = 3, 0.10 m
    square), with the plate's pixels read ``plate_bias_m`` further."""
    v, u = np.mgrid[0:SHAPE[0], 0:SHAPE[1]] + 0.5
    left, up = (CAMERA.cx - u) / CAMERA.fx, (CAMERA.cy - v) / CAMERA.fy  # per metre ahead
    c, s = math.cos(pose.yaw_rad), math.sin(pose.yaw_rad)
    dx, dy = c - s * left, s + c * left  # the ray's map-frame direction per metre ahead
    with np.errstate(divide="ignore", invalid="ignore"):
        wall = np.where(dx > 0, (WALL_X - pose.x_m) / dx, np.inf)
        t = (PLATE[0] - pose.x_m) / dx
        hit_y, hit_z = pose.y_m + t * dy, pose.height_m + t * up
        on_plate = (dx > 0) & (np.abs(hit_y - PLATE[1]) <= 0.05) & (np.abs(hit_z - PLATE[2]) <= 0.05) & (t < wall)
    depth = np.where(on_plate, t + plate_bias_m, wall)
    return np.where(np.isfinite(depth), depth, 0.0).astype(np.float32)


def _plate_pixels(pose: CameraPose):
    rows, cols, _ = world_to_camera(PLATE[None, :], CAMERA, pose)
    r, c = int(round(rows[0])), int(round(cols[0]))
    rr, cc = np.mgrid[r - 2:r + 3, c - 2:c + 3]
    return rr.ravel(), cc.ravel()


def _drive(check, speed=1.5, yaw_rate=0.0, offset_m=0.0, bias_rate=0.0, frames=20, jump_at=None, jump_m=0.05,
           ramp_from=0, every=1):
    """Approaches the plate from 2 m before it, turning at ``yaw_rate``, its depth read further at
    ``bias_rate`` from frame ``ramp_from``, the check fed every ``every`` frames; returns ``check.moving``."""
    x, y, yaw = PLATE[0] - 2.0, offset_m, 0.0
    for k in range(frames * every):
        t = k * FRAME_S
        if k % every == 0:
            pose = CameraPose(x, y, 0.17, yaw)
            depth = _render(pose, bias_rate * max(t - ramp_from * FRAME_S, 0.0))
            believed = CameraPose(x + (jump_m if jump_at is not None and k >= jump_at else 0.0), y, 0.17, yaw)
            check.observe(t, depth, CAMERA, believed, *_plate_pixels(believed))
        x += speed * FRAME_S * math.cos(yaw)
        y += speed * FRAME_S * math.sin(yaw)
        yaw += yaw_rate * FRAME_S
    return check.moving


def test_pixels_carried_to_the_map_and_back_land_where_they_were():
    pose = CameraPose(1.0, -0.5, 0.17, 0.3)
    rows, cols = np.array([10, 120, 200]), np.array([30, 160, 300])
    points = pixels_to_world(rows, cols, np.array([1.0, 2.5, 4.0]), CAMERA, pose)
    r, c, ahead = world_to_camera(points, CAMERA, pose)
    assert np.allclose(r, rows) and np.allclose(c, cols) and np.allclose(ahead, [1.0, 2.5, 4.0])


@settings(max_examples=12, deadline=None)
@given(st.floats(0.5, 2.0), st.floats(-0.6, 0.6), st.floats(-0.2, 0.2))
def test_a_world_that_stands_still_is_never_caught(speed, yaw_rate, offset_m):
    assert not _drive(StaticWorldCheck(), speed, yaw_rate, offset_m)


@settings(max_examples=12, deadline=None)
@given(st.floats(1.5, 6.0), st.floats(0.5, 2.0), st.floats(-0.4, 0.4))
def test_a_plate_read_further_and_further_is_caught(bias_rate, speed, yaw_rate):
    check = StaticWorldCheck()
    assert _drive(check, speed, yaw_rate, bias_rate=bias_rate)
    assert check.rate_mps == pytest.approx(bias_rate, rel=0.1)


def test_a_slow_drift_and_a_localisation_jump_are_not_caught():
    assert not _drive(StaticWorldCheck(), bias_rate=0.5)  # slower than the rate
    assert not _drive(StaticWorldCheck(), jump_at=8)  # a fix moves the car's pose 5 cm once
    # A 0.4 m fix: the window's fit runs faster than the rate, but it jumps, it does not run in a line.
    assert not _drive(StaticWorldCheck(), jump_at=8, jump_m=0.4)


def test_a_ramp_that_begins_late_is_judged_on_the_window_not_the_whole_approach():
    assert _drive(StaticWorldCheck(), speed=0.5, bias_rate=3.0, ramp_from=30, frames=45)


def test_a_few_frames_far_apart_are_not_enough():
    check = StaticWorldCheck()
    assert not _drive(check, bias_rate=3.0, frames=4, every=3)  # 4 frames over 0.3 s: under min_frames


def test_a_place_at_the_picture_s_edge_is_read_where_it_is_in_the_picture():
    check = StaticWorldCheck()
    pose = CameraPose(0.0, 0.0, 0.17, 0.0)
    rows, cols = np.array([-3, 100, 239, 240]), np.array([5, 319, 0, -1])
    check.observe(0.0, _render(pose), CAMERA, pose, rows, cols)
    assert len(check._points) == 2


def test_once_caught_the_depth_stays_outvoted_until_reset():
    check = StaticWorldCheck()
    assert _drive(check, bias_rate=3.0)
    assert _drive(check)  # the ramp stopped: the depth has not earned trust back
    check.reset()
    assert not check.moving and not _drive(check)


@pytest.mark.parametrize("field, value", [("rate_mps", 0.0), ("window_s", -1.0), ("min_frames", 2),
                                          ("residual_m", "a"), ("min_span_s", 1.0), ("min_points", 0)])
def test_bad_settings_are_refused(field, value):
    with pytest.raises(ValueError, match=field):
        StaticWorldConfig(**{field: value})
