"""Sensors: LiDAR ranges against walls and stop signs, camera depth at the sign, noise models, rates."""

from __future__ import annotations

import math

import gymnasium as gym
import mujoco
import numpy as np
import pytest

from racf import sim  # noqa: F401  (registers RACF/QCar2-v4)
from racf.sim.sensors import CameraConfig, Lidar2D, LidarConfig, RGBDCameraRig
from racf.sim.vehicle import QCar2
from racf.sim.world import map_facts
from racf.sim.world.scene import load_model
from racf.sim.world.stop_signs import stop_signs

LIDAR_BODY_X = -0.012
LIDAR_BODY_Z = 0.193
SMALL = {"camera_width": 160, "camera_height": 120}


@pytest.fixture(scope="module")
def world():
    model = load_model()
    data = mujoco.MjData(model)
    return model, data, QCar2(model)


def _place(world, x, y, yaw):
    model, data, car = world
    mujoco.mj_resetData(model, data)
    car.place(data, x, y, yaw)
    mujoco.mj_forward(model, data)
    return data


# -- LiDAR: walls -----------------------------------------------------------------------

D_WALL = 1.0
WALL_Y = 1.0  # no prop near the line y = 1.0 between x = 1.5 and the east wall


def _face_east_wall(world, distance):
    x_max = map_facts.WALL_BOUNDS_M[1]
    return _place(world, x_max - distance - LIDAR_BODY_X, WALL_Y, 0.0)


def test_lidar_site_where_the_facts_put_it(world):
    data = _face_east_wall(world, D_WALL)
    site = data.site("lidar").xpos
    assert site[2] == pytest.approx(LIDAR_BODY_Z, abs=2e-3)
    assert map_facts.WALL_BOUNDS_M[1] - site[0] == pytest.approx(D_WALL, abs=1e-3)
    assert site[1] == pytest.approx(WALL_Y, abs=1e-6)


def test_lidar_noise_free_range_to_wall(world):
    model, _, _ = world
    data = _face_east_wall(world, D_WALL)
    lidar = Lidar2D(LidarConfig(noise_rel=0.0, noise_floor_m=0.0))
    ranges = lidar.read(model, data, np.random.default_rng(0))
    assert ranges.shape == (360,) and ranges.dtype == np.float32
    assert ranges[0] == pytest.approx(D_WALL, abs=1e-3)
    # Beams are CCW from +x: 90 deg left (north wall), 270 deg right (south wall).
    site = data.site("lidar").xpos
    x0, x1, y0, y1 = map_facts.WALL_BOUNDS_M
    assert ranges[90] == pytest.approx(y1 - site[1], abs=1e-3)
    assert ranges[270] == pytest.approx(site[1] - y0, abs=1e-3)
    # A beam at +-10 deg hits the flat wall at D / cos(10 deg).
    for k in (10, 350):
        assert ranges[k] == pytest.approx(D_WALL / math.cos(math.radians(10)), abs=1e-3)
    # The map is enclosed: every beam returns, within the sensor's range.
    cfg = lidar.config
    assert np.isfinite(ranges).all()
    assert (ranges >= cfg.range_min_m).all() and (ranges <= cfg.range_max_m).all()
    diag = math.hypot(x1 - x0, y1 - y0)
    assert ranges.max() < diag


@pytest.mark.parametrize("distance", [0.5, 1.0, 2.0])
def test_lidar_noisy_range_to_wall_within_noise_model(world, distance):
    model, _, _ = world
    data = _face_east_wall(world, distance)
    cfg = LidarConfig()
    lidar = Lidar2D(cfg)
    sigma = max(cfg.noise_floor_m, cfg.noise_rel * distance)
    rng = np.random.default_rng(1234)
    reads = np.array([lidar.read(model, data, rng)[0] for _ in range(300)], dtype=float)
    assert np.isfinite(reads).all()
    assert np.abs(reads - distance).max() <= 4.5 * sigma
    # Unbiased, with the stated spread.
    assert abs(reads.mean() - distance) <= 4 * sigma / math.sqrt(len(reads))
    assert reads.std() == pytest.approx(sigma, rel=0.2)
    # A single reading is within 4 sigma.
    single = lidar.read(model, data, np.random.default_rng(5))[0]
    assert abs(single - distance) <= 4 * sigma


