"""The car's following stage (``following``): the car ahead perceived, its distance defended, and a speed cap.

A :class:`~racf.experiments.car.stage.CarStage` that a mission engages by name (the lead-vehicle
scenario does: the operator's adaptive cruise switch). Each control step it places the lane ahead
in the camera from the map and the car's own pose, perceives the car ahead on it
(:class:`~racf.controllers.lead_perception.LeadPerception`), asks its own defence instance for the
distance with the *relative* motion (the car's speed less the lead's, as
:class:`~racf.controllers.following.LeadSpeed` estimates it while the witnesses agree): every
estimator's kinematics, ODCA's branch and the EKF's prediction, then follow a target that moves
at a constant speed; and turns the defended gap into a speed cap (:class:`LeadFollower`). It
declares its step-log columns (``lead_*``) and the distance series a viewer draws. Like the rest of
the car, it reads the view and the map, never ``info``.

When the car ahead broadcasts (``racf.sim.radio``), its checked messages
(:class:`~racf.experiments.car.broadcast.BroadcastReceiver`) are a witness the sensor attacker does not
reach. The lead's speed is the broadcast's while it agrees with the car's confirmed track (the
defence's kinematics then know it to ``BROADCAST_STD_MPS``), else the slower of the two; the distance
the car follows is the defence's while the broadcast agrees with it, else the nearer of the two, and
the log says which (``lead_bc_nearer``). The broadcast earns the car's trust by agreeing with the
defence's distance for ``TRUST_STEPS`` steps running, and loses it at the first disagreement
(``lead_bc_trusted``): the supervisor lets a trusted broadcast alone stand for the lead where the sensors
have none, and an untrusted one only where it is the more cautious. A defence of its own that asks for it (a ``hear_broadcast(witness)``
method) is handed the checked witness each step, or None. A lead that broadcasts nothing is followed as
before.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from racf.controllers import LidarTargetConfig, LidarTargetTracker
from racf.controllers.following import FollowDecision, FollowingConfig, LeadFollower, LeadSpeed
from racf.controllers.lead_existence import NO_EVIDENCE, LeadEvidence, LeadExistenceCheck
from racf.controllers.lead_perception import LeadPerception, lane_in_camera
from racf.controllers.perception import PerceptionSample
from racf.experiments.car.broadcast import AGREE_M, SPEED_AGREE_MPS, BroadcastReceiver, BroadcastWitness
from racf.experiments.car.stage import CarStage, CarView, StageColumn, StageContext, StageLimit, TargetTrack

__all__ = ["FollowingStage", "LeadStep", "track_of", "LANE_AHEAD_M", "NO_LEAD", "COLUMNS", "BROADCAST_STD_MPS", "TRUST_STEPS"]

#: How far along the lane ahead the car looks for a car, m.
LANE_AHEAD_M = 4.0
#: Unseen this long (no detection, no LiDAR track), the car ahead is lost: it drove out of sight (a
#: curve takes it out of the camera's 70 degrees at 1 m), and a carried distance would hold the car
#: back for nothing. The defence and the speed estimate start again, and the policy lets the car
#: drive on, as a production adaptive cruise does, s.
LOST_AFTER_S = 0.5
#: How well the car knows the lead's speed while its broadcast and the track agree, m/s (the
#: broadcast's own error, a few centimetres a second, and the latency's).
BROADCAST_STD_MPS = 0.05
#: The broadcast is trusted once it has agreed with the defence's distance this many steps running (0.5 s
#: at 50 Hz): a lead that lies while the sensors see it loses that trust at once, and earns it back only so.
TRUST_STEPS = 25


@dataclass(frozen=True)
class LeadStep:
    """What the following stage made of one control step (for the log)."""

    sample: PerceptionSample
    d_fused: float
    lead_mps: float
    decision: FollowDecision
    d_follow: float | None = None  # what the policy followed, where not d_fused (the broadcast's, nearer)
    broadcast: BroadcastWitness | None = None
    speed_known: bool = False  # the lead's speed is confirmed (by the track, or the broadcast agreeing with it)
    broadcast_trusted: bool = False  # the broadcast agreed with the defence TRUST_STEPS steps running, since

    @property
    def followed_m(self) -> float:
        """The camera distance the policy acted on: the defence's, or the broadcast's where it was nearer."""
        return self.d_fused if self.d_follow is None else self.d_follow


NO_LEAD = LeadStep(PerceptionSample(None, math.nan, 0.0, math.nan, math.nan), math.nan, math.nan,
                   FollowDecision(math.inf, math.nan, math.nan, False))


#: The stage's step-log columns (the evidence's from ``LeadEvidence.columns()``).
COLUMNS = (
    StageColumn("lead_detected", "bool", "following: the vehicle detector found a car on the lane ahead"),
    StageColumn("lead_d_meas", "m", "following: the depth distance of the car ahead (NaN: none)"),
    StageColumn("lead_lidar", "m", "following: the LiDAR track's distance to the car ahead's rear (NaN: none)"),
    StageColumn("lead_d_size", "m", "following: the size witness, from the box's height and a QCar 2's (NaN: none)"),
    StageColumn("lead_d_fused", "m", "following: the defence's distance to the car ahead (NaN: none)"),
    StageColumn("lead_v_est", "m/s", "following: the car's estimate of the lead's speed (NaN: none)"),
    StageColumn("lead_gap_est", "m", "following: the gap the policy acts on, bumper to the lead's rear (NaN: none)"),
    StageColumn("lead_cap", "m/s", "following: the policy's speed cap (inf: none)"),
    StageColumn("lead_emergency", "bool", "following: the emergency brake on time-to-collision is on"),
    StageColumn("lead_support", "share", "following: the share of the lead's box that the depth finds upright at "
                                         "the box's size distance (NaN: no verdict)"),
    StageColumn("lead_nearest", "m", "following: the nearest upright thing the depth finds in the lead's box "
                                     "(NaN: none)"),
    StageColumn("lead_picture", "bool", "following: the lead's box is taken for a picture of a car (its size no "
                                        "witness)"),
    StageColumn("lead_d_bc", "m", "following: the lead's camera distance as its broadcast tells it (NaN: none fresh)"),
    StageColumn("lead_v_bc", "m/s", "following: the lead's speed as its broadcast tells it (NaN: none fresh)"),
    StageColumn("lead_bc_nearer", "bool", "following: the broadcast disagreed with the defence and was nearer: the "
                                          "car followed it"),
    StageColumn("lead_bc_trusted", "bool", "following: the broadcast has agreed with the defence's distance long "
                                           "enough, and not disagreed since"),
    StageColumn("lead_bc_accepted", "", "following: broadcast messages accepted so far this episode"),
    StageColumn("lead_bc_refused", "", "following: broadcast messages refused so far (each for a reason of "
                                       "racf.sim.radio.message.REFUSALS)"),
    StageColumn("lead_bc_slots", "", "following: which of this step's radio slots the receiver accepted (a bit mask)"),
)


def _columns(step: LeadStep, radio: BroadcastReceiver | None = None) -> dict:
    sample, decision, said = step.sample, step.decision, step.broadcast
    evidence = sample.witnesses if isinstance(sample.witnesses, LeadEvidence) else NO_EVIDENCE
    return {"lead_detected": sample.detected, "lead_d_meas": sample.d_meas, "lead_lidar": sample.lidar_m,
            "lead_d_size": sample.d_size, "lead_d_fused": step.d_fused, "lead_v_est": step.lead_mps,
            "lead_gap_est": decision.gap_m, "lead_cap": decision.speed_cap_mps, "lead_emergency": decision.emergency,
            **evidence.columns(),
            "lead_d_bc": math.nan if said is None else said.distance_m,
            "lead_v_bc": math.nan if said is None else said.speed_mps,
            "lead_bc_nearer": said is not None and not step.followed_m == step.d_fused,
            "lead_bc_trusted": step.broadcast_trusted,
            "lead_bc_accepted": 0 if radio is None else radio.accepted,
            "lead_bc_refused": 0 if radio is None else sum(radio.refused.values()),
            "lead_bc_slots": 0 if radio is None else radio.slots}


@lru_cache(maxsize=1)
def _vehicle_detector():
    """The process's vehicle detector (its network is loaded once; it keeps no state between frames)."""
    from racf.controllers.vehicle_detector import LearnedVehicleDetector

    return LearnedVehicleDetector()


