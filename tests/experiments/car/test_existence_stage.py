"""The existence stage's static-world check: the pixels of the map's plate and where the camera stood,
from the car's own pose (racf.experiments.car.existence)."""

import copy
import math
from types import SimpleNamespace

import numpy as np
import pytest

from racf.controllers.existence import Hypothesis
from racf.experiments.car.existence import ExistenceStage, camera_pose
from racf.experiments.episode.plan import car_calibration

CALIB = car_calibration(320, 240)
PLATE = np.array([3.0, 0.1, 0.25])  # the map's sign: its plate's centre in the map's frame
WALL_X = 6.0


def _camera(pose):
    x, y, yaw = pose
    cx, cy = CALIB.camera_xy_m
    return x + math.cos(yaw) * cx - math.sin(yaw) * cy, y + math.sin(yaw) * cx + math.cos(yaw) * cy, yaw


def _frame(pose, bias_m):
    """The depth the camera shows from ``pose``: a wall at x = 6, the 0.10 m plate read ``bias_m`` further."""
    cam = CALIB.camera
    x, y, yaw = _camera(pose)
    v, u = np.mgrid[0:240, 0:320] + 0.5
    left, up = (cam.cx - u) / cam.fx, (cam.cy - v) / cam.fy
    dx, dy = math.cos(yaw) - math.sin(yaw) * left, math.sin(yaw) + math.cos(yaw) * left
    wall, t = (WALL_X - x) / dx, (PLATE[0] - x) / dx
    on = (np.abs(y + t * dy - PLATE[1]) <= 0.05) & (np.abs(CALIB.camera_height_m + t * up - PLATE[2]) <= 0.05)
    return np.where(on, t + bias_m, wall).astype(np.float32)


def _place(pose):
    """The map's plate as the stage's hypothesis puts it, from the car's pose."""
    x, y, yaw = _camera(pose)
    dx, dy = PLATE[0] - x, PLATE[1] - y
    ahead, left = math.cos(yaw) * dx + math.sin(yaw) * dy, -math.sin(yaw) * dx + math.cos(yaw) * dy
    cam = CALIB.camera
    rows = tuple(int(round(cam.cy - cam.fy * (PLATE[2] - CALIB.camera_height_m + dz) / ahead)) for dz in (0.05, -0.05))
    return Hypothesis(math.atan2(left, ahead), ahead, 0.35, math.atan2(0.15, ahead), "map", rows)


def _approach(bias_rate):
    stage = ExistenceStage(CALIB)
    for k in range(15):
        t = k / 30
        pose = (1.0 + 1.5 * t, 0.0, 0.05 * t)
        stage._check_static(t, _frame(pose, bias_rate * t), np.array(pose), _place(pose))
    return stage.static.moving


def test_a_plate_that_stands_still_passes_and_one_read_further_and_further_is_caught():
    assert not _approach(0.0)
    assert _approach(3.0)


def test_the_camera_stands_at_its_mount_on_the_car_turned_with_it():
    x, y, height, yaw = (camera_pose(CALIB, np.array([1.0, 2.0, math.pi / 2])).__dict__[k]
                         for k in ("x_m", "y_m", "height_m", "yaw_rad"))
    forward, left = CALIB.camera_xy_m
    assert (x, y) == pytest.approx((1.0 - left, 2.0 + forward)) and height == CALIB.camera_height_m
    assert yaw == pytest.approx(math.pi / 2)


def test_a_depth_caught_moving_is_a_witness_until_the_next_target():
    from racf.controllers import PerceptionSample
    from racf.experiments.episode import TrialSpec
    from racf.experiments.episode.plan import plan_episode

    sign = plan_episode(TrialSpec("clean+vote", 0, 1.0, 0)).mission.targets[0]
    stage = ExistenceStage(CALIB)
    primary = SimpleNamespace(last_raw_detection=None)
    nothing = PerceptionSample(None, math.nan, 0.0, math.nan, math.nan)
    frame = (np.zeros((240, 320, 3), np.uint8), np.full((240, 320), 5.0, np.float32), np.full(360, np.inf))

    def observe(target):
        return stage.observe(*frame, target, np.zeros(3), 2.0, primary, nothing, t_s=0.0)

    observe(sign)
    stage.static.moving = True
    assert observe(sign).moving  # caught: a witness while the car approaches this sign
    assert not observe(copy.copy(sign)).moving  # the next target starts with nothing caught
