"""The supervisor of a moving target (``supervisor``): runtime assurance over the car ahead's track.

It reads the ``vehicle`` track a stage publishes (:class:`~racf.experiments.car.stage.TargetTrack`:
the following stage's, with the episode's defence: ODCA, the EKF, a user's) and nothing else of that
stage, and its cap stands in for the stage's. Each control step it:

1. bounds the car's own true speed (:class:`racf.controllers.speed.SpeedBound`) and moves the carried target's
   bounds on by the car's travel at that bound (:class:`~.track.CarriedTarget`);
2. judges this frame's range reading (:class:`~.vouch.ReadingChain`; the witnesses that read along the
   camera's axis are first taken to the straight line of the lane point there, :func:`~.clear.along_lane`,
   as the lane return and the clear gap are; a witness nearer than the lane the
   LiDAR sees clear is left out: it reads nothing on the lane): vouched, refused or implausible,
   a refusal judged again each step; a vouched one resets the bounds to it +- delta, with the target's
   speed the car measured itself (:class:`~.speed.RangeRate`: the chain's range rate plus its odometry);
3. drops the carried target only when the LiDAR sees the lane clear where it could be (:func:`~.clear.lane_clear`);
4. picks the cap, never bolder than the defence without positive evidence:

   - nothing carried: the defence's cap; eased off (never a hard brake) only where the LiDAR sees the
     lane clear where the defence puts its target;
   - the defence's distance agrees with the vouched reading: the defence's cap (eased off where no LiDAR
     witness confirms it);
   - otherwise, a target carried: the lower of the safe controller's cap (the headway policy and a
     comfortable stop on the worst-case gap) and the defence's; the defence's eased off (never a hard
     brake) where it brakes for what no LiDAR witness confirms against positive evidence: a reading
     vouched this step, one nearer than the carried target can be (a phantom), or the lane seen clear
     beyond where it puts its target. The safe controller's own cap falls at ``FIRM_MPS2`` at most, and
     eases off where the reading it acts on is the camera's alone.

   Whatever drives, a car faster than the worst-case gap allows is told to stop (cap 0,
   :func:`~.envelope.safe_speed`): the rule the guarantee rests on.

With a broadcast from the car ahead (on the track), a vouched reading that disagrees with it is
vouched at the nearer of the two. Where the sensors vouch for nothing, a broadcast the stage trusts is
vouched for alone, unless it puts the target farther than it can have gone; an untrusted one only where
it is nearer than the carried worst case. Each step a broadcast disagreed and was not taken counts as
outvoted (``sup_bc_outvoted``).
"""

from __future__ import annotations

import math

import numpy as np

from racf.controllers.following import FollowingConfig
from racf.controllers.lead_perception import lane_in_camera
from racf.controllers.speed import SpeedBound
from racf.experiments.car.broadcast import AGREE_M
from racf.experiments.car.following.stage import LANE_AHEAD_M
from racf.experiments.car.stage import CarStage, CarView, StageColumn, StageContext, StageLimit, TargetTrack
from racf.experiments.car.supervisor.clear import along_lane, lane_clear, lane_return
from racf.experiments.car.supervisor.envelope import Envelope, safe_speed, stopping_m
from racf.experiments.car.supervisor.speed import RangeRate
from racf.experiments.car.supervisor.track import CarriedTarget
from racf.experiments.car.supervisor.vouch import ChainConfig, ReadingChain, agree_m
from racf.vehicle import clear_gap_m

__all__ = ["VehicleSupervisor", "SUPERVISOR_COLUMNS", "EASE_MPS2", "FIRM_MPS2", "envelope_of"]

#: The LiDAR's lane return is carried between its 10 Hz scans for this long, s.
SCAN_HOLD_S = 0.15
#: A witness nearer than the LiDAR's lane return by more than this reads nothing on the lane, m: the lane
#: is seen clear up to the return (A4), and two witnesses read one car at most this far apart (the depth
#: the box's middle along the camera's axis, the lane return the straight line, in a bend).
LANE_SPREAD_M = 0.3
#: How hard the car eases off for what it cannot vouch for, m/s^2 (under the 3 m/s^2 of a hard brake).
EASE_MPS2 = 1.5
#: The hardest the safe controller's own cap asks the car to brake, m/s^2 (under a hard brake's 3, with
#: room for the drive's overshoot): the stop rule alone carries the guarantee, and brakes as hard as it must.
FIRM_MPS2 = 2.0

