"""A two-sided CUSUM (Page's test) on the depth's normalised innovation against the witness
(the LiDAR, else odometry): S+ = max(0, S+ + z - k), S- = max(0, S- - z - k); an alarm when
either passes ``h``. ``score`` is max(S+, S-) / h (> 1: ``flag``). While alarmed, the defence
drives on the witness; the alarm clears after ``recover_steps`` innovations within the slack.
"""

from __future__ import annotations


from racf.controllers.baselines.witness import Witness, valid

__all__ = ["CusumDetector"]


class CusumDetector:
    """Two-sided CUSUM on the depth's innovation; the witness replaces the depth on an alarm.

    Args:
        k: the slack, in innovation standard deviations.
        h: the alarm threshold of either sum.
        recover_steps: innovations within the slack that clear an alarm.
        depth_std_m: depth noise at full confidence, m.
        lidar_std_m, drift_per_m, max_carry_s: the witness's (:class:`Witness`).
    """

    name = "cusum"
    n_parameters = 0  # hand-set slack and threshold: nothing trained

    def __init__(self, k: float = 0.5, h: float = 8.0, recover_steps: int = 10, depth_std_m: float = 0.03,
                 lidar_std_m: float = 0.03, drift_per_m: float = 0.02, max_carry_s: float = 1.5) -> None:
        if not (k >= 0 and h > 0 and isinstance(recover_steps, int) and recover_steps >= 1 and depth_std_m > 0):
            raise ValueError(f"need k >= 0, h > 0, an int recover_steps >= 1, depth_std_m > 0; got {k!r}, {h!r}, "
                             f"{recover_steps!r}, {depth_std_m!r}")
        self.k, self.h, self.recover_steps, self.depth_std_m = float(k), float(h), recover_steps, float(depth_std_m)
        self.witness = Witness(lidar_std_m, drift_per_m, max_carry_s)
        self.reset()

    def reset(self) -> None:
        self.witness.reset()
        self.high = self.low = 0.0
        self.alarm, self.quiet, self._stepped = False, 0, False

    def _sums(self, z: float) -> tuple[float, float]:
        return max(0.0, self.high + z - self.k), max(0.0, self.low - z - self.k)

    @property
    def score(self) -> float:
        return max(self.high, self.low) / self.h

    def estimate(self, sample, speed_mps: float, dt: float, yaw_rate_radps: float = 0.0) -> float:
        self._stepped = True
        depth, lidar = sample.d_meas, sample.lidar_m
        reference, ref_std = self.witness.predict(lidar, speed_mps, dt)
        if valid(depth) and valid(reference):
            z = self.witness.innovation(depth, sample.c_meas, self.depth_std_m, reference, ref_std)
            self.high, self.low = self._sums(z)
            if self.score > 1.0:
                self.alarm, self.quiet = True, 0
            elif self.alarm:
                self.quiet = self.quiet + 1 if abs(z) <= self.k else 0
                if self.quiet >= self.recover_steps:
                    self.alarm, self.high, self.low = False, 0.0, 0.0
        return self.witness.step_output(depth, reference, self.alarm, lidar, speed_mps, dt)

    def diagnostics(self) -> dict[str, float]:
        return {"flag": float(self.alarm), "score": self.score} if self._stepped else {}

    def would_pass(self, *, depth: float, speed_mps: float, dt: float, yaw_rate_radps: float = 0.0,
                   lidar_shift: float = 0.0) -> bool:
        if self.alarm:
            return False
        reference, ref_std = self.witness.next_reference(speed_mps, dt, lidar_shift)
        if not (valid(depth) and valid(reference)):
            return True
        return max(self._sums(self.witness.innovation(depth, 1.0, self.depth_std_m, reference, ref_std))) <= self.h
