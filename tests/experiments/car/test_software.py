"""The car's side: it works from its calibration and the map, never from the simulator."""

import ast
import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from racf.controllers import CameraModel
from racf.experiments.car import software as car
from racf.experiments.car.software import CarCalibration, map_bearing, sign_depth_at_line

CAL = CarCalibration(CameraModel(width=320, fx=230.0, cx=160.0), camera_xy_m=(0.2, 0.0), bumper_x_m=0.25,
                     rear_axle_x_m=-0.128, lidar_xy_m=(-0.012, 0.0))


def _sign(x, y, face_yaw=math.pi):
    return SimpleNamespace(target=SimpleNamespace(centre=np.array([x, y, 0.3]), face_yaw=face_yaw),
                           target_s=5.0, stop_s=4.6)


def test_bearing_is_from_the_camera_left_positive_and_nan_behind_the_face():
    assert map_bearing(CAL, _sign(3.0, 0.0), np.array([0.0, 0.0, 0.0])) == pytest.approx(0.0)
    assert map_bearing(CAL, _sign(2.2, 2.0), np.array([0.0, 0.0, 0.0])) == pytest.approx(math.pi / 4)
    # Turned 90 deg left, the camera is at (0, 0.2): a sign straight ahead of it is at bearing 0.
    assert map_bearing(CAL, _sign(0.0, 3.0, -math.pi / 2), np.array([0.0, 0.0, math.pi / 2])) == pytest.approx(0.0)
    assert math.isnan(map_bearing(CAL, _sign(3.0, 0.0, face_yaw=0.0), np.array([0.0, 0.0, 0.0])))


def test_depth_at_the_line_is_the_camera_to_bumper_gap_plus_the_line_to_sign_gap():
    assert sign_depth_at_line(CAL, _sign(3.0, 0.0)) == pytest.approx(0.05 + 0.4)


def test_the_car_module_does_not_reach_into_the_simulator():
    tree = ast.parse(Path(car.__file__).read_text())
    imported = {alias.name for node in ast.walk(tree) if isinstance(node, ast.Import) for alias in node.names}
    imported |= {node.module for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)}
    assert not any(m.startswith(("gymnasium", "mujoco", "racf.sim.env")) for m in imported), imported
    assert "info" not in {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}