SUPERVISOR_COLUMNS = (
    StageColumn("sup_defence", "bool", "supervisor: the defence's distance is vouched and its cap drives the car"),
    StageColumn("sup_safe", "bool", "supervisor: a target is carried and the defence's distance is not vouched: the "
                                    "safe controller's cap, or the defence's where lower, drives the car"),
    StageColumn("sup_vouched", "bool", "supervisor: this step's range reading is vouched"),
    StageColumn("sup_carried", "bool", "supervisor: a target is carried in the lane (vouched once, not seen gone)"),
    StageColumn("sup_implausible", "bool", "supervisor: a reading nearer than the target can be (appeared from "
                                           "nowhere): the car eases off"),
    StageColumn("sup_refused", "bool", "supervisor: a reading farther than the target can be, or than its reach"),
    StageColumn("sup_eased", "bool", "supervisor: the defence braked for what no LiDAR witness confirms, against "
                                     "positive evidence: the car eased off instead"),
    StageColumn("sup_on_lane", "m", "supervisor: the LiDAR's first return on the lane, camera distance (NaN: none)"),
    StageColumn("sup_reading", "m", "supervisor: this step's range reading, the nearest of the depth, the LiDAR's "
                                    "track and its lane return, bounded by the size witness (NaN: none)"),
    StageColumn("sup_near", "m", "supervisor: the nearest the carried target can be, camera distance (NaN: none)"),
    StageColumn("sup_lead_mps", "m/s", "supervisor: the lead's speed from the car's own range rate and odometry "
                                       "(NaN: not measured)"),
    StageColumn("sup_speed_bound", "m/s", "supervisor: the bound on the car's own true speed the stop rule uses"),
    StageColumn("sup_cap", "m/s", "supervisor: its speed cap, in place of the supervised stage's (inf: none)"),
    StageColumn("sup_stop", "bool", "supervisor: the car was faster than the worst-case gap allows: told to stop"),
    StageColumn("sup_broadcast", "bool", "supervisor: the lead's broadcast set the vouched distance (nearer than "
                                         "the sensors', or theirs missing)"),
    StageColumn("sup_bc_outvoted", "bool", "supervisor: the lead's broadcast disagreed and was not taken"),
)


def envelope_of(context: StageContext) -> Envelope:
    """The envelope with what the mission states of its targets (None: the envelope's own; 0 is a value)."""
    stated = {name: getattr(context, name, None) for name in ("target_decel_mps2", "target_accel_mps2")}
    return Envelope(**{name: value for name, value in stated.items() if value is not None})


