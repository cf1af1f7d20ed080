"""Following the car ahead: a constant time-headway policy, an emergency brake on time-to-collision,
and the lead's speed estimated from the car's own track.

Scaled to the 1/10 car in space, not in time: the policy keeps ``standstill_gap_m`` (0.25 m, a
2.5 m gap at full scale) plus ``time_headway_s`` (1 s) of the car's own speed, so the speed it
allows is ``(gap - standstill) / headway``; the emergency brake asks for a full stop once the
time-to-collision (the gap over the closing speed) falls under ``ttc_brake_s`` (0.8 s, within
the 0.6-1.2 s of production AEB), or the gap under the standstill gap's half.

The closing speed is the car's own speed less the lead's, and the lead's speed is what the car
estimates (:class:`LeadSpeed`): from its own track of the distance, while its witnesses agree
(the camera's depth and the LiDAR's track within ``agree_m``), and carried while they disagree,
so that an attack on one witness cannot teach the car a lead that runs away. Before any
estimate it is 0: a target of unknown motion is taken to stand still, as a stop sign does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["FollowingConfig", "LeadSpeed", "LeadFollower", "FollowDecision"]


@dataclass(frozen=True)
class FollowingConfig:
    """The following controller's settings.

    Attributes:
        time_headway_s: the policy's time headway, s.
        standstill_gap_m: the gap it keeps at rest, m.
        ttc_brake_s: the emergency brake's time-to-collision threshold, s.
        agree_m: the witnesses agree when within this, m (the track learns the lead's speed then).
        alpha, beta: the range tracker's gains per new frame (position and rate).
        confirm_frames: agreeing frames before the lead's speed is used (0 before).
        gate_m: an agreeing range this far off the track's prediction starts the track again
            (the car ahead was out of sight, or another car took its place).
        max_lead_mps: the fastest lead the estimate allows, m/s (the QCar 2's top speed).
        speed_std_mps: how far a confirmed estimate may be off, m/s (one std; before it is
            confirmed the lead may be anywhere from standing to ``max_lead_mps``).
    """

    time_headway_s: float = 1.0
    standstill_gap_m: float = 0.25
    ttc_brake_s: float = 0.8
    agree_m: float = 0.1
    alpha: float = 0.4
    beta: float = 0.08
    confirm_frames: int = 6
    gate_m: float = 0.25
    max_lead_mps: float = 3.0
    speed_std_mps: float = 0.1

    def __post_init__(self) -> None:
        for name, lo, hi in (("time_headway_s", 0.1, 5.0), ("standstill_gap_m", 0.0, 2.0), ("ttc_brake_s", 0.0, 5.0),
                             ("agree_m", 0.0, 2.0), ("alpha", 0.0, 1.0), ("beta", 0.0, 1.0), ("gate_m", 0.0, 5.0),
                             ("max_lead_mps", 0.0, 10.0), ("speed_std_mps", 0.0, 5.0)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not lo <= value <= hi:
                raise ValueError(f"{name} must be in [{lo}, {hi}], got {value!r}")
        if isinstance(self.confirm_frames, bool) or not isinstance(self.confirm_frames, int) or self.confirm_frames < 0:
            raise ValueError(f"confirm_frames must be an int >= 0, got {self.confirm_frames!r}")


class LeadSpeed:
    """The lead's speed over ground, from an alpha-beta track of the range its witnesses agree on."""

    def __init__(self, config: FollowingConfig | None = None) -> None:
        self.config = config or FollowingConfig()
        self.reset()

    def reset(self) -> None:
        self.range_m = math.nan
        self.rate_mps = 0.0
        self.frames = 0
        self._since = 0.0

    @property
    def lead_mps(self) -> float:
        """The estimate used: 0 until ``confirm_frames`` agreeing frames, never negative."""
        return 0.0 if self.frames < self.config.confirm_frames else min(max(self._lead, 0.0), self.config.max_lead_mps)

    @property
    def std_mps(self) -> float:
        """How uncertain :attr:`lead_mps` is, m/s: the confirmed estimate's std, twice it before the
        estimate is confirmed. Not the whole range of speeds a lead may have: the gate's baseline is
        re-anchored on every agreeing frame, so what it must absorb is the estimate's drift between
        anchors; spread by the whole range, it is lost within a quarter second and catches nothing."""
        c = self.config
        return c.speed_std_mps if self.frames >= c.confirm_frames else 2.0 * c.speed_std_mps

    def update(self, depth_m: float, lidar_m: float, size_m: float, ego_mps: float, dt: float,
               new_frame: bool) -> float:
        """One control step: ``depth_m`` the camera's depth of the lead, ``lidar_m`` the LiDAR track's,
        ``size_m`` the size witness's (NaN: none), ``ego_mps`` the car's speed. Learns only on a new
        frame where the depth agrees with the LiDAR or, when the scan plane misses the lead, with the
        size witness (within ``agree_m`` or a tenth of the distance, the size's own spread); returns
        :attr:`lead_mps`."""
        c = self.config
        self._since += dt
        if not new_frame:
            return self.lead_mps
        other = lidar_m if math.isfinite(lidar_m) else size_m
        agree = math.isfinite(depth_m) and math.isfinite(other) and abs(depth_m - other) <= max(c.agree_m, 0.1 * depth_m)
        if agree:
            z = depth_m
            predicted = self.range_m + self.rate_mps * self._since
            if not abs(z - predicted) <= c.gate_m:  # a first range, or one off the track: start again
                self.range_m, self.rate_mps, self.frames = z, -ego_mps, 0
            else:
                innovation = z - predicted
                self.range_m = predicted + c.alpha * innovation
                self.rate_mps += c.beta * innovation / max(self._since, 1e-3)
            self._lead = ego_mps + self.rate_mps
            self.frames += 1
        elif math.isfinite(self.range_m):
            # Carried: the range moves at the lead's last estimated speed against the car's own (the track's
            # own estimate, confirmed or not: carried at the car's speed, a moving lead would leave the gate).
            lead = min(max(self._lead, 0.0), c.max_lead_mps)
            self.range_m += (lead - ego_mps) * self._since
            self.rate_mps = lead - ego_mps
        self._since = 0.0
        return self.lead_mps

    _lead = 0.0


@dataclass(frozen=True)
class FollowDecision:
    """What the follower asks on one step: a speed cap (inf: none) and why."""

    speed_cap_mps: float
    gap_m: float
    ttc_s: float
    emergency: bool


class LeadFollower:
    """The constant time-headway policy and the emergency brake, on the car's gap and closing speed."""

    def __init__(self, config: FollowingConfig | None = None) -> None:
        self.config = config or FollowingConfig()

    def step(self, gap_m: float, closing_mps: float) -> FollowDecision:
        """``gap_m``: the car's estimate of the clear gap to the lead (NaN: no lead seen);
        ``closing_mps``: how fast it shrinks (the car's speed less the lead's)."""
        c = self.config
        if not math.isfinite(gap_m):
            return FollowDecision(math.inf, math.nan, math.nan, False)
        ttc = gap_m / closing_mps if closing_mps > 1e-3 else math.inf
        emergency = ttc < c.ttc_brake_s or gap_m < 0.5 * c.standstill_gap_m
        cap = 0.0 if emergency else max(0.0, (gap_m - c.standstill_gap_m) / c.time_headway_s)
        return FollowDecision(cap, gap_m, ttc, emergency)
