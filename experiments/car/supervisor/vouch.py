"""Which range reading the supervisor vouches for: one whose track has no break, judged again each step.

Each step the range witnesses (the depth in the target's box, the LiDAR's track of it, the LiDAR's
first return on the lane) give one reading, the nearest: a witness moved away is outvoted by one
that is not. Readings form a chain while each lies where the last one, moved on by the relative
motion, puts it (within ``gate_m``) and no gap longer than ``gap_s`` parts them.

A chain is judged when it is born, and a chain not vouched is judged again on every later reading
(a refusal is not for life: the carried bounds and the witnesses change). A refused chain is lifted only
on the safe side (no farther than the worst case plus delta) or where the box confirms it; never
because the bounds grew to meet it:

- with nothing carried, on a lane the car has not yet watched: it is the target, vouched;
- on a watched lane, first seen nearer than ``seen_from_m`` (a vehicle is seen from farther), or
  nearer than the carried target can be: it appeared from nowhere (a phantom), implausible until
  two range witnesses agree on it for ``confirm_frames`` frames (a real car that cut in). Until
  then the car may ease off, not brake hard;
- nearer than the carried worst case (its near end) and read by one witness alone: no reading of the
  carried target (it cannot be there) and none a second witness confirms, implausible as above (the car
  eases off; the worst case still bounds it). The LiDAR's track on a car's near corner in a bend reads
  0.3 m short of the lane return: taken as the car ahead, the stop rule braked hard for nothing;
- within the carried bounds and no farther than the carried worst case plus delta: vouched (a
  reading that near is on the safe side whatever it is);
- farther than that, a *re-acquisition*: vouched only within the target's reach (where it would be
  had it kept the speed the car measured of it, :class:`~.track.CarriedTarget`) and only while the
  car lost it for at most ``reacquire_s``. Past that, or with the speed unmeasured beyond the worst
  case plus the car's own stopping distance, only a chain the size witness confirms is vouched.
  Hiding a car lets the LiDAR see the lane behind it, and a frustum spoof after a pause puts both
  range witnesses on a distance the target can have reached: neither is a reading of the car;
- farther than the carried target can have gone: a jump no car makes, refused.

A vouched chain whose reading walks past the far end (by more than ``noise_m``) broke: refused. A step
up because the nearest witness fell silent is no walk: the witnesses read a car at different places
(the depth its box's middle, the LiDAR's track its rear face, the lane return the straight-line
distance, in a bend up to 0.3 m apart), and the one that now gives the reading was read last step
where it reads now (within ``gate_m``).

The size witness bounds every vouch: the camera's box can only shrink with distance, so a reading
beyond the distance its height implies (plus :func:`size_slack_m`) is vouched at that bound, the
nearer of the two (nearer is on the safe side).
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
        noise_m: how far past the far end a going chain may read before it counts as broken, m (its
            reading is the nearest of witnesses that differ by about as much: the depth's axial
            distance, the lane return's straight-line one, in a bend).
        reacquire_s: how long after its last vouch a target may be re-acquired within its reach, s.
    """

    gate_m: float = 0.25
    gap_s: float = 0.5
    watch_s: float = 1.0
    seen_from_m: float = 1.5
    confirm_frames: int = 3
    noise_m: float = 0.15
    reacquire_s: float = 0.5

    def __post_init__(self) -> None:
        for name in ("gate_m", "gap_s", "watch_s", "seen_from_m", "noise_m", "reacquire_s"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.0 < value <= 10.0:
                raise ValueError(f"{name} must be in (0, 10], got {value!r}")
        if isinstance(self.confirm_frames, bool) or not isinstance(self.confirm_frames, int) or self.confirm_frames < 1:
            raise ValueError(f"confirm_frames must be an int >= 1, got {self.confirm_frames!r}")


def size_slack_m(size_m: float) -> float:
    """How far beyond the size witness a range may read and still be the box's target, m: the depth
    reads the box's middle 0.1 m past its rear, and the box's height is good to about a tenth."""
    return max(0.2, 0.2 * size_m)


def agree_m(distance_m: float) -> float:
    """How far two readings of one car may lie apart, m: the depth reads the box's middle, the LiDAR
    the rear's nearest face (0.1 m apart at 1 m; the following stage's own agreement, widened)."""
    return max(0.15, 0.15 * distance_m)


@dataclass(frozen=True)
class Verdict:
    """What the chain made of one frame.

    Attributes:
        reading_m: this frame's range reading, m (NaN: none): the nearest witness, bounded by the size
            witness where it gives one.
        vouched: the reading is vouched.
        implausible: the reading's chain is implausible: nearer than the target can be (ease off).
        refused: the reading's chain is refused: farther than the target can be, or than its reach.
        sized: the size witness bounded the reading (it read farther than the box allows).
    """

    reading_m: float
    vouched: bool
    implausible: bool = False
    refused: bool = False
    sized: bool = False


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
        self.born = False  # the last reading started a new chain
        self._each: list[float] = []  # each witness's last reading, moved on by the relative motion
        self._giver = -1  # which witness gave the last reading

    def step(self, readings: tuple[float, ...], closing_mps: float, dt: float, carried: CarriedTarget,
             size_m: float = math.nan, stopping_m: float = 0.0) -> Verdict:
        """One control step: the range witnesses' readings (NaN: none), the closing speed the car
        estimates (its speed less the lead's), the carried target, the size witness (the distance the
        target's box implies; NaN: none) and the car's own stopping distance, m (the reach of a target
        whose speed the car has not measured)."""
        c = self.config
        self.watched_s += dt
        self.since_s += dt
        if math.isfinite(self.last_m):
            self.last_m -= closing_mps * dt
        each = [r if math.isfinite(r) and r > 0 else math.nan for r in readings]
        before = [r - closing_mps * dt for r in self._each] if len(self._each) == len(each) else [math.nan] * len(each)
        self._each = each
        readings = sorted(r for r in each if math.isfinite(r))
        if not readings:
            if self.since_s > c.gap_s:
                self.last_m, self.state = math.nan, "none"
            self._giver = -1
            return NOTHING
        reading = min(readings)
        giver = each.index(reading)
        handed_on = (giver != self._giver and math.isfinite(before[giver])
                     and abs(reading - before[giver]) <= c.gate_m)  # another witness, read there last step
        self._giver = giver
        both = len(readings) >= 2 and readings[1] - readings[0] <= agree_m(reading)
        bound = size_m + size_slack_m(size_m) if math.isfinite(size_m) and size_m > 0 else math.inf
        sized = reading > bound
        continuous = (math.isfinite(self.last_m) and self.since_s <= c.gap_s
                      and (abs(reading - self.last_m) <= c.gate_m or handed_on))
        self.born = not continuous
        if self.born:
            self.confirmed = 0
        if self.born or self.state != "vouched":
            self.state = self._judge(reading, carried, sized, stopping_m, keep=self.state if continuous else "none",
                                     both=both)
        elif carried.held and reading > carried.far_m + c.noise_m and not handed_on:
            self.state = "refused"  # walked away faster than the target can go
        self.last_m, self.since_s = reading, 0.0
        if self.state == "implausible":
            self.confirmed = self.confirmed + 1 if both else 0
            if self.confirmed >= c.confirm_frames:
                self.state = "vouched"
        said = min(reading, bound)
        if self.state == "vouched":
            return Verdict(said, True, sized=sized)
        return Verdict(said, False, implausible=self.state == "implausible", refused=self.state == "refused",
                       sized=sized)

    def _judge(self, reading: float, carried: CarriedTarget, sized: bool, stopping_m: float, keep: str,
               both: bool = False) -> str:
        """A chain's verdict on this reading (``keep``: its verdict so far, "none" for a new chain;
        ``both``: two range witnesses agree on it)."""
        c, tolerance = self.config, agree_m(reading)
        if not carried.held:
            if keep == "implausible" or (keep == "none" and self.watched_s >= c.watch_s and reading < c.seen_from_m):
                return "implausible"
            return "vouched"
        if reading < carried.near_m - tolerance:
            return "implausible"  # nearer than the target can be: appeared from nowhere
        if reading < carried.near_m and not both:
            # Nearer than the carried worst case, a jump from the chain the car held, and one witness alone:
            # no reading of the carried target (it cannot be there), and none a second witness confirms. The
            # car eases off for it and the worst case still bounds the car; the stop rule waits for a second
            # witness (the LiDAR's track on a car's near corner in a bend, 0.3 m short of the lane return).
            return "implausible"
        if reading > carried.far_m + tolerance:
            return "refused"  # farther than the target can have gone: a jump
        if reading <= carried.near_m + carried.env.delta_m:
            return "vouched"  # no farther than the worst case allows: on the safe side whatever it is
        if sized:
            return "vouched"  # the box confirms a target there, and bounds the vouch
        if keep == "refused":
            # A chain refused as no reading of the target stays so until it comes to the safe side or the box
            # confirms it: the bounds growing to meet it are no evidence (the far end grows at the hardest
            # pull-away, the reach at a range rate that errs in a bend), and the lane behind a hidden car
            # stays behind it (seed 95366: a lane return 0.5 m behind the car, vouched once the reach met it).
            return "refused"
        # The reach already holds the witnesses' error (delta, budgeted once): no tolerance on top, or a
        # lane return behind a hidden car walks the bounds away by delta plus the tolerance each time.
        return "vouched" if reading <= self._reach(carried, stopping_m) else "refused"

    def _reach(self, carried: CarriedTarget, stopping_m: float) -> float:
        """How far a target lost for a while may be re-acquired without the box to confirm it, m."""
        if carried.unvouched_s > self.config.reacquire_s:
            return -math.inf
        if not carried.speed_measured:
            return carried.near_m + stopping_m
        return carried.reach_m
