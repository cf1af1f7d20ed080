"""The car's side of an episode: what a real car's software is told, and what it works out from it.

The car knows its own build (:class:`CarCalibration`), its mission (:class:`Mission`: the
route on the map, its targets and their stop lines, the cruise speed) and its own clock. Each
step it reads the observation and nothing else: its pose comes from its own localisation
filter (odometry and the gyro predict, the localiser's fixes correct), and that pose places
the map's targets in view, drives the lane follower and says which target is next. It never
sees ``info`` or the env; the calibration and the mission come from the episode's plan, made
once before the episode (:mod:`racf.experiments.episode.plan`). Ground truth is the referee's
(:mod:`racf.experiments.episode.referee`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from racf.controllers import (BrakeDecision, BrakingConfig, CameraModel, Perception, PerceptionSample, PoseFilter,
                         RouteFollower, StopSignBraker)
from racf.experiments.car.stage import CarView, TargetTrack
from racf.sim.sensors import TIMESTAMP_FIELDS
from racf.sim.sensors.localiser import LOCALISATIONS
from racf.sim.world.drives import RouteTarget
from racf.sim.world.road_graph import Path
from racf.sim.world.route_plan import current_slot

__all__ = ["CarCalibration", "Mission", "CarStep", "Car", "sign_depth_at_line", "route_follower", "map_bearing", "lowest_cap"]

#: The tyres' grip bounds the body's acceleration (friction 0.75 x g): a faster change of the
#: encoder's speed is the wheels spinning up or locking, not the car (m/s^2).
MAX_ACCEL_MPS2 = 0.75 * 9.81
_FIX_TIME, _SCAN_TIME = TIMESTAMP_FIELDS.index("gps"), TIMESTAMP_FIELDS.index("lidar")
_FRAME_TIME = TIMESTAMP_FIELDS.index("rgb")


@dataclass(frozen=True)
class CarCalibration:
    """The car's build as its software knows it (body frame: x forward, y left).

    Attributes:
        camera: the camera's horizontal intrinsics.
        camera_xy_m: the camera's position on the body, m.
        bumper_x_m: the front bumper's position ahead of the body origin, m.
        rear_axle_x_m: the rear axle's position on the body, m (negative: behind the origin).
        lidar_xy_m: the LiDAR's position on the body, m (the scan plane's origin).
        camera_height_m: the camera's height above the floor, m.
    """

    camera: CameraModel
    camera_xy_m: tuple[float, float]
    bumper_x_m: float
    rear_axle_x_m: float
    lidar_xy_m: tuple[float, float]
    camera_height_m: float = 0.172

    @property
    def camera_lever_m(self) -> float:
        """The camera's distance ahead of the rear axle, m (the kinematic branch's lever)."""
        return round(self.camera_xy_m[0] - self.rear_axle_x_m, 6)


@dataclass(frozen=True)
class Mission:
    """What the car is told before it starts: the route's path, its targets in order (the map's
    stop signs the route meets, and a crate's place when the operator put one on the route), the
    cruise speed, roughly where along the route it starts (None: anywhere) and the stages it engages
    beside the car's own loop (the names of ``racf.car_stages`` parts: ``following`` to follow the
    car ahead, a plug-in's)."""

    path: Path
    targets: tuple[RouteTarget, ...]
    cruise_mps: float
    start_hint_m: float | None = None
    #: The car stages engaged (``racf.experiments.car.stage``), by name, in the order they run.
    stages: tuple[str, ...] = ()
    #: The hardest a target of the mission may brake, m/s^2, as the scenario states it (the
    #: supervisor's a_max, a rule of the road like RSS's; None: none stated).
    target_decel_mps2: float | None = None
    #: The hardest a target of the mission may pull away, m/s^2, as the scenario states it (None: none stated).
    target_accel_mps2: float | None = None


@dataclass(frozen=True)
class CarStep:
    """What the car did on one step (for the log): its action and how it got there."""

    action: np.ndarray
    control: bool
    slot: int
    sample: PerceptionSample
    d_fused: float
    decision: BrakeDecision
    pose: np.ndarray
    scan_new: bool
    tracked_xy: tuple[float, float]
    frame_new: bool = True
    #: Each engaged stage's last word (``StageLimit``), by stage name.
    stages: dict = field(default_factory=dict)


#: Where a sign the map does not list has its stop line: where the sign stands (the rule the map's
#: own lines follow: each lies within 0.02 m of its sign's projection onto the lane), m past the line.
UNMAPPED_SIGN_PAST_LINE_M = 0.0