class VehicleSupervisor(CarStage):
    """Runtime assurance over a published ``vehicle`` track (see the module docstring).

    Args:
        context: the car's build (``target_decel_mps2``: the scenario's stated a_max).
        envelope: the guarantee's assumptions (default: :func:`envelope_of` the context).
        chain: the reading chain's settings.
        policy: the safe controller's headway policy (default: the following controller's).
    """

    name = "supervisor"
    #: The kind of track it reads, and that its cap stands in for the publisher's.
    supervises = "vehicle"
    stands_in = True
    columns = SUPERVISOR_COLUMNS
    series = {"sup_near": ((44, 160, 44), "the nearest the supervisor lets the car assume")}

    def __init__(self, context: StageContext, envelope: Envelope | None = None, chain: ChainConfig | None = None,
                 policy: FollowingConfig | None = None) -> None:
        super().__init__(context)
        self.envelope = envelope if envelope is not None else envelope_of(context)
        self.policy = policy if policy is not None else FollowingConfig()
        self.carried = CarriedTarget(self.envelope)
        self.chain = ReadingChain(chain)
        self.rate = RangeRate()
        self.speed_bound = SpeedBound(self.envelope.odometry_error)
        self.bumper_m = float(context.bumper_ahead_of_camera_m)
        self.camera_xy_m = context.camera_xy_m
        self._lidar_in_camera = (context.lidar_xy_m[0] - context.camera_xy_m[0],
                                 context.lidar_xy_m[1] - context.camera_xy_m[1])
        self.reset()

    def idle(self) -> StageLimit:
        own = {c.name: (False if c.unit == "bool" else math.nan) for c in SUPERVISOR_COLUMNS}
        return StageLimit(math.inf, {**own, "sup_cap": math.inf})

    def reset(self) -> None:
        self.carried.reset()
        self.chain.reset()
        self.rate.reset()
        self.speed_bound.reset()
        self._ease, self._eased_now, self._firm = math.inf, False, math.inf
        self._on_lane, self._on_lane_age = math.nan, math.inf

    def step(self, view: CarView) -> StageLimit:
        track: TargetTrack | None = view.tracks.get(self.supervises)
        if track is None:
            return self.idle()
        speed, dt, env = view.speed_mps, view.dt, self.envelope
        self._eased_now = False
        bound = self.speed_bound.step(speed, dt)
        self.carried.predict(bound, dt)
        lead_mps, known = self._lead_speed(track)
        closing = speed - (lead_mps if math.isfinite(lead_mps) else 0.0)
        ahead = self._lane(view)
        lane = ahead if view.scan is not None else None  # (the lane for the LiDAR: on the steps it scans)
        if lane is not None:
            self._on_lane, self._on_lane_age = lane_return(view.scan, lane, self._lidar_in_camera), 0.0
        else:  # between scans, moved on by the relative motion until the next
            self._on_lane, self._on_lane_age = self._on_lane - closing * dt, self._on_lane_age + dt
        on_lane = self._on_lane if self._on_lane_age <= SCAN_HOLD_S else math.nan
        # A witness nearer than the lane the LiDAR sees clear reads nothing on the lane (A4): a phantom
        # picture's depth and box, the LiDAR's track on a wall beside the lane. Left out of the chain, so the
        # car eases off for them (the defence's brake, unconfirmed) and never stops hard on them. Each read
        # along the camera's axis, taken to the straight line of the lane return and the clear gap first.
        depth, lidar, size = (_on_the_lane(along_lane(r, ahead), on_lane)
                              for r in (track.depth_m, track.lidar_m, track.size_m))
        defended = along_lane(track.distance_m, ahead)  # the defence's distance, the same way
        verdict = self.chain.step((depth, lidar, on_lane), closing, dt, self.carried, size, stopping_m(bound, env))
        if self.chain.born:
            self.rate.restart()
        self.rate.step(speed, dt, verdict.reading_m if verdict.vouched else math.nan)
        vouched, by_broadcast, outvoted = self._vouch(verdict, track)
        if math.isfinite(vouched):
            self.carried.vouch(vouched, lead_mps, known)  # (an unknown speed is not read)
        elif self.carried.held and lane is not None and lane_clear(view.scan, lane, self.carried.near_m,
                                                                    self.carried.far_m, self._lidar_in_camera):
            self.carried.reset()
        fresh = math.isfinite(vouched)
        agrees = fresh and math.isfinite(defended) and abs(defended - vouched) <= agree_m(vouched)
        confirmed = any(math.isfinite(r) and abs(r - defended) <= agree_m(defended)
                        for r in (lidar, on_lane))
        clear_there = math.isfinite(defended) and (
            math.isnan(_on_the_lane(defended, on_lane))  # the lane seen clear beyond where the defence puts it
            or (not self.carried.held and lane is not None
                and lane_clear(view.scan, lane, defended - env.delta_m, defended + env.delta_m,
                               self._lidar_in_camera)))
        ranged = fresh and any(math.isfinite(r) and abs(r - vouched) <= agree_m(vouched) for r in (lidar, on_lane))
        cap, stop, eased = self._cap(track.cap_mps, speed, dt, bound, fresh, agrees, math.isfinite(defended),
                                     evidence=((fresh or verdict.implausible) and not confirmed) or clear_there,
                                     unranged=fresh and not ranged)
        if verdict.implausible:
            cap = min(cap, self._ease if eased else self._eased(speed, dt))
        elif not eased:
            self._ease = math.inf
        values = {"sup_defence": agrees, "sup_safe": self.carried.held and not agrees, "sup_vouched": verdict.vouched,
                  "sup_carried": self.carried.held, "sup_implausible": verdict.implausible,
                  "sup_refused": verdict.refused, "sup_eased": eased, "sup_on_lane": on_lane,
                  "sup_reading": verdict.reading_m, "sup_near": self.carried.near_m,
                  "sup_lead_mps": lead_mps if known else math.nan, "sup_speed_bound": bound, "sup_cap": cap,
                  "sup_stop": stop, "sup_broadcast": by_broadcast, "sup_bc_outvoted": outvoted}
        return StageLimit(cap, values)

    def _lead_speed(self, track: TargetTrack) -> tuple[float, bool]:
        """The lead's speed and whether it is measured: the car's own range rate where it is, else the
        publishing stage's confirmed estimate, else unknown."""
        mps, measured = self.rate.estimate()
        if measured:
            return mps, True
        if track.speed_known and math.isfinite(track.speed_mps):
            return max(track.speed_mps, 0.0), True
        return math.nan, False

    def _vouch(self, verdict, track: TargetTrack) -> tuple[float, bool, bool]:
        """The distance vouched for this step (NaN: none), whether the broadcast set it, and whether a
        broadcast disagreed and was not taken: the sensors' reading while the broadcast agrees (or
        there is none), the nearer of the two where they disagree; where the sensors vouch for nothing,
        a trusted broadcast no farther than the carried target can have gone, or an untrusted one
        nearer than its worst case."""
        told = track.broadcast_m
        if not math.isfinite(told):
            return (verdict.reading_m if verdict.vouched else math.nan), False, False
        if verdict.vouched:
            reading = verdict.reading_m
            if abs(reading - told) <= AGREE_M:
                return reading, False, False
            return (reading, False, True) if reading < told else (told, True, False)
        if not self.carried.held:
            return told, True, False
        if told > (self.carried.far_m + AGREE_M if track.broadcast_trusted else self.carried.near_m):
            return math.nan, False, True
        return told, True, False

    def _eased(self, speed: float, dt: float) -> float:
        """The ease-off cap: down from the car's speed at ``EASE_MPS2``, never a hard brake (lowered once
        a step, however many of the cap's reasons ask for it)."""
        if not self._eased_now:
            self._ease = max(min(self._ease, speed) - EASE_MPS2 * dt, 0.0)
            self._eased_now = True
        return self._ease

    def _cap(self, defence_cap: float, speed: float, dt: float, speed_bound: float, fresh: bool, agrees: bool,
             defended: bool, evidence: bool, unranged: bool = False) -> tuple[float, bool, bool]:
        """The speed cap, whether the stop rule fired, and whether a brake was eased off (see the module
        docstring). ``evidence``: positive evidence against what the defence brakes for; ``unranged``:
        this step's vouched reading is the camera's alone (no LiDAR witness reads it)."""
        firm, self._firm = self._firm, math.inf  # the safe controller's last cap, while it drives on
        softened = defence_cap
        if evidence and defence_cap < speed:
            softened = max(defence_cap, self._eased(speed, dt))
        eased = softened > defence_cap
        if not self.carried.held:
            return softened, False, eased
        env = self.envelope
        gap = clear_gap_m(self.carried.near_m, self.bumper_m)  # the referee's definition, on the worst case
        slow = self.carried.slow_mps
        if speed_bound > safe_speed(gap, slow, env):
            return 0.0, True, False
        if agrees:  # (eased where no LiDAR witness confirms the distance it brakes for: the stop rule stands)
            return softened, False, eased
        safe = max(safe_speed(gap, slow, env, env.comfort_brake_mps2), 0.0)
        if defended:  # the defence follows a distance the reading disagrees with: the headway policy on the reading
            policy_gap = gap + (env.delta_m if fresh else 0.0)  # on the reading itself when fresh
            safe = min(safe, max(0.0, (policy_gap - self.policy.standstill_gap_m) / self.policy.time_headway_s))
        # else the defence has let go of the target (out of its view): it sets no headway, and neither does
        # the supervisor; the comfortable stop on the worst case bounds the car.
        # Never a hard brake of its own (the stop rule is there): down from its last cap at FIRM_MPS2 at most.
        if safe < speed:
            safe = self._firm = max(safe, min(firm, speed) - FIRM_MPS2 * dt)
        cap = min(safe, softened)
        if unranged and cap < speed:  # a nearer target only the camera reads: ease off, the stop rule stands
            cap = max(cap, self._eased(speed, dt))
        return cap, False, cap > min(safe, defence_cap)

    def _lane(self, view: CarView):
        """The lane ahead in the camera's frame, from the map and the car's own pose (None: no map)."""
        path = view.path
        if path is None or view.pose is None:
            return None
        # Every step (the axial witnesses are read along it): a slice of the sorted arclengths, not a mask
        # over the whole route.
        first = int(np.searchsorted(path.arclength, view.progress_m, side="left"))
        last = int(np.searchsorted(path.arclength, view.progress_m + LANE_AHEAD_M, side="right"))
        return lane_in_camera(path.points[first:last], view.pose, self.camera_xy_m)


def _on_the_lane(reading_m: float, on_lane_m: float) -> float:
    """``reading_m``, or NaN where it lies more than ``LANE_SPREAD_M`` nearer than the lane the LiDAR sees
    clear (``on_lane_m``, NaN: no lane return): then it reads nothing on the lane (A4)."""
    return math.nan if math.isfinite(on_lane_m) and reading_m < on_lane_m - LANE_SPREAD_M else reading_m
