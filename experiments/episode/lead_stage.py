"""The car's following stage: the car ahead perceived, its distance defended, and a speed cap.

Part of the car's software (:class:`~racf.experiments.episode.car.Car`), engaged when the mission
says the car drives in traffic (``Mission.follow``: the operator's adaptive cruise switch). Each
control step it places the lane ahead in the camera from the map and the car's own pose,
perceives the car ahead on it (:class:`~racf.controllers.lead_perception.LeadPerception`), asks
the defence for the distance with the *relative* motion (the car's speed less the lead's, as
:class:`~racf.controllers.following.LeadSpeed` estimates it while the witnesses agree): every
estimator's kinematics, ODCA's branch and the EKF's prediction, then follow a target that moves
at a constant speed; and turns the defended gap into a speed cap (:class:`LeadFollower`). Like
the rest of the car, it reads the observation, the map and its own estimates, never ``info``.

A defence that answers whether its target stands (``existence = True``, the vote) is given the
car ahead's witnesses (:func:`~racf.controllers.lead_existence.lead_witnesses`) with each sample,
and the depth's distance is the upright surface's in the detector's mask. The car then follows a
car only once the defence says one stands, and lets it go when it has not said so for
``DOUBT_AFTER_S``: a picture of a car (a phantom) never holds the car back.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from racf.controllers.existence import NO_WITNESSES
from racf.controllers.following import FollowDecision, FollowingConfig, LeadFollower, LeadSpeed
from racf.controllers.lead_existence import lead_witnesses
from racf.controllers.lead_perception import LeadPerception, lane_in_camera
from racf.controllers.perception import PerceptionSample

__all__ = ["LeadStage", "LeadStep", "LANE_AHEAD_M", "NO_LEAD", "DOUBT_AFTER_S"]

#: How far along the lane ahead the car looks for a car, m.
LANE_AHEAD_M = 4.0
#: Unseen this long (no detection, no LiDAR track), the car ahead is lost: it drove out of sight (a
#: curve takes it out of the camera's 70 degrees at 1 m), and a carried distance would hold the car
#: back for nothing. The defence and the speed estimate start again, and the policy lets the car
#: drive on, as a production adaptive cruise does, s.
LOST_AFTER_S = 0.5
#: With a defence that answers whether a car stands: a followed car that it has not said stands for
#: this long is let go (its vote may drop for a frame or two: the car ahead at the picture's edge), s.
DOUBT_AFTER_S = 0.3


@dataclass(frozen=True)
class LeadStep:
    """What the following stage made of one control step (for the log)."""

    sample: PerceptionSample
    d_fused: float
    lead_mps: float
    decision: FollowDecision
    stands: float = math.nan  # the defence's verdict that a car stands ahead (1/0; NaN: it gives none)


NO_LEAD = LeadStep(PerceptionSample(None, math.nan, 0.0, math.nan, math.nan), math.nan, math.nan,
                   FollowDecision(math.inf, math.nan, math.nan, False))


class LeadStage:
    """Perception, defence and policy for the car ahead.

    Args:
        perception: the lead's perception pipeline.
        estimator: the defence for its distance (its own instance: its state is the lead's).
        bumper_ahead_of_camera_m: the front bumper's distance ahead of the camera, m (the gap is
            the camera's distance less it).
        camera_xy_m: the camera's place on the body, m.
        config: the following controller's settings.
    """

    def __init__(self, perception: LeadPerception, estimator, bumper_ahead_of_camera_m: float,
                 camera_xy_m: tuple[float, float], config: FollowingConfig | None = None) -> None:
        self.perception = perception
        self.estimator = estimator
        self.bumper_m = float(bumper_ahead_of_camera_m)
        self.camera_xy_m = camera_xy_m
        self.config = config or FollowingConfig()
        self.follower = LeadFollower(self.config)
        self.speed = LeadSpeed(self.config)
        self.last = NO_LEAD
        self._unseen_s = 0.0
        self._lost = False
        self.existence = bool(getattr(estimator, "existence", False))
        self._witnesses = NO_WITNESSES
        self._doubt_s = math.inf  # since the defence last said a car stands ahead (inf: never)

    def reset(self) -> None:
        self.perception.reset()
        self.estimator.reset()
        self.speed.reset()
        self.last = NO_LEAD
        self._unseen_s = 0.0
        self._lost = False
        self._witnesses = NO_WITNESSES
        self._doubt_s = math.inf

    def step(self, obs: dict, pose: np.ndarray, path, progress_m: float, speed: float, yaw_rate: float,
             lateral: float, dt: float, frame_new: bool, scan_new: bool, ages) -> LeadStep:
        """One control step on the observation, the car's pose estimate and its progress along ``path``."""
        lane = None
        if frame_new:
            ahead = (path.arclength >= progress_m) & (path.arclength <= progress_m + LANE_AHEAD_M)
            lane = lane_in_camera(path.points[ahead], pose, self.camera_xy_m)
        closing = speed - self.speed.lead_mps
        # The tracker carries the lead's point by the relative motion, as the defence does.
        sample = self.perception.process(obs["rgb"], obs["depth"][..., 0], obs["lidar"] if scan_new else None,
                                         lane=lane, speed=closing, yaw_rate=yaw_rate, lateral_speed=lateral, dt=dt,
                                         new_frame=frame_new, beam_age_s=ages)
        stands = math.nan
        if self.existence:
            sample = self._with_witnesses(sample, obs, frame_new)
        seen = sample.detected or math.isfinite(sample.lidar_m)
        self._unseen_s = 0.0 if seen else self._unseen_s + dt
        if self._unseen_s > LOST_AFTER_S:
            if not self._lost:  # lost just now: what the car knew of this lead is of no use for the next
                self.estimator.reset()
                self.speed.reset()
                self._lost = True
                self._doubt_s = math.inf
            d = math.nan
        else:
            self._lost = False
            d = float(self.estimator.estimate(sample, closing, dt, yaw_rate_radps=yaw_rate))
            if self.existence:
                stands = float(bool(self.estimator.stands()))
                self._doubt_s = 0.0 if stands else self._doubt_s + dt
                if self._doubt_s > DOUBT_AFTER_S:
                    d = math.nan  # no car said to stand ahead (yet, or for a while): nothing to follow
        lead = self.speed.update(sample.d_meas, sample.lidar_m, sample.d_size, speed, dt, frame_new)
        decision = self.follower.step(d - self.bumper_m, speed - lead)
        self.last = LeadStep(sample, d, lead, decision, stands)
        return self.last

    def _with_witnesses(self, sample: PerceptionSample, obs: dict, frame_new: bool) -> PerceptionSample:
        """The sample with the car ahead's witnesses (read on new frames, carried between them), and the
        depth's distance the upright surface's where one stands in the mask."""
        if frame_new:
            self._witnesses = lead_witnesses(sample, obs["depth"][..., 0], self.perception.camera)
        w = self._witnesses
        return replace(sample, witnesses=w, d_meas=w.depth_m if w.depth else sample.d_meas)
