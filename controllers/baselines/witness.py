"""The witness a residual detector tests the depth against: the LiDAR's distance when it
reports, else the last distance put out, moved on by the car's odometry (a one-step prediction),
for at most ``max_carry_s``. Its standard deviation grows with the distance travelled since the
LiDAR last reported, as odometry drifts."""

from __future__ import annotations

import math

__all__ = ["Witness", "valid"]


def valid(x: float) -> bool:
    """A usable distance: finite and positive (anything else counts as missing)."""
    return isinstance(x, (int, float)) and math.isfinite(x) and x > 0


class Witness:
    """The reference distance and its std, step by step.

    Args:
        lidar_std_m: the LiDAR's noise, m.
        drift_per_m: odometry's added std per metre travelled since the last LiDAR report.
        max_carry_s: how long a distance is carried by odometry alone.
    """

    def __init__(self, lidar_std_m: float = 0.03, drift_per_m: float = 0.02, max_carry_s: float = 1.5) -> None:
        if not (lidar_std_m > 0 and drift_per_m >= 0 and max_carry_s >= 0):
            raise ValueError(f"need lidar_std_m > 0, drift_per_m >= 0, max_carry_s >= 0; got {lidar_std_m}, "
                             f"{drift_per_m}, {max_carry_s}")
        self.lidar_std_m, self.drift_per_m, self.max_carry_s = lidar_std_m, drift_per_m, max_carry_s
        self.reset()

    def reset(self) -> None:
        self.last = math.nan  # the last distance put out, m
        self.lidar = math.nan  # the last LiDAR report, m
        self.travelled_m = 0.0  # since the last LiDAR report
        self.carried_s = 0.0  # how long the output has rested on odometry alone

    def predict(self, lidar: float, speed_mps: float, dt: float) -> tuple[float, float]:
        """This step's reference and its std (NaN, NaN: none), from ``lidar`` or the last output."""
        if valid(lidar):
            return float(lidar), self.lidar_std_m
        if not valid(self.last) or self.carried_s + dt > self.max_carry_s:
            return math.nan, math.nan
        moved = abs(speed_mps) * dt if math.isfinite(speed_mps) else 0.0
        return max(self.last - moved, 0.0), self.lidar_std_m + self.drift_per_m * (self.travelled_m + moved)

    def innovation(self, depth: float, confidence: float, depth_std_m: float, reference: float,
                   ref_std: float) -> float:
        """The depth's innovation against ``reference`` in standard deviations; low confidence
        (clipped at 0.05) widens the depth's share."""
        conf = min(1.0, max(0.05, confidence if math.isfinite(confidence) else 0.0))
        return (depth - reference) / math.sqrt(depth_std_m ** 2 / conf + ref_std ** 2)

    def next_reference(self, speed_mps: float, dt: float, lidar_shift: float = 0.0) -> tuple[float, float]:
        """The next step's reference as a white-box attacker predicts it: the LiDAR (if it
        reported this step) moved by the car's motion and ``lidar_shift``, else the odometry
        carry. Changes nothing."""
        lidar = (self.lidar - abs(speed_mps) * dt + lidar_shift if valid(self.lidar) and self.travelled_m == 0.0
                 else math.nan)
        return self.predict(lidar, speed_mps, dt)

    def step_output(self, depth: float, reference: float, alarmed: bool, lidar: float, speed_mps: float,
                    dt: float) -> float:
        """What the defence puts out this step (the depth, or the witness while alarmed or with no
        depth; NaN with neither), with the witness moved on."""
        on_witness = alarmed or not valid(depth)
        out = reference if on_witness else float(depth)
        out = out if valid(out) else math.nan
        self.advance(lidar, speed_mps, dt, out, on_odometry=on_witness and not valid(lidar))
        return out

    def advance(self, lidar: float, speed_mps: float, dt: float, output: float, on_odometry: bool) -> None:
        """Moves on one step: ``output`` is what the defence put out, ``on_odometry`` whether it
        rested on the odometry-carried witness."""
        moved = abs(speed_mps) * dt if math.isfinite(speed_mps) else 0.0
        self.travelled_m = 0.0 if valid(lidar) else self.travelled_m + moved
        self.lidar = float(lidar) if valid(lidar) else self.lidar
        self.carried_s = self.carried_s + dt if on_odometry else 0.0
        self.last = output if valid(output) else self.last