def sign_depth_at_line(calibration: CarCalibration, target: RouteTarget) -> float:
    """The target's camera depth when the front bumper is on its stop line, m (from the map and the
    car's build; a target the map does not list: by the rule of the road, ``UNMAPPED_SIGN_PAST_LINE_M``)."""
    camera_to_bumper = float(calibration.bumper_x_m - calibration.camera_xy_m[0])
    return camera_to_bumper + (target.target_s - target.stop_s if getattr(target, "mapped", True) else UNMAPPED_SIGN_PAST_LINE_M)


def lowest_cap(braker_cap: float, said, stages=()) -> float:
    """The car's speed cap: the lowest of its braker's and every stage's (``StageLimit``): no stage can
    raise what another limits, but for a supervising stage that stands in for the stage whose track it
    supervises (``stands_in``: its cap replaces that stage's, and it answers for never being bolder)."""
    replaced = {s.supervises for s in stages if getattr(s, "stands_in", False)}
    kinds = [getattr(s, "publishes", None) for s in stages] or [None] * len(said)
    return min([braker_cap, *(limit.speed_cap_mps for limit, kind in zip(said, kinds) if kind not in replaced)])


def route_follower(path: Path, cruise_mps: float, start_s: float = 0.0) -> RouteFollower:
    """Lane following along ``path`` (an approach's or a drive's), starting ``start_s`` m along it."""
    follower = RouteFollower(path.points, path.headings, path.arclength, path.curvature, cruise_mps)
    follower.reset(start_s)
    return follower


def _from_camera(calibration: CarCalibration, target: RouteTarget, pose: np.ndarray) -> tuple[float, float, float]:
    """The map's target from the camera: (dx, dy) in the map frame and the car's yaw."""
    cx, cy = calibration.camera_xy_m
    x, y, yaw = (float(v) for v in pose)
    c, s = np.cos(yaw), np.sin(yaw)
    tx, ty = target.target.centre[:2]
    return tx - (x + c * cx - s * cy), ty - (y + s * cx + c * cy), yaw


def camera_offset(calibration: CarCalibration, target: RouteTarget, pose: np.ndarray) -> tuple[float, float]:
    """Where the map puts ``target`` from the camera, from the car's pose: (ahead along the optical
    axis, left of it), m."""
    dx, dy, yaw = _from_camera(calibration, target, pose)
    c, s = np.cos(yaw), np.sin(yaw)
    return float(c * dx + s * dy), float(-s * dx + c * dy)


def map_bearing(calibration: CarCalibration, target: RouteTarget, pose: np.ndarray) -> float:
    """Bearing of ``target`` from the camera's optical axis (rad, left positive), from the map and the car's pose.

    NaN when the map says the camera cannot see the target's face (a stop sign showing
    the car its back): no detection is its then.
    """
    dx, dy, _ = _from_camera(calibration, target, pose)
    face = getattr(target.target, "face_yaw", None)
    if face is not None and -(dx * np.cos(face) + dy * np.sin(face)) < 0.0:
        return float("nan")
    ahead, left = camera_offset(calibration, target, pose)
    return float(np.arctan2(left, ahead))


