"""Drives: random routes that meet targets in order, the env's drive reset, and ground truth per target."""

import gymnasium as gym
import numpy as np
import pytest

from racf import sim  # noqa: F401  (registers the env)
from racf.controllers import RouteFollower
from racf.sim.world.route_plan import PASS_LINE_M
from racf.sim.world.drives import MIN_TARGET_AHEAD_M, draw_drive, estimate_duration_s, targets_on_path
from racf.sim.world.obstacles import obstacles
from racf.sim.world.road_graph import qcar2_road_graph
from racf.sim.world.stop_signs import POLE_ONLY, stop_signs

SMALL = {"camera_width": 80, "camera_height": 60}


def test_every_sign_and_crate_is_met_on_its_own_approach():
    for sign in stop_signs():
        found = targets_on_path(sign.path)
        assert [t.name for t in found] == [f"sign{sign.index}"]
        assert found[0].stop_s == pytest.approx(sign.stop_s, abs=0.02)
    crate = obstacles()[1]
    found = targets_on_path(crate.path, crate=1)
    assert found[-1].name == "obstacle1" and found[-1].target_s - found[-1].stop_s == pytest.approx(0.25, abs=0.02)
    assert targets_on_path(crate.path) == ()  # not placed: not met


def test_targets_carry_the_sign_geometry_and_are_met_where_they_were():
    for sign in stop_signs():
        default, pole = targets_on_path(sign.path), targets_on_path(sign.path, geometry=POLE_ONLY)
        assert [(t.name, t.stop_s, t.target_s) for t in pole] == [(t.name, t.stop_s, t.target_s) for t in default]
        assert pole[0].target is stop_signs(POLE_ONLY)[sign.index]
        assert pole[0].target.centre[2] == POLE_ONLY.centre_height_m


@pytest.mark.parametrize("seed", range(6))
def test_drawn_drives_meet_two_or_more_targets_in_order_and_differ_by_seed(seed):
    drive = draw_drive(np.random.default_rng(seed))
    assert drive == draw_drive(np.random.default_rng(seed))  # same seed, same drive
    assert drive != draw_drive(np.random.default_rng(seed + 100))
    path = qcar2_road_graph().route_path(list(drive.route))
    targets = targets_on_path(path, drive.crate, drive.start_s_m)
    assert len(targets) >= 2
    assert all(a.stop_s < b.stop_s for a, b in zip(targets, targets[1:]))
    assert targets[0].stop_s >= drive.start_s_m + MIN_TARGET_AHEAD_M
    assert abs(drive.lateral_offset_m) <= 0.03 and abs(np.degrees(drive.heading_error_rad)) <= 5
    assert 20 <= estimate_duration_s(path, drive.start_s_m, targets, drive.cruise_speed_mps) <= 60
    if drive.crate is not None:
        assert targets[-1].kind == "obstacle"  # the crate ends the drive


def test_nominal_speed_is_kept_within_ten_percent():
    for seed in range(5):
        v = draw_drive(np.random.default_rng(seed), nominal_speed_mps=1.5).cruise_speed_mps
        assert 1.35 <= v <= 1.65


def test_a_crate_right_ahead_of_the_start_is_refused():
    crate = obstacles()[0]
    with pytest.raises(ValueError, match="crate 0 stands"):
        targets_on_path(crate.path, crate=0, start_s=crate.stop_s - 1.0)


def test_env_drive_reset_places_the_car_and_switches_targets_once_passed():
    env = gym.make(sim.ENV_ID, **SMALL, max_episode_s=60)
    drive = draw_drive(np.random.default_rng(3))
    obs, info = env.reset(seed=0, options=drive.reset_options())
    u = env.unwrapped
    assert info["target_slot"] == 0 and len(u.route_targets) >= 2
    x, y, _ = u.route_path.pose_at(drive.start_s_m)
    assert np.hypot(info["pose"][0] - x, info["pose"][1] - y) == pytest.approx(abs(drive.lateral_offset_m), abs=1e-3)
    assert info["route_s"] == pytest.approx(drive.start_s_m, abs=0.01)
    first = u.route_targets[0]
    assert info["dist_to_stop_line"] == pytest.approx(first.stop_s - drive.start_s_m - 0.2125, abs=0.02)
    # Drive through the first stop line without stopping: the next target becomes current
    # once the bumper is PASS_LINE_M past it.
    p = u.route_path
    follower = RouteFollower(p.points, p.headings, p.arclength, p.curvature, 1.5)
    follower.reset(info["route_s"])
    while info["target_slot"] == 0:
        before = info["dist_to_stop_line"]
        obs, _, terminated, truncated, info = env.step(np.array(follower.act(*info["pose"], info["speed"], 0.02),
                                                                np.float32))
        assert not (terminated or truncated)
    assert before <= -PASS_LINE_M + 0.05
    assert info["target_sign"] == u.route_targets[1].target.index
    assert info["dist_to_stop_line"] == pytest.approx(u.route_targets[1].stop_s - info["route_s"] - 0.2125, abs=0.02)
    env.close()


def test_lidar_scans_at_10_hz_and_reports_when():
    env = gym.make(sim.ENV_ID, **SMALL)
    obs, info = env.reset(seed=1, options={"sign": 2})
    times, scans = [info["lidar_time"]], [obs["lidar"]]
    for _ in range(10):
        obs, *_, info = env.step(np.array([1.0, 0.0], np.float32))
        times.append(info["lidar_time"])
        scans.append(obs["lidar"])
    assert times == [0.0] * 5 + [0.1] * 5 + [0.2]
    assert np.array_equal(scans[1], scans[0]) and not np.array_equal(scans[5], scans[4])
    env.close()


@pytest.mark.parametrize("options, name", [
    ({"route": (0, 5)}, "not in the graph"),
    ({"route": "0,2"}, "route"),
    ({"route": (0, 2, 4), "sign": 1}, "do not combine"),
    ({"start_s_m": 1.0}, "need options\\['route'\\]"),
    ({"route": (0, 2, 4), "lateral_offset_m": 0.5}, "lateral_offset_m"),
    ({"route": (0, 2, 4), "heading_error_rad": 2.0}, "heading_error_rad"),
    ({"route": (0, 2, 4), "crate": 5}, "crate"),
    ({"route": (0, 2, 4), "start_s_m": 99.0}, "start_s_m"),
    ({"route": (12, 0)}, "meets no target"),
])
def test_bad_drive_options_are_named(options, name):
    env = gym.make(sim.ENV_ID, **SMALL)
    with pytest.raises(ValueError, match=name):
        env.reset(seed=0, options=options)
    env.close()
