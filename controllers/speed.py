"""Speed along a route: a curvature speed limit and a PI speed loop.

The limit keeps lateral acceleration within what the tyres and the lane follower handle
(at 2 m/s the map's 0.62 m arcs would need 6.4 m/s^2) and slows down ahead of curves at
a comfortable deceleration. The PI loop turns the reference into the speed command the
car's motor controller receives, removing the steady-state error of its own P loop.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["SpeedProfile", "SpeedPIConfig", "SpeedPI"]


class SpeedProfile:
    """Highest speed at each arclength of a route, for a given cruise speed.

    Args:
        arclength: (N,) increasing arclength of the route's points, metres.
        curvature: (N,) signed curvature at the points, 1/m.
        max_lateral_accel_mps2: bound on v^2 |kappa|.
        max_decel_mps2: deceleration used to slow down ahead of a curve.
    """

    def __init__(self, arclength: np.ndarray, curvature: np.ndarray, max_lateral_accel_mps2: float = 3.0,
                 max_decel_mps2: float = 2.0) -> None:
        s, k = np.asarray(arclength, float), np.abs(np.asarray(curvature, float))
        if s.ndim != 1 or s.shape != k.shape or len(s) < 2 or np.any(np.diff(s) <= 0):
            raise ValueError(f"need increasing arclength (N>=2,) and curvature of the same shape, got {s.shape}, {k.shape}")
        if not (max_lateral_accel_mps2 > 0 and max_decel_mps2 > 0):
            raise ValueError("max_lateral_accel_mps2 and max_decel_mps2 must be > 0 m/s^2, got "
                             f"{max_lateral_accel_mps2} and {max_decel_mps2}")
        limit = np.sqrt(max_lateral_accel_mps2 / np.maximum(k, 1e-9))
        # Backward pass: v(s)^2 <= v(s')^2 + 2 a (s' - s) for every s' ahead.
        for i in range(len(s) - 2, -1, -1):
            limit[i] = min(limit[i], np.sqrt(limit[i + 1] ** 2 + 2 * max_decel_mps2 * (s[i + 1] - s[i])))
        self.arclength, self.limit = s, limit

    def at(self, s: float, cruise_mps: float) -> float:
        """Speed reference (m/s) at arclength ``s`` for a car cruising at ``cruise_mps``."""
        i = int(np.clip(np.searchsorted(self.arclength, s), 0, len(self.limit) - 1))
        return float(min(cruise_mps, self.limit[i]))


@dataclass(frozen=True)
class SpeedPIConfig:
    """Gains of the speed loop.

    Attributes:
        kp: proportional gain (command m/s per m/s of error).
        ki: integral gain (1/s).
        integral_limit_mps: bound on the integral term's contribution, m/s.
        max_command_mps: highest speed command.
    """

    kp: float = 0.3
    ki: float = 1.0
    integral_limit_mps: float = 0.3
    max_command_mps: float = 3.0

    def __post_init__(self) -> None:
        for name in ("kp", "ki", "integral_limit_mps"):
            if not 0.0 <= getattr(self, name) <= 20.0:
                raise ValueError(f"{name} must be in [0, 20], got {getattr(self, name)}")
        if not 0.0 < self.max_command_mps <= 10.0:
            raise ValueError(f"max_command_mps must be in (0, 10] m/s, got {self.max_command_mps}")


class SpeedPI:
    """Feed-forward reference plus PI on the speed error; never commands reverse."""

    def __init__(self, config: SpeedPIConfig | None = None) -> None:
        self.config = config or SpeedPIConfig()
        self._integral = 0.0

    def reset(self) -> None:
        self._integral = 0.0

    def command(self, reference_mps: float, speed_mps: float, dt: float) -> float:
        """Speed command (m/s) to track ``reference_mps`` from the measured ``speed_mps``."""
        c = self.config
        if reference_mps <= 0.0:
            # Stopping: command zero outright and forget the integral (no creeping).
            self._integral = 0.0
            return 0.0
        error = reference_mps - speed_mps
        self._integral = float(np.clip(self._integral + c.ki * error * dt, -c.integral_limit_mps, c.integral_limit_mps))
        return float(np.clip(reference_mps + c.kp * error + self._integral, 0.0, c.max_command_mps))
