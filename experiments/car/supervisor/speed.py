"""Speeds the supervisor may rely on, from the car's own witnesses only.

- :class:`RangeRate`: the target's speed along the lane, measured from the vouched chain's readings
  plus the car's own travel (its encoder): a target's position in the car's travel frame is its
  reading plus how far the car went, and its speed is that position's slope over the last
  ``window_s``. Measured once the readings span ``span_s`` and the slope is known to
  ``max_std_mps``: then a hidden target's reach is its last measured speed, not its top speed.

The car's own speed is bounded by :class:`racf.controllers.speed.SpeedBound` (the braker reads it
too): the stop rule and the carried target's near end use it.
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np

__all__ = ["RangeRate"]


class RangeRate:
    """The target's speed from the vouched readings and the car's own travel (see the module)."""

    def __init__(self, window_s: float = 0.6, span_s: float = 0.3, max_std_mps: float = 0.1) -> None:
        self.window_s, self.span_s, self.max_std_mps = float(window_s), float(span_s), float(max_std_mps)
        self.reset()

    def reset(self) -> None:
        self._t = 0.0
        self._travel = 0.0
        self._points: deque[tuple[float, float]] = deque()

    def restart(self) -> None:
        """A new chain: its readings may be of another target, so the slope starts again."""
        self._points.clear()

    def step(self, ego_mps: float, dt: float, vouched_m: float) -> None:
        """One control step: the car's encoder speed (m/s), the period (s) and this step's vouched
        reading (m; NaN: none)."""
        self._t += dt
        self._travel += max(ego_mps, 0.0) * dt
        if math.isfinite(vouched_m):
            self._points.append((self._t, vouched_m + self._travel))
        while self._points and self._points[0][0] < self._t - self.window_s:
            self._points.popleft()

    def estimate(self) -> tuple[float, bool]:
        """The target's speed (m/s, >= 0: targets do not reverse) and whether it is measured."""
        if len(self._points) < 4:
            return math.nan, False
        t, x = np.array(self._points).T
        if t[-1] - t[0] < self.span_s:
            return math.nan, False
        tc = t - t.mean()
        slope = float(tc @ (x - x.mean()) / (tc @ tc))
        residual = x - x.mean() - slope * tc
        std = math.sqrt(float(residual @ residual) / max(len(t) - 2, 1) / float(tc @ tc))
        return max(slope, 0.0), std <= self.max_std_mps
