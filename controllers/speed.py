"""Speed along a route: a curvature speed limit, a PI speed loop and a bound on the car's true speed.

The limit keeps lateral acceleration within what the tyres and the lane follower handle
(at 2 m/s the map's 0.62 m arcs would need 6.4 m/s^2) and slows down ahead of curves at
a comfortable deceleration. The PI loop turns the reference into the speed command the
car's motor controller receives, removing the steady-state error of its own P loop.

:class:`SpeedBound` is an upper bound on the car's own true speed. The encoder reads the wheels,
which spin up and lock faster than the body can follow (per step -25 % to +170 % of the body's
speed under a hard brake); the body's speed changes no faster than the tyres' grip, so the bound
is the encoder's reading with its error, or the last bound less what the grip can take off in a
step, whichever is higher. What plans a stop on the car's speed (the braker, the supervisor's
stop rule and its carried target) reads it: planned on a locked wheel's reading, a stop creeps.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["SpeedProfile", "SpeedPIConfig", "SpeedPI", "SpeedBound", "GRIP_MPS2"]

#: The tyres' grip, m/s^2 (friction 0.75 x g): the body's speed changes no faster.
GRIP_MPS2 = 0.75 * 9.81


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


class SpeedBound:
    """An upper bound on the car's true speed from its encoder (see the module).

    Args:
        error: the encoder's relative error the bound allows above its reading.
        grip_mps2: the most the body's speed can fall in a second.
    """

    def __init__(self, error: float = 0.02, grip_mps2: float = GRIP_MPS2) -> None:
        self.error, self.grip_mps2 = float(error), float(grip_mps2)
        self.reset()

    def reset(self) -> None:
        self.bound_mps = math.nan

    def step(self, encoder_mps: float, dt: float) -> float:
        """This step's bound, m/s. A reading that is no number tells nothing: the bound falls at the grip."""
        reading = max(encoder_mps, 0.0) * (1.0 + self.error) if math.isfinite(encoder_mps) else 0.0
        if not math.isfinite(self.bound_mps):
            self.bound_mps = reading
        else:
            self.bound_mps = max(reading, self.bound_mps - self.grip_mps2 * dt)
        return self.bound_mps
