"""Vehicle state as the car's own software knows it (encoder speed, servo angle, IMU)."""

from __future__ import annotations

import numpy as np

from sim.sensors.base import Sensor
from sim.vehicle.qcar2 import QCar2

__all__ = ["VehicleStateSensor", "STATE_FIELDS"]

#: Order of the entries of the ``state`` observation (units in the names).
STATE_FIELDS = ("speed_mps", "steering_rad", "yaw_rate_radps", "accel_mps2", "lateral_speed_mps")


class VehicleStateSensor(Sensor):
    """(5,) float32: see ``STATE_FIELDS``. Noise-free: the car's encoders and IMU are good."""

    name = "state"
    dtype = np.float32
    low, high = -np.inf, np.inf
    shape = (len(STATE_FIELDS),)

    def __init__(self, car: QCar2) -> None:
        self.car = car

    def read(self, model, data, rng: np.random.Generator) -> np.ndarray:
        s = self.car.state(data)
        return np.array([s.speed, s.steering, s.yaw_rate, s.accel, s.lateral_speed], np.float32)
