"""The supervisor as a car stage (``supervisor``): runtime assurance over the following stage.

It runs the following stage (:class:`~racf.experiments.car.following.stage.FollowingStage`, with the
episode's defence: ODCA, the EKF, a user's) as its advanced controller, and each control step:

1. moves the carried target's bounds on by the car's own travel (:class:`~.track.CarriedTarget`);
2. judges this frame's range reading (:class:`~.vouch.ReadingChain`): vouched, refused (a jump no car
   makes) or implausible (appeared from nowhere); a vouched one resets the bounds to it +- delta;
3. drops the carried target only when the LiDAR sees the lane clear where it could be (:func:`~.clear.lane_clear`);
4. picks the controller. The defence's cap while its distance agrees with the vouched reading; else the
   safe controller's: the headway policy and a comfortable stop, both on the worst-case gap (the
   carried bounds' near end). Either way, a car faster than that gap allows is told to stop
   (:func:`~.envelope.safe_speed`): the rule the guarantee rests on. An implausible reading nearer
   than the target can be eases the car off at ``EASE_MPS2``, never more.

With a broadcast from the car ahead (the following stage's checked witness), a vouched reading that
disagrees with it is vouched at the nearer of the two. Where the sensors vouch for nothing, a broadcast
the following stage trusts (it has agreed with the sensors' distance, and not disagreed since) is
vouched for alone, unless it puts the target farther than the carried target can have gone; an
untrusted one only where it is nearer than the carried worst case. A signed message may lie (an
insider): one that lies while the sensors see the lead loses the car's trust at once, so it can make
the car more cautious than its sensors, never bolder.

It reads the view and the map only, like the rest of the car. Its columns are the following stage's
and its own (``sup_*``).
"""

from __future__ import annotations

import math

from racf.experiments.car.broadcast import AGREE_M
from racf.experiments.car.following.stage import COLUMNS as FOLLOWING_COLUMNS
from racf.experiments.car.following.stage import LANE_AHEAD_M, FollowingStage
from racf.controllers.lead_perception import lane_in_camera
from racf.experiments.car.stage import CarStage, CarView, StageColumn, StageContext, StageLimit
from racf.experiments.car.supervisor.clear import lane_clear, lane_return
from racf.experiments.car.supervisor.envelope import Envelope, safe_speed
from racf.experiments.car.supervisor.track import CarriedTarget
from racf.experiments.car.supervisor.vouch import ChainConfig, ReadingChain, agree_m

__all__ = ["SupervisorStage", "SUPERVISOR_COLUMNS", "EASE_MPS2"]

#: The LiDAR's lane return is carried between its 10 Hz scans for this long, s.
SCAN_HOLD_S = 0.15
#: How hard the car eases off for a reading it cannot vouch for, m/s^2 (under the 3 m/s^2 of a hard brake).
EASE_MPS2 = 1.5

SUPERVISOR_COLUMNS = (
    StageColumn("sup_defence", "bool", "supervisor: the defence's distance is vouched and its cap drives the car"),
    StageColumn("sup_vouched", "bool", "supervisor: this step's range reading is vouched (its track has no break)"),
    StageColumn("sup_carried", "bool", "supervisor: a target is carried in the lane (vouched once, not seen gone)"),
    StageColumn("sup_implausible", "bool", "supervisor: a reading nearer than the target can be (appeared from "
                                           "nowhere): the car eases off"),
    StageColumn("sup_refused", "bool", "supervisor: a reading farther than the target can have gone (a jump): ignored"),
    StageColumn("sup_on_lane", "m", "supervisor: the LiDAR's first return on the lane, camera distance (NaN: none)"),
    StageColumn("sup_reading", "m", "supervisor: this step's range reading, the nearest of the depth, the LiDAR's "
                                    "track and its lane return (NaN: none)"),
    StageColumn("sup_near", "m", "supervisor: the nearest the carried target can be, camera distance (NaN: none)"),
    StageColumn("sup_cap", "m/s", "supervisor: its speed cap (inf: none)"),
    StageColumn("sup_stop", "bool", "supervisor: the car was faster than the worst-case gap allows: told to stop"),
    StageColumn("sup_broadcast", "bool", "supervisor: the lead's broadcast set the vouched distance (nearer than "
                                         "the sensors', or theirs missing)"),
)


