"""Which range reading the supervisor vouches for: one whose track has no break.

Each step the range witnesses (the depth in the lead's box, the LiDAR's track of it, the LiDAR's
first return on the lane) give one reading, the nearest: a witness moved away is outvoted by one
that is not. Readings form a chain
while each lies where the last one, moved on by the relative motion, puts it (within ``gate_m``) and
no gap longer than ``gap_s`` parts them. A chain is judged once, when it is born:

- born where the carried target can be (:class:`~.track.CarriedTarget`'s bounds), or with nothing
  carried on a lane the car has not yet watched: it is the target, and its readings are vouched
  while they stay within the bounds (a vouched reading beyond the far end by more than
  ``noise_m`` breaks the chain: motion no car makes);
- born farther than the target can have gone: a jump no car makes (a frustum or depth spoof moves
  the witnesses at once). Refused, with every reading it carries on to; and until a reading within
  the carried target's reach (where it would be, had it kept its vouched speed) is vouched again,
  a chain born beyond that reach is refused too: a gap in the readings does not launder a jump;
- born beyond the reach, even with no jump before it: refused. Hiding a car from the LiDAR lets it
  see the lane behind the car, and that is no reading of the car;
- born farther than the camera's box allows (the size witness: a car's box can only shrink, so a
  range beyond what its height implies is no car's): refused as a jump. Only a new chain is
  checked against the box: a chain that goes on is the track, and a box that grows under it is a
  picture (a phantom), not the car;
- born nearer than the target can be, or first seen inside the distance a vehicle must have been
  seen from on a lane the car has watched: it appeared from nowhere (a phantom), implausible until
  two range witnesses agree on it for ``confirm_frames`` frames (a real car that cut in). Until
  then the car may ease off, not brake hard.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from racf.experiments.car.supervisor.track import CarriedTarget

__all__ = ["ChainConfig", "Verdict", "ReadingChain", "agree_m", "size_slack_m"]


@dataclass(frozen=True)
class ChainConfig:
    """The chain's settings.

    Attributes:
        gate_m: a reading this far from the chain's prediction starts a new chain, m.
        gap_s: readings further apart than this start a new chain, s.
        watch_s: the car has watched its lane ahead after this long, s (before, any first sight is plausible).
        seen_from_m: on a watched lane a vehicle is first seen no nearer than this, m (the detector
            finds a QCar 2 from 2.5 m; one first seen nearer came from nowhere in view).
        confirm_frames: frames both range witnesses must agree on an implausible chain before it is vouched.
    """

    gate_m: float = 0.25
    gap_s: float = 0.5
    watch_s: float = 1.0
    seen_from_m: float = 1.5
    confirm_frames: int = 3
    noise_m: float = 0.05

    def __post_init__(self) -> None:
        for name in ("gate_m", "gap_s", "watch_s", "seen_from_m", "noise_m"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.0 < value <= 10.0:
                raise ValueError(f"{name} must be in (0, 10], got {value!r}")
        if isinstance(self.confirm_frames, bool) or not isinstance(self.confirm_frames, int) or self.confirm_frames < 1:
            raise ValueError(f"confirm_frames must be an int >= 1, got {self.confirm_frames!r}")


def size_slack_m(size_m: float) -> float:
    """How far beyond the size witness a range may read and still be the box's car, m: the depth reads
    the box's middle 0.1 m past its rear, and the box's height is good to about a tenth."""
    return max(0.2, 0.2 * size_m)


def agree_m(distance_m: float) -> float:
    """How far two readings of one car may lie apart, m: the depth reads the box's middle, the LiDAR
    the rear's nearest face (0.1 m apart at 1 m; the following stage's own agreement, widened)."""
    return max(0.15, 0.15 * distance_m)


@dataclass(frozen=True)
class Verdict:
    """What the chain made of one frame.

    Attributes:
        reading_m: this frame's range reading, m (NaN: none).
        vouched: the reading is vouched (its chain was born plausible, or was confirmed).
        implausible: the reading's chain is implausible and nearer than the target can be (ease off).
        refused: the reading's chain jumped away (ignored).
    """

    reading_m: float
    vouched: bool
    implausible: bool = False
    refused: bool = False


NOTHING = Verdict(math.nan, False)


class ReadingChain:
    """The chain of range readings and its verdict (see the module docstring)."""

    def __init__(self, config: ChainConfig | None = None) -> None:
        self.config = config if config is not None else ChainConfig()
        self.reset()

    def reset(self) -> None:
        self.last_m = math.nan
        self.since_s = 0.0
        self.watched_s = 0.0
        self.state = "none"  # "vouched", "implausible", "refused"
        self.confirmed = 0
        self.jumped = False  # a chain jumped away from the carried target, and it has not been seen since

    def step(self, readings: tuple[float, ...], closing_mps: float, dt: float, carried: CarriedTarget,
             size_m: float = math.nan) -> Verdict:
        """One control step: the range witnesses' readings (the depth in the lead's box, the LiDAR's
        track, the LiDAR's first return on the lane; NaN: none), the closing speed the car estimates
        (its speed less the lead's), the carried target, and the size witness (the distance the lead's
        box implies; NaN: none)."""
        c = self.config
        self.watched_s += dt
        self.since_s += dt
        if math.isfinite(self.last_m):
            self.last_m -= closing_mps * dt
        readings = sorted(r for r in readings if math.isfinite(r) and r > 0)
        if not readings:
            if self.since_s > c.gap_s:
                self.last_m, self.state = math.nan, "none"
            return NOTHING
        reading = min(readings)
        both = len(readings) >= 2 and readings[1] - readings[0] <= agree_m(reading)
        continuous = (math.isfinite(self.last_m) and self.since_s <= c.gap_s
                      and abs(reading - self.last_m) <= c.gate_m)
        if not continuous:
            self.state, self.confirmed = self._born(reading, carried, size_m), 0
        elif self.state == "vouched" and carried.held and reading > carried.far_m + c.noise_m:
            self.state, self.jumped = "refused", True  # walked away faster than the target can go
        self.last_m, self.since_s = reading, 0.0
        if self.state == "implausible":
            self.confirmed = self.confirmed + 1 if both else 0
            if self.confirmed >= c.confirm_frames:
                self.state = "vouched"
        if self.state == "vouched":
            if carried.held and reading <= carried.reach_m + agree_m(reading):
                self.jumped = False
            return Verdict(reading, True)
        return Verdict(reading, False, implausible=self.state == "implausible", refused=self.state == "refused")

    def _born(self, reading: float, carried: CarriedTarget, size_m: float = math.nan) -> str:
        c, tolerance = self.config, agree_m(reading)
        if math.isfinite(size_m) and reading > size_m + size_slack_m(size_m):
            self.jumped = carried.held
            return "refused"
        if carried.held:
            if reading > carried.reach_m + tolerance and reading <= carried.far_m + tolerance:
                # Farther than the target would be had it kept its vouched speed: a jump's readings after a
                # gap, or what the LiDAR sees behind a car hidden from it. Not the target, until it is seen
                # within its reach again.
                return "refused"
            if carried.holds(reading, tolerance):
                return "vouched"
            if reading > carried.far_m:
                self.jumped = True
                return "refused"
            return "implausible"
        if self.watched_s >= c.watch_s and reading < c.seen_from_m:
            return "implausible"
        return "vouched"