def test_lidar_beyond_range_max_is_inf(world):
    model, _, _ = world
    data = _face_east_wall(world, D_WALL)
    lidar = Lidar2D(LidarConfig(range_max_m=0.5, noise_rel=0.0, noise_floor_m=0.0))
    ranges = lidar.read(model, data, np.random.default_rng(0))
    assert np.isinf(ranges[0]) and ranges[0] > 0
    # Closer than range_max: a finite reading.
    data = _face_east_wall(world, 0.4)
    assert lidar.read(model, data, np.random.default_rng(0))[0] == pytest.approx(0.4, abs=1e-3)


def test_lidar_below_range_min_is_inf(world):
    model, _, _ = world
    data = _face_east_wall(world, 0.3)
    lidar = Lidar2D(LidarConfig(range_min_m=0.5, noise_rel=0.0, noise_floor_m=0.0))
    assert np.isinf(lidar.read(model, data, np.random.default_rng(0))[0])


def test_lidar_ignores_the_car_itself(world):
    model, _, _ = world
    data = _face_east_wall(world, D_WALL)
    lidar = Lidar2D(LidarConfig(noise_rel=0.0, noise_floor_m=0.0))
    # The rear beam would hit the car body (0.2 m behind the body origin) if the car were visible.
    assert lidar.read(model, data, np.random.default_rng(0))[180] > 1.0


def test_lidar_dropout_share(world):
    model, _, _ = world
    data = _face_east_wall(world, D_WALL)
    lidar = Lidar2D(LidarConfig(n_beams=1000, dropout=0.2))
    ranges = np.concatenate([lidar.read(model, data, np.random.default_rng(s)) for s in range(5)])
    assert np.mean(np.isinf(ranges)) == pytest.approx(0.2, abs=0.03)


@pytest.mark.parametrize("kwargs, name", [({"n_beams": 1}, "n_beams"), ({"range_max_m": 0.0}, "range_max_m"),
                                          ({"noise_rel": -1.0}, "noise_rel"), ({"dropout": 1.0}, "dropout"),
                                          ({"range_min_m": 5.0, "range_max_m": 4.0}, "range_min_m")])
def test_lidar_config_rejects_out_of_range(kwargs, name):
    with pytest.raises(ValueError, match=name):
        LidarConfig(**kwargs)


# -- LiDAR: stop signs ------------------------------------------------------------------

@pytest.mark.parametrize("index", [0, 2, 3])
@pytest.mark.parametrize("noise_free", [True, False])
def test_lidar_sees_stop_sign(world, index, noise_free):
    model, _, _ = world
    sign = stop_signs()[index]
    x, y, yaw = sign.path.pose_at(sign.stop_s - 1.0)
    data = _place(world, x, y, yaw)
    site = data.site("lidar").xpos.copy()
    expected = float(np.linalg.norm(np.asarray(sign.position) - site[:2]))
    bearing = math.atan2(sign.position[1] - site[1], sign.position[0] - site[0]) - yaw
    bearing = (bearing + math.pi) % (2 * math.pi) - math.pi
    assert abs(bearing) < math.radians(45)
    cfg = LidarConfig(noise_rel=0.0, noise_floor_m=0.0) if noise_free else LidarConfig()
    ranges = Lidar2D(cfg).read(model, data, np.random.default_rng(index))
    angles = (cfg.angles + math.pi) % (2 * math.pi) - math.pi
    near_bearing = np.abs(((angles - bearing) + math.pi) % (2 * math.pi) - math.pi) <= math.radians(3)
    tol = 0.02 if noise_free else 0.05
    assert np.any(np.abs(ranges[near_bearing] - expected) <= tol), (expected, ranges[near_bearing])


# -- Camera depth at the sign -----------------------------------------------------------

@pytest.fixture(scope="module")
def cam_env():
    e = gym.make("RACF/QCar2-v4", **SMALL)
    yield e
    e.close()


def _sign_centre_pixel(env):
    u = env.unwrapped
    cam_pos, cam_mat = u.car.camera_pose(u.model, u.data)
    # MuJoCo camera frame (x right, y up, looking along -z) -> optical (x right, y down, z forward).
    to_optical = np.diag([1.0, -1.0, -1.0]) @ cam_mat.T
    centre = to_optical @ (u.target_sign.centre - cam_pos)
    uv = u.rig.intrinsics.project(centre[None])[0]
    return centre, uv


