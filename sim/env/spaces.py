"""The env's observation and action spaces, from its sensors and the car's limits."""

from __future__ import annotations

import numpy as np
from gymnasium import spaces

from racf.sim.radio import RADIO_SLOTS, SIGNED_BYTES
from racf.sim.sensors import TIMESTAMP_FIELDS

__all__ = ["env_spaces"]


def env_spaces(sensors, lidar_shape: tuple[int, ...], vehicle) -> tuple[spaces.Dict, spaces.Box]:
    """The observation (each sensor's reading, the LiDAR's per-bin times, each reading's timestamp, the
    radio's messages received this step and when each arrived) and the action ([speed command m/s, steering rad] within the car's limits)."""
    observation = spaces.Dict({
        **{s.name: spaces.Box(low=s.low, high=s.high, shape=s.shape, dtype=s.dtype) for s in sensors},
        "lidar_beam_times": spaces.Box(low=0.0, high=np.inf, shape=lidar_shape, dtype=np.float64),
        "timestamps": spaces.Box(low=0.0, high=np.inf, shape=(len(TIMESTAMP_FIELDS),), dtype=np.float64),
        "radio": spaces.Box(low=0, high=255, shape=(RADIO_SLOTS * SIGNED_BYTES,), dtype=np.uint8),
        "radio_times": spaces.Box(low=0.0, high=np.inf, shape=(RADIO_SLOTS,), dtype=np.float64)})
    action = spaces.Box(low=np.array([-vehicle.max_reverse_mps, -vehicle.max_steer_rad], np.float32),
                        high=np.array([vehicle.max_speed_mps, vehicle.max_steer_rad], np.float32), dtype=np.float32)
    return observation, action
