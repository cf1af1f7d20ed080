"""Vehicle state as the car itself measures it: motor encoder speed, servo angle, IMU.

The speed comes from the motor encoder: whole counts over the interval since the previous
reading, so it is quantised (one count is about 6.9 um of travel). The gyro and the
accelerometer carry a zero-rate offset drawn per episode and white noise at their datasheet
densities (TDK IIM-42652). No sensor on the car measures lateral speed, so there is none.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from racf.sim.sensors.base import Sensor, SensorRate, check_range
from racf.sim.vehicle.qcar2 import QCar2

__all__ = ["OdometryConfig", "VehicleStateSensor", "STATE_FIELDS"]

#: Order of the entries of the ``state`` observation (units in the names).
STATE_FIELDS = ("speed_mps", "steering_rad", "yaw_rate_radps", "accel_mps2")

_WHEELS = ("wheel_fl", "wheel_fr", "wheel_rl", "wheel_rr")


@dataclass(frozen=True)
class OdometryConfig:
    """Encoder and IMU error model (SI units).

    Attributes:
        m_per_count: travel per encoder count: 720 counts/rev (2880 in quadrature) on the
            motor, 0.01977 m of travel per motor revolution.
        gyro_noise_density: gyro white noise, rad/s/sqrt(Hz) (0.0038 deg/s/sqrt(Hz)).
        gyro_bias_max: zero-rate offset bound, rad/s; drawn per episode U(-max, max).
        accel_noise_density: accelerometer white noise, m/s^2/sqrt(Hz) (70 ug/sqrt(Hz)).
        accel_bias_max: accelerometer offset bound, m/s^2 (20 mg); drawn per episode.
        exact: True gives the noise-free state (no quantisation, noise or bias).
    """

    m_per_count: float = 0.01977 / 2880
    gyro_noise_density: float = math.radians(0.0038)
    gyro_bias_max: float = math.radians(0.5)
    accel_noise_density: float = 70e-6 * 9.81
    accel_bias_max: float = 0.020 * 9.81
    exact: bool = False

    def __post_init__(self) -> None:
        check_range("m_per_count", self.m_per_count, 0.0, 0.01, low_open=True)
        for name, high in (("gyro_noise_density", 0.1), ("gyro_bias_max", 1.0), ("accel_noise_density", 1.0),
                           ("accel_bias_max", 10.0)):
            check_range(name, getattr(self, name), 0.0, high)
        if not isinstance(self.exact, bool):
            raise ValueError(f"exact must be True or False, got {self.exact!r}")


class VehicleStateSensor(Sensor):
    """(4,) float32, see ``STATE_FIELDS``: encoder speed, steering, gyro yaw rate, longitudinal accel.

    Args:
        car: the car measured.
        config: encoder and IMU errors; default ``OdometryConfig()``.
        rate_hz: reading rate; sets the noise std (density * sqrt(rate)) and the first
            reading's quantisation interval.

    ``reset(rng)`` draws the episode's gyro and accelerometer offsets and forgets the previous
    encoder count; a ``read`` before any ``reset`` resets from its own generator first.
    """

    name = "state"
    dtype = np.float32
    low, high = -np.inf, np.inf
    shape = (len(STATE_FIELDS),)

    def __init__(self, car: QCar2, config: OdometryConfig | None = None, rate_hz: float = 50.0) -> None:
        self.car = car
        self.config = config or OdometryConfig()
        self.rate_hz = SensorRate(rate_hz).rate_hz
        self._wheel_qpos = np.array([car.model.joint(w).qposadr[0] for w in _WHEELS])
        self._gyro_bias = 0.0
        self._accel_bias = 0.0
        self._was_reset = False
        self._prev: tuple[int, float] | None = None  # (encoder count, time) of the previous read
        self._speed = 0.0

    def reset(self, rng: np.random.Generator) -> None:
        """Draws the gyro then the accelerometer offset (exact: draws nothing)."""
        cfg = self.config
        self._was_reset, self._prev, self._speed = True, None, 0.0
        if cfg.exact:
            self._gyro_bias = self._accel_bias = 0.0
            return
        self._gyro_bias = float(rng.uniform(-cfg.gyro_bias_max, cfg.gyro_bias_max))
        self._accel_bias = float(rng.uniform(-cfg.accel_bias_max, cfg.accel_bias_max))

    def read(self, model, data, rng: np.random.Generator) -> np.ndarray:
        s = self.car.state(data)
        cfg = self.config
        if cfg.exact:
            return np.array([s.speed, s.steering, s.yaw_rate, s.accel], np.float32)
        if not self._was_reset:
            self.reset(rng)
        speed = self._encoder_speed(data, s.speed)
        sigma = math.sqrt(self.rate_hz)
        noise = rng.standard_normal(2) * (cfg.gyro_noise_density * sigma, cfg.accel_noise_density * sigma)
        return np.array([speed, s.steering, s.yaw_rate + self._gyro_bias + noise[0],
                         s.accel + self._accel_bias + noise[1]], np.float32)

    def _encoder_speed(self, data, true_speed: float) -> float:
        """Whole counts since the previous read over its interval; the first read quantises the true speed."""
        m = self.config.m_per_count
        travel = float(np.mean(data.qpos[self._wheel_qpos])) * self.car.wheel_radius_m
        count, now = math.floor(travel / m), float(data.time)
        if self._prev is not None and now == self._prev[1]:
            return self._speed  # read twice at one time: the same reading
        if self._prev is None or now < self._prev[1]:  # first read, or time restarted without a reset
            dt = 1.0 / self.rate_hz
            self._speed = round(true_speed * dt / m) * m / dt
        else:
            self._speed = (count - self._prev[0]) * m / (now - self._prev[1])
        self._prev = (count, now)
        return self._speed
