"""A CUSUM residual detector over the depth camera against the LiDAR: an example racf defence.

Page's two-sided CUSUM accumulates the residual r = depth - LiDAR beyond a slack ``k_m``; once
either sum passes ``h_m`` the depth is declared attacked, and the defence drives on the LiDAR
(or, with no LiDAR return, on its last distance carried forward by odometry) until the
residual has stayed within the slack for ``recover_steps`` steps. Odometry alone is trusted
for ``max_carry_s`` at most: after that the defence has no distance (NaN), not a guess.

It implements racf's ``DistanceEstimator`` contract (``racf.controllers.DistanceEstimator``):
``name``, ``reset``, ``estimate``, ``diagnostics`` and ``would_pass``. Nothing here imports
the simulator: the defence sees what the car's perception hands it, in both worlds.
"""

from __future__ import annotations

import math

__all__ = ["CusumDefence"]


class CusumDefence:
    """CUSUM on the depth-LiDAR residual; the LiDAR (or odometry) replaces the depth on an alarm.

    Args:
        k_m: the slack, m: residuals within it count as noise.
        h_m: the alarm threshold of either cumulative sum, m.
        recover_steps: steps within the slack that clear an alarm.
        max_carry_s: how long the last distance is carried forward by odometry alone, s.
    """

    name = "lidar_cusum"

    def __init__(self, k_m: float = 0.05, h_m: float = 0.25, recover_steps: int = 10, max_carry_s: float = 1.0) -> None:
        if not (k_m >= 0 and h_m > 0 and recover_steps >= 1 and max_carry_s >= 0):
            raise ValueError(f"need k_m >= 0, h_m > 0, recover_steps >= 1, max_carry_s >= 0; got {k_m}, {h_m}, "
                             f"{recover_steps}, {max_carry_s}")
        self.k_m, self.h_m, self.recover_steps = float(k_m), float(h_m), int(recover_steps)
        self.max_carry_s = float(max_carry_s)
        self.reset()

    def reset(self) -> None:
        self.high = self.low = 0.0
        self.alarm = False
        self.quiet = 0
        self.last = math.nan  # the distance last put out, m
        self.lidar = math.nan  # the last LiDAR reference, m
        self.carried_s = 0.0  # how long the output has rested on odometry alone, s
        self.stepped = False

    def _sums(self, residual: float) -> tuple[float, float]:
        return (max(0.0, self.high + residual - self.k_m), max(0.0, self.low - residual - self.k_m))

    def estimate(self, sample, speed_mps: float, dt: float, yaw_rate_radps: float = 0.0) -> float:
        self.stepped = True
        depth, lidar = sample.d_meas, sample.lidar_m
        if math.isfinite(lidar):
            self.lidar = lidar
        if math.isfinite(depth) and math.isfinite(lidar):
            residual = depth - lidar
            self.high, self.low = self._sums(residual)
            if max(self.high, self.low) > self.h_m:
                self.alarm, self.quiet = True, 0
            elif self.alarm:
                self.quiet = self.quiet + 1 if abs(residual) <= self.k_m else 0
                if self.quiet >= self.recover_steps:
                    self.alarm, self.high, self.low = False, 0.0, 0.0
        self.carried_s = self.carried_s + dt if self.alarm and not math.isfinite(lidar) else 0.0
        if not self.alarm:
            out = depth
        elif math.isfinite(lidar):
            out = lidar
        elif self.carried_s <= self.max_carry_s and math.isfinite(self.last):
            out = max(self.last - speed_mps * dt, 0.0)  # no witness: the last distance, moved on by odometry
        else:
            out = math.nan
        self.last = out if math.isfinite(out) else self.last
        return out

    def diagnostics(self) -> dict[str, float]:
        return {"flag": float(self.alarm), "cusum_m": max(self.high, self.low)} if self.stepped else {}

    def would_pass(self, *, depth: float, speed_mps: float, dt: float, yaw_rate_radps: float = 0.0,
                   lidar_shift: float = 0.0) -> bool:
        if self.alarm:
            return False
        if not math.isfinite(self.lidar):
            return True
        expected = self.lidar - speed_mps * dt + lidar_shift
        return max(self._sums(depth - expected)) <= self.h_m