@pytest.mark.parametrize("index, run_up", [(2, 0.5), (2, 1.0), (3, 0.5)])
def test_camera_depth_at_sign_centre(cam_env, index, run_up):
    u = cam_env.unwrapped
    obs, info = cam_env.reset(seed=11, options={"sign": index, "cruise_speed": 0.0, "run_up_m": run_up})
    centre, uv = _sign_centre_pixel(cam_env)
    d_true = info["d_true"]
    assert d_true == pytest.approx(centre[2], abs=1e-6)
    assert info["d_true_euclid"] == pytest.approx(float(np.linalg.norm(centre)), abs=1e-6)
    assert 0.3 < d_true < 2.0
    w, h = u.rig.intrinsics.width, u.rig.intrinsics.height
    col, row = int(round(uv[0])), int(round(uv[1]))
    assert 1 <= col < w - 1 and 1 <= row < h - 1, "sign centre outside the image"
    assert info["sign_in_view"] and info["sign_mask"][row, col]

    # Noise-free rendered depth at the centre pixel.
    _, clean = u.rig.render(u.model, u.data)
    assert clean[row, col] == pytest.approx(d_true, abs=0.01)

    # Observed (noisy) depth: median of a 3x3 window within 3 sigma + 1 cm.
    sigma = u.config.camera.depth_noise_k_per_m * d_true**2
    window = obs["depth"][row - 1:row + 2, col - 1:col + 2]
    valid = window[window > 0]
    assert valid.size >= 5
    assert abs(float(np.median(valid)) - d_true) <= 3 * sigma + 0.01

    # Median over the whole visible face, too (the face is small and nearly flat).
    face = obs["depth"][info["sign_mask"]]
    face = face[face > 0]
    assert abs(float(np.median(face)) - d_true) <= 3 * sigma + 0.02


@pytest.mark.parametrize("index, run_up", [(2, 0.5), (2, 1.0), (3, 0.5), (0, 0.5)])
def test_sign_mask_is_the_red_octagon(cam_env, index, run_up):
    obs, info = cam_env.reset(seed=0, options={"sign": index, "cruise_speed": 0.0, "run_up_m": run_up})
    mask = info["sign_mask"]
    assert mask.shape == obs["rgb"].shape[:2]
    assert mask.sum() >= 20
    rgb = obs["rgb"].astype(int)
    red = (rgb[..., 0] > 120) & (rgb[..., 0] > 2 * rgb[..., 1])
    # The red face covers 0.88^2 = 77 % of the octagon; the rest is the white border.
    assert red[mask].mean() >= 0.6
    # Almost every red pixel of the image near the sign is inside the mask.
    rows, cols = np.nonzero(mask)
    box = np.zeros_like(mask)
    box[max(rows.min() - 5, 0):rows.max() + 6, max(cols.min() - 5, 0):cols.max() + 6] = True
    assert (red & box & ~mask).sum() <= 0.1 * mask.sum()
    # Masked depth lies on the sign (well in front of the background wall).
    depth = obs["depth"][mask]
    depth = depth[depth > 0]
    assert np.all(np.abs(depth - np.median(depth)) < 0.15)


def test_every_signs_mask_belongs_to_the_held_frame(cam_env):
    """At 2 m/s the camera's 30 Hz frame is held over 50 Hz steps: the frame's masks, not masks
    from the pose now, are what the frame shows (a near sign moves pixels between the two)."""
    obs, info = cam_env.reset(seed=0, options={"sign": 0, "cruise_speed": 2.0, "run_up_m": 1.2})
    u = cam_env.unwrapped
    held = 0
    for _ in range(40):
        obs, _, terminated, truncated, info = cam_env.step(np.array([0.3, 0.0], np.float32))
        masks = u.frame_sign_masks()
        assert len(masks) == 4 and all(m.shape == obs["rgb"].shape[:2] for m in masks)
        assert np.array_equal(masks[info["target_sign"]], info["sign_mask"])
        held += u.sensor_observation()["timestamps"][0] < info["time"] - 1e-9
        if terminated or truncated:
            break
    assert held > 0  # some steps showed an older frame, and the masks still matched it


def test_sign_out_of_view_has_empty_mask(cam_env):
    # Sign 2 from 2 m: the car is still in the bend and the sign is outside the image.
    obs, info = cam_env.reset(seed=0, options={"sign": 2, "cruise_speed": 0.0, "run_up_m": 2.0})
    _, uv = _sign_centre_pixel(cam_env)
    w = cam_env.unwrapped.rig.intrinsics.width
    assert not 0 <= uv[0] < w, "test pose no longer has the sign outside the image"
    assert not info["sign_in_view"]
    assert not info["sign_mask"].any()


