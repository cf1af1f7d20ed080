"""The one contract every sensor follows: a space, ``reset(rng)`` per episode and ``read(model, data, rng)``."""

from __future__ import annotations

import math
import numbers
from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np

__all__ = ["Sensor", "SensorRate", "TIMESTAMP_FIELDS", "check_range"]

#: The entries of the env's ``timestamps`` observation: when each sensor's held reading was
#: taken, s (a sensor between readings holds its last one and its time).
TIMESTAMP_FIELDS = ("rgb", "depth", "lidar", "gps", "state")


def check_range(name: str, value: float, low: float, high: float, low_open: bool = False) -> None:
    """ValueError naming ``name`` and its interval unless ``value`` is a finite real number in it."""
    ok = isinstance(value, numbers.Real) and not isinstance(value, bool) and math.isfinite(value)
    if not ok or value > high or value < low or (low_open and value == low):
        interval = f"{'(' if low_open else '['}{low}, {high}]"
        raise ValueError(f"{name} must be in {interval}, got {value!r}")


@dataclass(frozen=True)
class SensorRate:
    """How often a sensor produces a new reading; between readings the last one is held.

    Attributes:
        rate_hz: readings per second; at most the control rate.
    """

    rate_hz: float = 50.0

    def __post_init__(self) -> None:
        if not (np.isfinite(self.rate_hz) and self.rate_hz > 0):
            raise ValueError(f"rate_hz must be a positive number, got {self.rate_hz}")


class Sensor(ABC):
    """A sensor of the car.

    Subclasses set ``space`` (a ``gymnasium.spaces.Box``-compatible description is built by
    the env from ``shape``, ``dtype``, ``low`` and ``high``) and implement ``read``.
    """

    #: Observation key.
    name: str
    shape: tuple[int, ...]
    dtype: type
    low: float
    high: float

    @abstractmethod
    def read(self, model, data, rng: np.random.Generator) -> np.ndarray:
        """One reading of the sensor at the current simulation state.

        Args:
            model: ``mujoco.MjModel``.
            data: ``mujoco.MjData`` after ``mj_forward``/``mj_step``.
            rng: the generator all the sensor's noise is drawn from.
        """

    def reset(self, rng: np.random.Generator) -> None:
        """Per-episode draws (biases, drift); the default draws nothing."""

    def close(self) -> None:
        """Releases resources (GL contexts); reading after close re-creates them."""
