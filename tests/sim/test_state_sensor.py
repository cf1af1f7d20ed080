"""The state sensor as the car measures it: encoder quantisation, IMU offsets and noise, exact mode."""

from __future__ import annotations

import math

import gymnasium as gym
import mujoco
import numpy as np
import pytest

from racf import sim
from racf.sim.sensors import STATE_FIELDS, OdometryConfig, VehicleStateSensor
from racf.sim.vehicle import QCar2
from racf.sim.world.scene import load_model

RATE_HZ = 50.0
DT = 1.0 / RATE_HZ
M_PER_COUNT = 0.01977 / 2880
SPEED, YAW_RATE, ACCEL = (STATE_FIELDS.index(f) for f in ("speed_mps", "yaw_rate_radps", "accel_mps2"))


@pytest.fixture(scope="module")
def world():
    model = load_model()
    return model, mujoco.MjData(model), QCar2(model)


def _at_rest(world):
    model, data, car = world
    mujoco.mj_resetData(model, data)
    car.place(data, 1.0, 1.101, math.pi)
    mujoco.mj_forward(model, data)
    return data


def _imu_errors(world, sensor, rng, n):
    """(n, 2) yaw-rate and accel readings minus the true ones, the car standing still."""
    model, data, car = world
    data = _at_rest(world)
    exact = VehicleStateSensor(car, OdometryConfig(exact=True)).read(model, data, rng)
    reads = np.array([sensor.read(model, data, rng) for _ in range(n)], np.float64)
    return reads[:, [YAW_RATE, ACCEL]] - exact[[YAW_RATE, ACCEL]]


def test_fields_are_what_the_car_measures():
    assert STATE_FIELDS == ("speed_mps", "steering_rad", "yaw_rate_radps", "accel_mps2")
    assert VehicleStateSensor.shape == (4,)


def test_imu_offsets_bounded_fixed_per_episode_and_redrawn(world):
    cfg = OdometryConfig()
    sensor = VehicleStateSensor(world[2], cfg, rate_hz=RATE_HZ)
    means = []
    for seed in (0, 0, 1, 2):
        rng = np.random.default_rng(seed)
        sensor.reset(rng)
        err = _imu_errors(world, sensor, rng, 400)
        first, second = err[:200].mean(axis=0), err[200:].mean(axis=0)
        tol = 5 * np.array([cfg.gyro_noise_density, cfg.accel_noise_density]) * math.sqrt(RATE_HZ) / math.sqrt(200)
        assert (np.abs(first - second) < 2 * tol).all()  # one offset for the whole episode
        mean = err.mean(axis=0)
        assert abs(mean[0]) <= cfg.gyro_bias_max + tol[0] and abs(mean[1]) <= cfg.accel_bias_max + tol[1]
        means.append(mean)
    np.testing.assert_array_equal(means[0], means[1])  # same seed, same offsets
    assert (np.abs(means[2] - means[3]) > 0.01 * np.array([cfg.gyro_bias_max, cfg.accel_bias_max])).all()


@pytest.mark.parametrize("rate_hz", [50.0, 200.0])
def test_imu_noise_std_follows_the_density(world, rate_hz):
    cfg = OdometryConfig()
    sensor = VehicleStateSensor(world[2], cfg, rate_hz=rate_hz)
    rng = np.random.default_rng(3)
    sensor.reset(rng)
    err = _imu_errors(world, sensor, rng, 2000)
    want = np.array([cfg.gyro_noise_density, cfg.accel_noise_density]) * math.sqrt(rate_hz)
    np.testing.assert_allclose(err.std(axis=0), want, rtol=0.08)


def _drive(world, sensor, rng, n, speed=1.0, steer=0.0):
    """Reads while the car drives; returns (readings, true speeds, wheel travel at each read)."""
    model, data, car = world
    mujoco.mj_resetData(model, data)
    car.place(data, 1.0, 1.101, math.pi, speed=speed)
    mujoco.mj_forward(model, data)
    wheels = [model.joint(w).qposadr[0] for w in ("wheel_fl", "wheel_fr", "wheel_rl", "wheel_rr")]
    reads, true, travel = [], [], []
    for _ in range(n):
        reads.append(sensor.read(model, data, rng))
        true.append(car.state(data).speed)
        travel.append(np.mean(data.qpos[wheels]) * car.wheel_radius_m)
        car.apply(data, speed, steer)
        mujoco.mj_step(model, data, nstep=round(DT / model.opt.timestep))
    return np.array(reads, np.float64), np.array(true), np.array(travel)


def test_encoder_speed_is_whole_counts_per_interval(world):
    sensor = VehicleStateSensor(world[2], rate_hz=RATE_HZ)
    rng = np.random.default_rng(4)
    sensor.reset(rng)
    reads, true, travel = _drive(world, sensor, rng, 40)
    counts = reads[:, SPEED] * DT / M_PER_COUNT
    np.testing.assert_allclose(counts, np.round(counts), atol=2e-3)  # the first read too
    assert reads[0, SPEED] == pytest.approx(true[0], abs=M_PER_COUNT / DT)
    np.testing.assert_allclose(reads[:, SPEED], true, rtol=0.01)
    # Quantisation does not accumulate: the counts add up to the wheels' travel within one count.
    assert abs(np.sum(counts[1:]) - (travel[-1] - travel[0]) / M_PER_COUNT) <= 1.0 + 1e-6


def test_exact_mode_is_the_true_state_without_draws(world):
    model, _, car = world
    sensor = VehicleStateSensor(car, OdometryConfig(exact=True))
    rng = np.random.default_rng(5)
    sensor.reset(rng)
    reads, _, _ = _drive(world, sensor, rng, 3, speed=0.7, steer=0.2)
    data = world[1]
    s = car.state(data)
    out = sensor.read(model, data, rng)
    assert out.dtype == np.float32 and out.shape == (4,)
    np.testing.assert_allclose(out, [s.speed, s.steering, s.yaw_rate, s.accel], rtol=1e-6, atol=1e-7)
    assert rng.random() == np.random.default_rng(5).random()  # nothing drawn


@pytest.mark.parametrize("field, value", [
    ("m_per_count", 0.0), ("gyro_noise_density", -1.0), ("gyro_bias_max", math.inf),
    ("accel_noise_density", 2.0), ("accel_bias_max", -0.1), ("exact", 1),
])
def test_bad_config_names_the_field(field, value):
    with pytest.raises(ValueError, match=field):
        OdometryConfig(**{field: value})


def test_encoder_agrees_with_true_speed_in_the_env():
    env = gym.make(sim.ENV_ID, camera_width=80, camera_height=60)
    try:
        env.reset(seed=0, options={"sign": 0, "cruise_speed": 1.0})
        u = env.unwrapped
        sensor = VehicleStateSensor(u.car)
        rng = np.random.default_rng(6)
        sensor.reset(rng)
        enc, true = [], []
        for _ in range(40):  # about 0.8 m straight on, before the car leaves the curving lane
            _, _, terminated, _, _ = env.step(np.array([1.0, 0.0], np.float32))
            assert not terminated
            enc.append(sensor.read(u.model, u.data, rng)[SPEED])
            true.append(u.car.state(u.data).speed)
    finally:
        env.close()
    np.testing.assert_allclose(enc, true, rtol=0.01)  # wheel slip here is about 0.2 %
    assert np.mean(enc) == pytest.approx(1.0, rel=0.01)
