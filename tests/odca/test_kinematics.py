"""The kinematic branch: exact on a straight approach, close on a curve, honest about its uncertainty."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from racf.odca import KinematicBranch, KinematicsConfig


@settings(max_examples=100, deadline=None)
@given(st.floats(0.5, 4.0), st.floats(-0.6, 0.6), st.lists(st.floats(0.0, 2.5), min_size=1, max_size=60))
def test_on_a_straight_approach_d_kin_falls_by_the_distance_driven_whatever_the_bearing(d0, bearing, speeds):
    branch = KinematicBranch(KinematicsConfig(max_std_m=10.0))
    branch.anchor(d0, bearing)
    for v in speeds:
        branch.predict(v, 0.0, 0.02)
    expected = d0 - 0.02 * sum(speeds)
    beside = abs(math.atan2(d0 * math.tan(bearing), expected)) > KinematicsConfig().max_bearing_rad
    if expected > 0 and not beside:
        assert branch.distance == pytest.approx(expected, abs=1e-9)
    else:
        assert not branch.alive  # the target is behind the camera, or the car is passing it: the branch is lost


def _camera_frame(point, pose, lever):
    """A world point in the camera frame (z forward, y left) of a car whose rear axle is at pose."""
    x, y, yaw = pose
    cx, cy = x + lever * math.cos(yaw), y + lever * math.sin(yaw)
    dx, dy = point[0] - cx, point[1] - cy
    return math.cos(yaw) * dx + math.sin(yaw) * dy, -math.sin(yaw) * dx + math.cos(yaw) * dy


@pytest.mark.parametrize("yaw_rate", [-0.9, -0.3, 0.4, 1.0])
def test_on_a_curve_d_kin_follows_the_geometry(yaw_rate):
    """A car on a circular arc (no slip at the rear axle) and a static sign: the branch's
    depth stays within a millimetre of the exact camera-frame depth."""
    cfg = KinematicsConfig(max_std_m=10.0)
    pose, v, dt = np.array([0.0, 0.0, 0.0]), 1.2, 0.02
    sign = (2.2, -0.45)
    z, y = _camera_frame(sign, pose, cfg.camera_lever_m)
    branch = KinematicBranch(cfg)
    branch.anchor(z, math.atan2(y, z))
    for _ in range(60):
        # Exact arc motion of the rear axle over dt.
        yaw = pose[2]
        pose = pose + np.array([v * dt * math.cos(yaw + yaw_rate * dt / 2), v * dt * math.sin(yaw + yaw_rate * dt / 2),
                                yaw_rate * dt])
        branch.predict(v, yaw_rate, dt)
        z, y = _camera_frame(sign, pose, cfg.camera_lever_m)
        if z < 0.2 or abs(math.atan2(y, z)) > cfg.max_bearing_rad:  # passed: the branch is lost by design
            break
        assert branch.distance == pytest.approx(z, abs=2e-3)


def test_uncertainty_grows_with_travel_and_time_and_the_branch_is_lost_past_its_bound():
    cfg = KinematicsConfig(anchor_std_m=0.03, travel_std=0.04, time_std_mps=0.01, max_std_m=0.2)
    branch = KinematicBranch(cfg)
    assert not branch.alive and math.isnan(branch.distance)
    branch.anchor(3.0)
    assert branch.std == cfg.anchor_std_m
    branch.predict(0.0, 0.0, 1.0)  # standing still: only time
    assert branch.std == pytest.approx(0.04)
    branch.predict(1.0, 0.0, 1.0)  # 1 m in 1 s
    assert branch.std == pytest.approx(0.09)
    assert branch.tolerance(0.1) == pytest.approx(0.1 + cfg.n_sigma * 0.09)
    for _ in range(3):
        branch.predict(1.0, 0.0, 1.0)
    assert not branch.alive  # std 0.23 > 0.2


def test_bad_settings_are_clear_errors():
    with pytest.raises(ValueError, match="travel_std"):
        KinematicsConfig(travel_std=-0.1)
    with pytest.raises(ValueError, match="max_std_m"):
        KinematicsConfig(max_std_m=float("nan"))
    with pytest.raises(ValueError, match="max_bearing_rad"):
        KinematicsConfig(max_bearing_rad=2.0)


@pytest.mark.parametrize("side", [-1.0, 1.0])
def test_the_branch_is_lost_once_the_car_has_passed_the_target(side):
    """Driving past a sign 0.4 m to the side: once its bearing passes the limit the branch (and
    at the next step its baseline) says nothing, so no later return beside the car re-anchors a
    point carried far to the side."""
    cfg = KinematicsConfig(max_std_m=10.0)
    branch = KinematicBranch(cfg)
    branch.anchor(2.0, math.atan2(side * 0.4, 2.0))
    steps = 0
    while branch.alive:
        assert abs(math.atan2(branch.y, branch.z)) <= cfg.max_bearing_rad
        branch.predict(1.5, 0.0, 0.02)
        steps += 1
    z_passed = 0.4 / math.tan(cfg.max_bearing_rad)
    assert 2.0 - 1.5 * 0.02 * steps == pytest.approx(z_passed, abs=0.03)  # lost as the bearing passed the limit
    free = KinematicBranch(KinematicsConfig(max_std_m=10.0, max_bearing_rad=None))
    free.anchor(2.0, math.atan2(side * 0.4, 2.0))
    for _ in range(steps):
        free.predict(1.5, 0.0, 0.02)
    assert free.alive  # without the limit: only once it is behind the camera


def test_the_baseline_is_anchored_once_and_moved_by_odometry_alone():
    b = KinematicBranch(KinematicsConfig())
    b.anchor(3.0, 0.0)
    for _ in range(10):
        b.predict(1.0, 0.0, 0.02)
    b.anchor(2.5)  # a re-anchor moves the branch, not the baseline
    assert b.distance == 2.5 and b.baseline == pytest.approx(2.8)
    tol = 0.1 + 3.0 * b.base_std
    assert not b.drifted(2.8 + 0.99 * tol, 0.1) and b.drifted(2.8 + 1.01 * tol, 0.1)
    assert not KinematicBranch(KinematicsConfig(drift_travel_std=None)).drifted(9.0, 0.1)  # no baseline


def test_only_a_confirmed_anchor_starts_the_baseline_and_it_is_lost_with_the_branch():
    b = KinematicBranch(KinematicsConfig())
    b.anchor(3.0, confirmed=False)  # a depth alone may already be corrupted: no baseline from it
    assert b.alive and math.isnan(b.baseline) and not b.drifted(9.0, 0.1)
    b.anchor(3.0, confirmed=True)  # no bearing: no place to start from
    assert math.isnan(b.baseline)
    b.anchor(3.0, 0.0, confirmed=True)
    assert b.baseline == 3.0
    while b.alive:  # the target unseen: the branch's std grows until it is lost
        b.predict(1.0, 0.5, 0.02)
    b.predict(1.0, 0.5, 0.02)  # the baseline goes at the next step (an anchor in between keeps it)
    assert math.isnan(b.baseline)  # a point carried through long unseen turns is not trusted