def lead_perception(context: StageContext) -> LeadPerception:
    """The vehicle detector on the lane, the car's LiDAR tracker and the existence check, on the car's build."""
    tracker = LidarTargetTracker(LidarTargetConfig(lidar_position_m=context.lidar_xy_m,
                                                   camera_position_m=context.camera_xy_m))
    return LeadPerception(context.camera, _vehicle_detector(), tracker,
                          existence=LeadExistenceCheck(context.camera, context.camera_height_m))


class FollowingStage(CarStage):
    """Perception, defence and policy for the car ahead.

    Args:
        context: the car's build and the episode's defence.
        perception: the lead's perception pipeline (default: :func:`lead_perception`).
        estimator: the defence for its distance (default: a new instance of the episode's, so its
            state is the lead's).
        config: the following controller's settings.
    """

    name = "following"
    columns = COLUMNS
    publishes = "vehicle"
    series = {
        "lead_d_meas": ((255, 152, 150), "its depth (depth camera)"),
        "lead_lidar": ((158, 218, 229), "its LiDAR track"),
        "lead_d_size": ((255, 187, 120), "its size witness"),
        "lead_d_fused": ((174, 199, 232), "the defence's distance (what the car follows)"),
    }

    def __init__(self, context: StageContext, perception=None, estimator=None,
                 config: FollowingConfig | None = None) -> None:
        super().__init__(context)
        self.perception = perception if perception is not None else lead_perception(context)
        self.estimator = estimator if estimator is not None else context.make_defence()
        self.bumper_m = float(context.bumper_ahead_of_camera_m)
        self.camera_xy_m = context.camera_xy_m
        self.config = config if config is not None else FollowingConfig()
        self.follower = LeadFollower(self.config)
        self.speed = LeadSpeed(self.config)
        self.last = NO_LEAD
        self.radio = BroadcastReceiver(context.fleet_keys)
        self._agreed = 0
        self._unseen_s = 0.0
        self._lost = False

    def idle(self) -> StageLimit:
        return StageLimit(math.inf, _columns(NO_LEAD), NO_LEAD)

    def reset(self) -> None:
        self.perception.reset()
        self.estimator.reset()
        self.speed.reset()
        self.radio.reset()
        self._agreed = 0
        self.last = NO_LEAD
        self._unseen_s = 0.0
        self._lost = False

    def step(self, view: CarView) -> StageLimit:
        """One control step on the view; its cap is the following policy's."""
        lane = None
        if view.frame_new:
            path = view.path
            ahead = (path.arclength >= view.progress_m) & (path.arclength <= view.progress_m + LANE_AHEAD_M)
            lane = lane_in_camera(path.points[ahead], view.pose, self.camera_xy_m)
        speed, dt = view.speed_mps, view.dt
        stamps = view.obs.get("timestamps")  # the newest reading's time: the car's clock now
        now = float(np.max(stamps)) if stamps is not None else math.nan
        self.radio.hear(view.obs, now)
        said = self.radio.witness(now, view.pose, self.camera_xy_m, view.path, view.progress_m)
        lead_mps, known = self._lead_speed(said)
        closing = speed - lead_mps
        # The tracker carries the lead's point by the relative motion, as the defence does.
        sample = self.perception.process(view.obs["rgb"], view.obs["depth"][..., 0], view.scan, lane=lane,
                                         speed=closing, yaw_rate=view.yaw_rate_radps, lateral_speed=view.lateral_mps,
                                         dt=dt, new_frame=view.frame_new, beam_age_s=view.beam_age_s)
        seen = sample.detected or math.isfinite(sample.lidar_m)
        self._unseen_s = 0.0 if seen else self._unseen_s + dt
        if self._unseen_s > LOST_AFTER_S:
            if not self._lost:  # lost just now: what the car knew of this lead is of no use for the next
                self.estimator.reset()
                self.speed.reset()
                self.perception.lose()
                self._lost = True
            d = math.nan
        else:
            self._lost = False
            moving = getattr(self.estimator, "follow_moving_target", None)
            if callable(moving):  # its target moves: how well the car knows the lead's speed
                moving(BROADCAST_STD_MPS if known and said is not None else self.speed.std_mps)
            hear = getattr(self.estimator, "hear_broadcast", None)
            if callable(hear):  # a defence that asks for the lead's broadcast gets the checked witness (or None)
                hear(said)
            d = float(self.estimator.estimate(sample, closing, dt, yaw_rate_radps=view.yaw_rate_radps))
        self.speed.update(sample.d_meas, sample.lidar_m, sample.d_size, speed, dt, view.frame_new)
        lead, known = self._lead_speed(said)
        follow = d if said is None else _cautious(d, said.distance_m)
        if said is not None and math.isfinite(d):  # a step on which the two can be compared
            self._agreed = self._agreed + 1 if abs(d - said.distance_m) <= AGREE_M else 0
        decision = self.follower.step(follow - self.bumper_m, speed - lead)
        self.last = LeadStep(sample, d, lead, decision, follow, said, known, self._agreed >= TRUST_STEPS)
        return StageLimit(decision.speed_cap_mps, _columns(self.last, self.radio), self.last, track_of(self.last))

    def _lead_speed(self, said: BroadcastWitness | None) -> tuple[float, bool]:
        """The lead's speed and whether it is confirmed: the broadcast's while it agrees with the confirmed
        track, else the slower of the two (an unconfirmed track counts as a standing lead)."""
        confirmed = self.speed.frames >= self.config.confirm_frames
        track = self.speed.lead_mps
        if said is None:
            return track, confirmed
        if confirmed and abs(track - said.speed_mps) <= SPEED_AGREE_MPS:
            return said.speed_mps, True
        return min(track, said.speed_mps), confirmed


def track_of(step: LeadStep) -> TargetTrack:
    """What the stage publishes of the car ahead (the supervision contract): the distance its cap acts
    on, its speed estimate, the witnesses behind them and the lead's own broadcast."""
    sample, said = step.sample, step.broadcast
    return TargetTrack("vehicle", step.followed_m, step.decision.speed_cap_mps, moving=True,
                       speed_mps=step.lead_mps, speed_known=step.speed_known, depth_m=sample.d_meas,
                       lidar_m=sample.lidar_m, size_m=sample.d_size,
                       broadcast_m=math.nan if said is None else said.distance_m,
                       broadcast_mps=math.nan if said is None else said.speed_mps,
                       broadcast_trusted=step.broadcast_trusted, detected=bool(sample.detected))


def _cautious(defended_m: float, broadcast_m: float) -> float:
    """The distance to follow: the defence's while the broadcast agrees with it, else the nearer (the
    broadcast's alone where the defence has none)."""
    if not math.isfinite(defended_m):
        return broadcast_m
    return defended_m if abs(defended_m - broadcast_m) <= AGREE_M else min(defended_m, broadcast_m)