# -- Depth noise model ------------------------------------------------------------------

def test_depth_noise_std_scales_with_z_squared():
    rig = RGBDCameraRig(CameraConfig(width=320, height=240, depth_dropout=0.0, depth_noise_k_per_m=0.01))
    flat = np.full((240, 320), 2.0, np.float32)
    noisy = rig.noisy_depth(flat, np.random.default_rng(0))
    assert noisy.shape == flat.shape and noisy.dtype == np.float32
    assert noisy.std() == pytest.approx(0.01 * 2.0**2, rel=0.10)
    assert abs(noisy.mean() - 2.0) < 0.002
    assert (noisy > 0).all()
    # The input is left alone.
    assert (flat == 2.0).all()
    # 1 mm quantisation.
    assert np.allclose(noisy * 1000, np.round(noisy * 1000), atol=1e-2)
    # z^2: at 1 m the spread is a quarter.
    one = rig.noisy_depth(np.ones((240, 320), np.float32), np.random.default_rng(1))
    assert one.std() == pytest.approx(0.01, rel=0.10)


def test_depth_noise_is_normal_and_fresh_every_frame():
    from scipy import stats

    # No quantisation, so the draws themselves are visible: (noisy - z) / (k z^2).
    rig = RGBDCameraRig(CameraConfig(depth_dropout=0.0, depth_noise_k_per_m=0.01, depth_quantum_m=0.0))
    flat = np.full((240, 320), 3.0, np.float32)
    rng = np.random.default_rng(7)
    frames = [(rig.noisy_depth(flat, rng) - 3.0) / np.float32(0.01 * 9.0) for _ in range(4)]
    draws = np.concatenate([f.ravel() for f in frames]).astype(np.float64)
    assert stats.kstest(draws, "norm").pvalue > 0.01
    assert abs(stats.kurtosis(draws)) < 0.05
    # Consecutive frames do not repeat a pattern.
    assert abs(np.corrcoef(frames[0].ravel(), frames[1].ravel())[0, 1]) < 0.02


def test_depth_out_of_range_is_zero():
    cfg = CameraConfig(depth_dropout=0.0)
    rig = RGBDCameraRig(cfg)
    far = rig.noisy_depth(np.full((120, 160), 20.0, np.float32), np.random.default_rng(0))
    assert (far == 0).all()
    near = rig.noisy_depth(np.full((120, 160), 0.1, np.float32), np.random.default_rng(0))
    assert (near == 0).all()
    ok = rig.noisy_depth(np.full((120, 160), 1.0, np.float32), np.random.default_rng(0))
    assert (ok > 0).all()


@pytest.mark.parametrize("dropout", [0.005, 0.1, 0.3])
def test_depth_dropout_share(dropout):
    rig = RGBDCameraRig(CameraConfig(depth_dropout=dropout, depth_noise_k_per_m=0.0))
    noisy = rig.noisy_depth(np.full((480, 640), 1.5, np.float32), np.random.default_rng(3))
    share = float(np.mean(noisy == 0))
    # Drawn positions may repeat, so the share is at most the configured value.
    assert share == pytest.approx(dropout, rel=0.15, abs=0.002)
    assert np.all((noisy == 0) | (np.abs(noisy - 1.5) < 1e-6))


def test_noise_free_depth_is_exact_but_quantised():
    rig = RGBDCameraRig(CameraConfig(depth_dropout=0.0, depth_noise_k_per_m=0.0))
    depth = np.linspace(0.5, 5.0, 160 * 120, dtype=np.float32).reshape(120, 160)
    out = rig.noisy_depth(depth, np.random.default_rng(0))
    assert np.abs(out - depth).max() <= 0.0005 + 1e-6


@pytest.mark.parametrize("kwargs, name", [({"width": 5}, "width"), ({"depth_dropout": 1.0}, "depth_dropout"),
                                          ({"depth_noise_k_per_m": -1.0}, "depth_noise_k_per_m"),
                                          ({"depth_min_m": 3.0, "depth_max_m": 2.0}, "depth_min_m")])
def test_camera_config_rejects_out_of_range(kwargs, name):
    with pytest.raises(ValueError, match=name):
        CameraConfig(**kwargs)


