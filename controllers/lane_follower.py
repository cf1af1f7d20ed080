"""Stanley lane following along a lane-centre polyline, with a speed PI loop.

Pure numpy: the route arrives as arrays (x, y, heading per point), the car's pose and
speed as numbers; nothing here knows the simulator. Quanser's reference controller is
Stanley with k = 1 and a PI speed loop (Kp 0.1, Ki 1); ours commands speed directly, so
the PI loop shapes a speed command rather than a motor duty.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from racf.controllers.speed import SpeedPI, SpeedPIConfig, SpeedProfile

__all__ = ["StanleyConfig", "StanleyController", "RouteFollower"]


@dataclass(frozen=True)
class StanleyConfig:
    """Stanley gains.

    Attributes:
        k: cross-track gain (1/s in the atan2(k e, v) term).
        softening_mps: added to the speed so the law stays gentle near standstill.
        max_steer_rad: steering limit.
        front_axle_m: body origin to the front axle along x (half the wheelbase).
    """

    k: float = 1.0
    softening_mps: float = 0.3
    max_steer_rad: float = math.radians(30.0)
    front_axle_m: float = 0.128

    def __post_init__(self) -> None:
        if not 0.0 < self.k <= 20.0:
            raise ValueError(f"k must be in (0, 20], got {self.k}")
        if not 0.0 <= self.softening_mps <= 5.0:
            raise ValueError(f"softening_mps must be in [0, 5] m/s, got {self.softening_mps}")
        if not 0.0 < self.max_steer_rad <= math.radians(45):
            raise ValueError(f"max_steer_rad must be in (0, 0.785] rad, got {self.max_steer_rad}")


class StanleyController:
    """Steering from the front axle's heading and cross-track error to a polyline.

    Args:
        points: (N, 2) lane-centre points, metres.
        headings: (N,) heading of travel at each point, radians.
        config: gains.
    """

    def __init__(self, points: np.ndarray, headings: np.ndarray, config: StanleyConfig | None = None) -> None:
        points, headings = np.asarray(points, float), np.asarray(headings, float)
        if points.ndim != 2 or points.shape[1] != 2 or len(points) < 2 or headings.shape != (len(points),):
            raise ValueError(f"need points (N>=2, 2) and headings (N,), got {points.shape} and {headings.shape}")
        self.points, self.headings = points, headings
        self.config = config or StanleyConfig()
        self._index = 0

    def reset(self, s: float | None = None, arclength: np.ndarray | None = None) -> None:
        """Forget the last match; with ``s`` and the route's ``arclength``, start the search there."""
        self._index = 0 if s is None or arclength is None else int(np.searchsorted(arclength, s))

    @property
    def index(self) -> int:
        """Index of the route point last matched to the front axle."""
        return self._index

    def steer(self, x: float, y: float, yaw: float, speed: float) -> float:
        """Steering angle (rad, left positive) for a car at pose (x, y, yaw) and ``speed`` m/s."""
        c = self.config
        front = np.array([x + c.front_axle_m * math.cos(yaw), y + c.front_axle_m * math.sin(yaw)])
        # Search forward from the last match only: routes may pass near themselves.
        lo, hi = max(0, self._index - 20), min(len(self.points), self._index + 200)
        k = lo + int(np.argmin(((self.points[lo:hi] - front) ** 2).sum(axis=1)))
        self._index = k
        heading = self.headings[k]
        rel = front - self.points[k]
        lateral = -math.sin(heading) * rel[0] + math.cos(heading) * rel[1]  # left positive
        heading_err = (heading - yaw + math.pi) % (2 * math.pi) - math.pi
        delta = heading_err + math.atan2(-c.k * lateral, abs(speed) + c.softening_mps)
        return float(np.clip(delta, -c.max_steer_rad, c.max_steer_rad))


class RouteFollower:
    """Drives a route: Stanley steering, a curvature speed limit and the PI speed loop.

    Args:
        points, headings, arclength, curvature: the route's (N,) / (N, 2) arrays.
        cruise_mps: speed on straights, m/s.
        stanley, speed_pi: gains.
        max_lateral_accel_mps2: the curve speed limit's lateral acceleration bound. 2 m/s^2:
            with 3, a 2 m/s car runs wide out of the map's S-bends (the steering servo
            lags 0.16 s) and meets the wall.
    """

    def __init__(self, points: np.ndarray, headings: np.ndarray, arclength: np.ndarray, curvature: np.ndarray,
                 cruise_mps: float, stanley: StanleyConfig | None = None, speed_pi: SpeedPIConfig | None = None,
                 max_lateral_accel_mps2: float = 2.0) -> None:
        if not 0.0 <= cruise_mps <= 10.0:
            raise ValueError(f"cruise_mps must be in [0, 10] m/s, got {cruise_mps}")
        self.steering = StanleyController(points, headings, stanley)
        self.profile = SpeedProfile(arclength, curvature, max_lateral_accel_mps2)
        self.speed_loop = SpeedPI(speed_pi)
        self.cruise_mps = float(cruise_mps)

    def reset(self, start_s: float | None = None) -> None:
        """Forget the past; ``start_s`` (m along the route) is where the car starts."""
        self.steering.reset(start_s, self.profile.arclength)
        self.speed_loop.reset()

    @property
    def progress_m(self) -> float:
        """Arclength of the route point last matched to the front axle, m (the car's own localisation)."""
        return float(self.profile.arclength[self.steering.index])

    def act(self, x: float, y: float, yaw: float, speed: float, dt: float,
            speed_cap_mps: float = float("inf")) -> tuple[float, float]:
        """(speed command m/s, steering rad) for the car's pose and speed.

        ``speed_cap_mps`` lowers the reference (the braking controller's profile).
        """
        steer = self.steering.steer(x, y, yaw, speed)
        s = self.profile.arclength[self.steering.index]
        reference = min(self.profile.at(s, self.cruise_mps), speed_cap_mps)
        return self.speed_loop.command(reference, speed, dt), steer