class SupervisorStage(CarStage):
    """Runtime assurance over the following stage.

    Args:
        context: the car's build and the episode's defence (``target_decel_mps2``: the scenario's stated a_max).
        advanced: the advanced controller (default: a :class:`FollowingStage` on the context).
        envelope: the guarantee's assumptions (default: :class:`Envelope` with the context's a_max).
        chain: the reading chain's settings.
    """

    name = "supervisor"
    #: The stage it takes the place of when a spec asks for the supervisor.
    supervises = "following"
    columns = (*FOLLOWING_COLUMNS, *SUPERVISOR_COLUMNS)
    series = {**FollowingStage.series, "sup_near": ((44, 160, 44), "the nearest the supervisor lets the car assume")}

    def __init__(self, context: StageContext, advanced: FollowingStage | None = None,
                 envelope: Envelope | None = None, chain: ChainConfig | None = None) -> None:
        super().__init__(context)
        self.advanced = advanced if advanced is not None else FollowingStage(context)
        stated = {name: getattr(context, name, None) for name in ("target_decel_mps2", "target_accel_mps2")}
        self.envelope = envelope if envelope is not None else Envelope(
            **{name: value for name, value in stated.items() if value})
        self.carried = CarriedTarget(self.envelope)
        self.chain = ReadingChain(chain)
        self.bumper_m = float(context.bumper_ahead_of_camera_m)
        self._lidar_in_camera = (context.lidar_xy_m[0] - context.camera_xy_m[0],
                                 context.lidar_xy_m[1] - context.camera_xy_m[1])
        self._ease = math.inf
        self._on_lane, self._on_lane_age = math.nan, math.inf

    def idle(self) -> StageLimit:
        base = self.advanced.idle()
        own = {c.name: (False if c.unit == "bool" else math.nan) for c in SUPERVISOR_COLUMNS}
        return StageLimit(math.inf, {**base.values, **own, "sup_cap": math.inf}, base.detail)

    def reset(self) -> None:
        self.advanced.reset()
        self.carried.reset()
        self.chain.reset()
        self._ease = math.inf
        self._on_lane, self._on_lane_age = math.nan, math.inf

    def step(self, view: CarView) -> StageLimit:
        said = self.advanced.step(view)
        lead = said.detail
        speed, dt, env = view.speed_mps, view.dt, self.envelope
        self.carried.predict(speed, dt)
        known = lead.speed_known
        closing = speed - lead.lead_mps
        lane = self._lane(view) if view.scan is not None else None
        if lane is not None:
            self._on_lane, self._on_lane_age = lane_return(view.scan, lane, self._lidar_in_camera), 0.0
        else:  # between scans, moved on by the relative motion until the next
            self._on_lane, self._on_lane_age = self._on_lane - closing * dt, self._on_lane_age + dt
        on_lane = self._on_lane if self._on_lane_age <= SCAN_HOLD_S else math.nan
        verdict = self.chain.step((lead.sample.d_meas, lead.sample.lidar_m, on_lane), closing, dt, self.carried,
                                  lead.sample.d_size)
        vouched, by_broadcast = self._vouch(verdict, lead)
        if math.isfinite(vouched):
            self.carried.vouch(vouched, lead.lead_mps, known)
        elif self.carried.held and lane is not None and lane_clear(view.scan, lane, self.carried.near_m,
                                                                    self.carried.far_m, self._lidar_in_camera):
            self.carried.reset()
        fresh = math.isfinite(vouched)
        defence = fresh and math.isfinite(lead.followed_m) and abs(lead.followed_m - vouched) <= agree_m(vouched)
        cap, stop = self._cap(said.speed_cap_mps if defence else None, speed, fresh)
        if verdict.implausible:
            self._ease = max(min(self._ease, speed) - EASE_MPS2 * dt, 0.0)
            cap = min(cap, self._ease)
        else:
            self._ease = math.inf
        values = {**said.values, "sup_defence": defence, "sup_vouched": verdict.vouched,
                  "sup_carried": self.carried.held, "sup_implausible": verdict.implausible,
                  "sup_refused": verdict.refused, "sup_on_lane": on_lane, "sup_reading": verdict.reading_m,
                  "sup_near": self.carried.near_m, "sup_cap": cap, "sup_stop": stop, "sup_broadcast": by_broadcast}
        return StageLimit(cap, values, lead)

    def _vouch(self, verdict, lead) -> tuple[float, bool]:
        """The distance vouched for this step (NaN: none) and whether the broadcast set it: the sensors'
        reading while the broadcast agrees (or there is none), the nearer of the two where they disagree;
        where the sensors vouch for nothing, a trusted broadcast no farther than the carried target can have
        gone, or an untrusted one nearer than its worst case."""
        said = lead.broadcast
        if said is None:
            return (verdict.reading_m if verdict.vouched else math.nan), False
        told = said.distance_m
        if verdict.vouched:
            reading = verdict.reading_m
            if abs(reading - told) <= AGREE_M or reading < told:
                return reading, False
            return told, True
        if not self.carried.held:
            return told, True
        if told > (self.carried.far_m + AGREE_M if lead.broadcast_trusted else self.carried.near_m):
            return math.nan, False
        return told, True

    def _cap(self, defence_cap: float | None, speed: float, fresh: bool) -> tuple[float, bool]:
        """The speed cap and whether the stop rule fired: ``defence_cap`` when the defence drives
        (None: the safe controller; ``fresh``: on a reading vouched this step), never above what the
        worst-case gap allows."""
        if not self.carried.held:
            return (math.inf if defence_cap is None else defence_cap), False
        env, follow = self.envelope, self.advanced.config
        gap = self.carried.near_m - self.bumper_m
        slow = self.carried.slow_mps
        if speed > safe_speed(gap, slow, env):
            return 0.0, True
        if defence_cap is not None:
            return defence_cap, False
        # The headway policy on the reading itself when it is fresh (delta is the stop rule's margin).
        policy_gap = gap + (env.delta_m if fresh else 0.0)
        headway = max(0.0, (policy_gap - follow.standstill_gap_m) / follow.time_headway_s)
        return max(min(headway, safe_speed(gap, slow, env, env.comfort_brake_mps2)), 0.0), False

    def _lane(self, view: CarView):
        """The lane ahead in the camera's frame, from the map and the car's own pose."""
        path = view.path
        ahead = (path.arclength >= view.progress_m) & (path.arclength <= view.progress_m + LANE_AHEAD_M)
        return lane_in_camera(path.points[ahead], view.pose, self.advanced.camera_xy_m)