def test_intrinsics_scale_with_resolution():
    big = RGBDCameraRig(CameraConfig(width=640, height=480)).intrinsics
    small = RGBDCameraRig(CameraConfig(width=160, height=120)).intrinsics
    assert (big.fx, big.fy, big.cx, big.cy) == pytest.approx((455.2, 459.4, 308.5, 213.6))
    assert (small.fx, small.fy, small.cx, small.cy) == pytest.approx((455.2 / 4, 459.4 / 4, 308.5 / 4, 213.6 / 4))


# -- Sensor rates -----------------------------------------------------------------------

def test_sensor_rates_hold_readings():
    e = gym.make("RACF/QCar2-v4", lidar_hz=10, camera_hz=25, **SMALL)
    try:
        obs0, _ = e.reset(seed=0, options={"sign": 3, "cruise_speed": 1.0, "run_up_m": 2.0})
        seq = [obs0]
        for _ in range(10):
            obs, *_ = e.step(np.array([1.0, 0.0], np.float32))
            seq.append(obs)
        lidar = [o["lidar"] for o in seq]
        depth = [o["depth"] for o in seq]
        state = [o["state"] for o in seq]
        # LiDAR at 10 Hz with 50 Hz control: new reading at steps 0, 5, 10; held in between.
        for k in range(1, 5):
            assert np.array_equal(lidar[k], lidar[0]), f"lidar changed at step {k}"
            assert np.array_equal(lidar[5 + k], lidar[5]), f"lidar changed at step {5 + k}"
        assert not np.array_equal(lidar[5], lidar[0])
        assert not np.array_equal(lidar[10], lidar[5])
        # Camera at 25 Hz: new reading every second step.
        for k in range(0, 10, 2):
            assert np.array_equal(depth[k + 1], depth[k]), f"depth changed at step {k + 1}"
            assert np.array_equal(seq[k + 1]["rgb"], seq[k]["rgb"])
            assert not np.array_equal(depth[k + 2], depth[k]), f"depth not updated at step {k + 2}"
        # State at the default 50 Hz: new every step while moving.
        for k in range(1, 11):
            assert not np.array_equal(state[k], state[k - 1])
    finally:
        e.close()


# -- Camera: rendered image agrees with the declared intrinsics --------------------------

@pytest.mark.parametrize("size", [(640, 480), (160, 120)])
def test_rendered_depth_matches_intrinsics(size):
    """Back-projects noise-free depth of known planes (the floor, the east wall) through the
    declared intrinsics and recovers the principal point to a tenth of a pixel."""
    w, h = size
    model = load_model()
    data = mujoco.MjData(model)
    car = QCar2(model)
    rig = RGBDCameraRig(CameraConfig(width=w, height=h))
    rig.configure_model(model)
    k = rig.intrinsics
    try:
        # Floor (z = 0) seen from a level camera: depth z at row v gives v - cy = cam_h * fy / z.
        car.place(data, -1.9, -1.0, math.pi / 2)
        mujoco.mj_forward(model, data)
        cam_pos, _ = car.camera_pose(model, data)
        _, depth = rig.render(model, data)
        rows = np.arange(int(k.cy) + h // 8, h - 2)
        z = depth[rows, int(k.cx)].astype(float)
        implied_cy = np.median(rows - cam_pos[2] * k.fy / z)

        # East wall (x = X0) seen at 20 deg: solve each pixel's ray for its x slope.
        x_wall = map_facts.WALL_BOUNDS_M[1]
        car.place(data, 1.8, 1.0, math.radians(20))
        mujoco.mj_forward(model, data)
        cam_pos, cam_mat = car.camera_pose(model, data)
        r = cam_mat @ np.diag([1.0, -1.0, -1.0])  # optical -> world
        _, depth = rig.render(model, data)
        v = int(k.cy) + h // 24
        cols = np.arange(w // 4, 3 * w // 4)
        z = depth[v, cols].astype(float)
        b = (v - k.cy) / k.fy
        a = ((x_wall - cam_pos[0]) / z - b * r[0, 1] - r[0, 2]) / r[0, 0]
        implied_cx = np.median(cols - a * k.fx)
    finally:
        rig.close()
    assert implied_cy == pytest.approx(k.cy, abs=0.1)
    assert implied_cx == pytest.approx(k.cx, abs=0.1)