class Car:
    """The car's software for one episode: localisation, perception, estimator, braker, lane follower.

    Args:
        calibration: the car's build.
        mission: the route and its targets.
        perceptions: one perception pipeline per target kind (``sign``, ``obstacle``).
        estimator: the distance estimator (``DistanceEstimator`` protocol).
        braking: the braking controller's parameters.
        dt: the car's loop period, s (one observation per call of :meth:`step`).
        control_every: the controller runs every this many steps and holds its action between;
            the localisation filter runs every step.
        localisation: the env's (``racf.sim.sensors.localiser.LOCALISATIONS``): ``qcar2``, the car runs its
            own filter on odometry, the gyro and the localiser's fixes; ``true``, the fix is the
            true pose at every step and the car takes it as it is (the ablation).
        existence: the existence stage (``racf.experiments.car.existence.ExistenceStage``) for a
            defence that answers ``stands()``: its witnesses reach the defence with each sample, and
            its verdict, not the detector's, drives the braker's track. None: the detector's.
        stages: the stages the mission engages (``racf.experiments.car.stage.CarStage``): each one's
            speed cap joins the braker's, the lowest wins.
    """

    def __init__(self, calibration: CarCalibration, mission: Mission, perceptions: dict[str, Perception],
                 estimator, braking: BrakingConfig, dt: float, control_every: int = 1,
                 localisation: str = "qcar2", existence=None, stages=()) -> None:
        if localisation not in LOCALISATIONS:
            raise ValueError(f"localisation must be one of {LOCALISATIONS}, got {localisation!r}")
        if not mission.targets:
            raise ValueError("a mission needs at least one target")
        self.calibration = calibration
        self.mission = mission
        self.perceptions = perceptions
        self.estimator = estimator
        self.braking = braking
        self.dt = float(dt)
        self.every = int(control_every)
        self.existence = existence
        self.stages = tuple(stages)
        self._said = {stage.name: stage.idle() for stage in self.stages}
        self.pose_filter = PoseFilter() if localisation == "qcar2" else None
        self._step = 0
        self._fix_time = -math.inf
        self._scan_time = -math.inf
        self._frame_time = -math.inf
        self._pose = np.zeros(3)
        self._odometry_mps = math.nan
        self.slot = 0
        self.follower: RouteFollower | None = None
        self.perception = self.braker = None
        self._decision: BrakeDecision | None = None
        self._sample: PerceptionSample | None = None
        self._action = np.zeros(2, np.float32)
        self._d_fused = math.nan

    @property
    def target(self) -> RouteTarget:
        return self.mission.targets[self.slot]

    @property
    def pose(self) -> np.ndarray:
        """The car's own pose estimate (x, y m, yaw rad, map frame)."""
        return self._pose.copy()

    def _begin(self, slot: int) -> None:
        self.slot = slot
        self.estimator.reset()
        self.perception = self.perceptions[self.target.kind]
        self.perception.reset()
        if self.existence is not None:
            self.existence.reset()
        self._left_at_edge = False
        self.braker = StopSignBraker(self.braking, sign_depth_at_line(self.calibration, self.target))
        self._decision = None

    def _localise(self, obs: dict, first: bool) -> float:
        """Updates the pose from this step's odometry and any new fix; returns the gyro's yaw rate
        less the filter's bias estimate, rad/s."""
        speed, yaw_rate = float(obs["state"][0]), float(obs["state"][2])
        # Odometry for the pose: the encoder's speed, changing no faster than the tyres allow
        # (a launch from the stop line spins the wheels up well before the body follows).
        step = MAX_ACCEL_MPS2 * self.dt
        self._odometry_mps = speed if first else min(max(speed, self._odometry_mps - step), self._odometry_mps + step)
        fix, fix_time = np.asarray(obs["gps"], np.float64), float(obs["timestamps"][_FIX_TIME])
        new_fix, self._fix_time = fix_time != self._fix_time, fix_time
        if self.pose_filter is None:
            self._pose = fix.copy()
            return yaw_rate
        if first:
            self.pose_filter.reset(fix)
        else:
            # No slip at the rear axle: the body origin moves sideways at the yaw rate x its lever arm.
            lateral = (yaw_rate - self.pose_filter.gyro_bias) * -self.calibration.rear_axle_x_m
            self.pose_filter.predict(self._odometry_mps, yaw_rate, self.dt, lateral_speed=lateral)
            if new_fix:
                self.pose_filter.correct(fix)
        self._pose = self.pose_filter.pose
        return yaw_rate - self.pose_filter.gyro_bias

    def _unmapped_in_view(self) -> bool:
        """Whether a target the map does not list should still be in view: its last detection's box
        lay more than its own width from the image's sides (a sign that vanished there went out of
        the picture, as a box moves by about its width a frame when it leaves; one that vanished
        further in was hidden)."""
        detection = self._sample.detection or self.perception.last_raw_detection
        if detection is not None:
            x0, _, x1, _ = detection.box
            self._left_at_edge = x0 <= x1 - x0 or x1 >= self.calibration.camera.width - (x1 - x0)
        return not self._left_at_edge

    def _stands(self) -> bool:
        """Whether a target stands ahead this step: the defence's verdict when it gives one
        (``stands()``, None: it defers), else the detector's."""
        verdict = getattr(self.estimator, "stands", None)
        said = verdict() if callable(verdict) else None
        return self._sample.detected if said is None else bool(said)

    def _track(self, bearing: float | None) -> TargetTrack:
        """What the car's own loop believes of its target this step (the supervision contract): the
        defended distance and the braker's cap, the perception's witnesses and the map's place for it."""
        sample, target = self._sample, self.target
        mapped = bearing is not None and math.isfinite(bearing)
        map_m = camera_offset(self.calibration, target, self._pose)[0] if mapped else math.nan
        listed = getattr(target, "mapped", True)
        line_m = target.stop_s - (self.follower.progress_m + self._bumper_ahead_of_axle) if listed else math.nan
        return TargetTrack(target.kind, self._d_fused, self._decision.speed_cap_mps, depth_m=sample.d_meas,
                           lidar_m=sample.lidar_m, size_m=sample.d_size, map_m=map_m,
                           stop_at_m=sign_depth_at_line(self.calibration, target), line_m=line_m,
                           detected=bool(sample.detected), index=self.slot, bearing_rad=sample.bearing_rad)

    def step(self, obs: dict) -> CarStep:
        """One 50 Hz step of the car's software on one observation; returns its action and why."""
        first = self._step == 0
        yaw_rate = self._localise(obs, first)
        x, y, yaw = self._pose
        if first:
            start_s, _ = self.mission.path.project(np.array([x, y]), s_hint=self.mission.start_hint_m)
            self.follower = route_follower(self.mission.path, self.mission.cruise_mps, start_s)
            self._bumper_ahead_of_axle = self.calibration.bumper_x_m - self.follower.steering.config.front_axle_m
            self._begin(0)
            for stage in self.stages:
                stage.reset()
        # The car's own localisation and the map say which target is next (the env's rule, on the car's pose).
        slot = current_slot(self.mission.targets, self.slot, self.follower.progress_m + self._bumper_ahead_of_axle)
        if slot != self.slot:
            self._begin(slot)
        speed = float(obs["state"][0])
        # A scan is handed to the tracker once, on the step it arrives (the LiDAR runs at 10 Hz).
        scan_time = float(obs["timestamps"][_SCAN_TIME])
        scan_new, self._scan_time = scan_time != self._scan_time, scan_time
        control = self._decision is None or self._step % self.every == 0
        frame_new = False
        if control:
            dt = self.dt * self.every
            # The camera runs slower than the loop: its detector and depth stages run on new frames only.
            frame_time = float(obs["timestamps"][_FRAME_TIME])
            frame_new, self._frame_time = frame_time != self._frame_time, frame_time
            # A target the map does not list has no bearing to check detections against.
            bearing = map_bearing(self.calibration, self.target, self._pose) if getattr(self.target, "mapped", True) else None
            # No slip at the rear axle: the camera moves sideways at yaw rate x its lever arm.
            lateral = yaw_rate * (self.calibration.camera_xy_m[0] - self.calibration.rear_axle_x_m)
            # The scan's beams were taken over its revolution: the tracker moves each cluster on by its age.
            ages = np.maximum(self._step * self.dt - obs["lidar_beam_times"], 0.0) if scan_new else None
            self._sample = self.perception.process(obs["rgb"], obs["depth"][..., 0], obs["lidar"] if scan_new else None,
                                                   speed=speed, yaw_rate=yaw_rate, lateral_speed=lateral, dt=dt,
                                                   map_bearing=bearing, new_frame=frame_new, beam_age_s=ages)
            if self.existence is not None and frame_new:
                to_line = self.target.stop_s - (self.follower.progress_m + self._bumper_ahead_of_axle)
                witnesses = self.existence.observe(obs["rgb"], obs["depth"][..., 0], obs["lidar"], self.target,
                                                   self._pose, to_line, self.perception, self._sample,
                                                   t_s=self._frame_time)
                self._sample = replace(self._sample, witnesses=witnesses)
            elif self.existence is not None:
                self._sample = replace(self._sample, witnesses=self.existence.witnesses)
            self._d_fused = float(self.estimator.estimate(self._sample, speed, dt, yaw_rate_radps=yaw_rate))
            in_fov = self._unmapped_in_view() if bearing is None else (
                math.isfinite(bearing) and abs(bearing) <= self.calibration.camera.half_hfov_rad)
            if not in_fov and self._sample.witnesses is not None and self._sample.witnesses.source == "detector":
                # The existence stage found the sign off its map entry (a moved sign): in view by where it was seen.
                in_fov = self._unmapped_in_view()
            self._decision = self.braker.step(self._stands(), self._d_fused, speed, dt, expected_in_view=in_fov)
            cap = self._decision.speed_cap_mps
            if self.stages:
                # The tracks published this step: the car's own target's first, then each stage's as it runs.
                tracks = {self.target.kind: self._track(bearing)}
                view = CarView(obs, self._pose, self.mission.path, self.follower.progress_m, speed, yaw_rate, lateral,
                               dt, frame_new, scan_new, ages, tracks)
                for stage in self.stages:
                    said = self._said[stage.name] = stage.step(view)
                    if said.track is not None:
                        tracks[said.track.kind] = said.track
                cap = lowest_cap(cap, [self._said[stage.name] for stage in self.stages], self.stages)
            self._action = np.array(self.follower.act(x, y, yaw, speed, dt, cap), np.float32)
        self._step += 1
        track = self.perception.lidar.state.position  # camera-relative; + the camera's body position
        cam_x, cam_y = self.calibration.camera_xy_m
        return CarStep(self._action.copy(), control, self.slot, self._sample, self._d_fused, self._decision,
                       self._pose.copy(), scan_new, (track[0] + cam_x, track[1] + cam_y), frame_new, dict(self._said))
