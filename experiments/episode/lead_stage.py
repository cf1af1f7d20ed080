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
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from racf.controllers.following import FollowDecision, FollowingConfig, LeadFollower, LeadSpeed
from racf.controllers.lead_perception import LeadPerception, lane_in_camera
from racf.controllers.perception import PerceptionSample

__all__ = ["LeadStage", "LeadStep", "LANE_AHEAD_M", "NO_LEAD"]

#: How far along the lane ahead the car looks for a car, m.
LANE_AHEAD_M = 4.0
#: Unseen this long (no detection, no LiDAR track), the car ahead is lost: it drove out of sight (a
#: curve takes it out of the camera's 70 degrees at 1 m), and a carried distance would hold the car
#: back for nothing. The defence and the speed estimate start again, and the policy lets the car
#: drive on, as a production adaptive cruise does, s.
LOST_AFTER_S = 0.5


@dataclass(frozen=True)
class LeadStep:
    """What the following stage made of one control step (for the log)."""

    sample: PerceptionSample
    d_fused: float
    lead_mps: float
    decision: FollowDecision


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

    def reset(self) -> None:
        self.perception.reset()
        self.estimator.reset()
        self.speed.reset()
        self.last = NO_LEAD
        self._unseen_s = 0.0
        self._lost = False

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
            d = float(self.estimator.estimate(sample, closing, dt, yaw_rate_radps=yaw_rate))
        lead = self.speed.update(sample.d_meas, sample.lidar_m, sample.d_size, speed, dt, frame_new)
        decision = self.follower.step(d - self.bumper_m, speed - lead)
        self.last = LeadStep(sample, d, lead, decision)
        return self.last
