"""``RACF/QCar2-v4``: the QCar 2 on the indoor map, approaching a stop sign.

Plumbing only (step order, seeding, spaces, sensor scheduling, reward and termination); the
world, the car and the sensors are built by their own modules. Step order: validate action ->
write controls -> ``substeps`` physics steps, after each of which the swept LiDAR casts the
samples whose time has come and the camera takes a frame if one falls due -> read the other
sensors that are due (each holds its last reading and its timestamp) -> the radio -> ground
truth -> reward and flags. Each version's changes: ``docs/concepts/environment.md``.
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np

from racf.sim._gl import ensure_gl_backend
from racf.sim.env.config import RESET_OPTIONS, EnvConfig
from racf.sim.world.manager import WorldManager
from racf.sim.radio.channel import Radio, empty_rows
from racf.sim.env.chase_view import ChaseView
from racf.sim.env.contacts import Contacts
from racf.sim.env.spaces import env_spaces
from racf.sim.env.stickers import Stickers
from racf.sim.env.truth import WorldTruth
from racf.sim.sensors import (TIMESTAMP_FIELDS, DepthCamera, Lidar2D, LocalisationFix, RGBCamera, RGBDCameraRig, Sensor,
                         VehicleStateSensor)
from racf.sim.sensors.a2m12 import A2M12Lidar
from racf.sim.vehicle import QCar2
from racf.sim.world.drives import RouteTarget
from racf.sim.world.route_plan import current_slot, plan_route
from racf.sim.world.road_graph import Path
from racf.sim.world.scene import load_model, obstacle_body
from racf.sim.world.sign_patch import PatchPlacement
from racf.sim.world.obstacles import Obstacle, obstacles
from racf.sim.world.stop_signs import StopSign, stop_signs

ensure_gl_backend()
import mujoco  # noqa: E402

__all__ = ["QCar2Env", "TIMESTAMP_FIELDS"]

#: Sensors whose noise comes from the navigation generator (apart from the cameras' and the
#: LiDAR's, so that adding them left those draws as they were).
_NAV_SENSORS = ("gps", "state")
#: Each sensor's entry in the ``timestamps`` observation.
_STAMP_SLOT = {name: i for i, name in enumerate(TIMESTAMP_FIELDS)}


class QCar2Env(gym.Env):
    """The QCar 2 driving a road-graph route towards one of the four stop signs.

    Observation (``Dict``): ``rgb`` (H, W, 3) uint8; ``depth`` (H, W, 1) float32 m, 0 = no
    return (both the last frame, taken at ``camera_hz``: 30 Hz on the ``qcar2`` profile);
    ``lidar`` (360,) float32 m, inf = no return, bin i at i deg counter-clockwise from the
    car's forward (the last complete revolution, on ``qcar2`` swept over 0.1 s through Quanser's
    driver: ``racf.sim.sensors.a2m12``); ``lidar_beam_times`` (360,) float64, when each bin was
    measured, s; ``gps`` (3,) float32, the localiser's fix (x, y m, yaw rad, map frame), one per
    scan with Quanser's drift and noise (``localisation="qcar2"``) or the true pose every step
    (``"true"``); ``state`` (4,) float32, the encoder's speed, the steering servo's angle and the
    IMU's yaw rate and acceleration (``racf.sim.sensors.STATE_FIELDS``); ``timestamps`` (5,)
    float64, when each held reading was taken (``TIMESTAMP_FIELDS``' order); ``radio`` (800,)
    uint8, the signed messages (100 bytes each) the world's vehicles broadcast that arrived this step (zeros: none),
    and ``radio_times`` (8,), when each arrived (``racf.sim.radio``). Action (``Box``): [speed
    command m/s, steering rad].

    ``reset(options=...)`` sets up one of two kinds of episode:

    - an approach: ``sign`` (0..3) or ``obstacle`` (0..1, a crate on a lane with a virtual
      stop line before it), ``cruise_speed`` (m/s; the car starts moving at it) and
      ``run_up_m`` (distance from the front bumper to the stop line at the start);
    - a drive (``racf.sim.world.drives``): ``route`` (road-graph nodes), ``start_s_m``,
      ``lateral_offset_m``, ``heading_error_rad``, ``crate`` (a crate index on the route, which
      ends the drive, or None) and ``cruise_speed``. Its targets are the stop signs whose lines the
      route crosses in their direction (and the crate); the next becomes current once the bumper
      is ``route_plan.PASS_LINE_M`` past the current one's line (``info["target_slot"]``).

    Ground truth is in ``info`` (the ``sign_*`` keys describe the current target, sign or crate;
    ``target_kind`` says which), read from the world after every manager acted
    (``racf.sim.env.ground_truth``): ``d_true`` (target depth along the camera axis, m),
    ``d_true_euclid``, ``sign_bearing``, ``sign_mask``, ``sign_in_view``, ``target_stands``,
    ``pose``, ``speed``, ``route_s``, ``lateral_error``, ``dist_to_stop_line`` (front bumper to the
    stop line along the route, m), ``collision``, ``collision_with`` (what the car first touched),
    ``off_road``, ``radio_sent`` and ``radio_delivered`` (messages this step), and what each world
    manager reports (``racf.sim.world.manager``: the env knows none of them). ``sign_mask`` and
    ``sign_in_view`` describe the held camera frame, ``d_true`` and ``sign_bearing`` the car's pose
    now. The car's side reads the observation only.

    Reward per step: metres of route progress, minus 0.1 x lateral error (m), minus 10
    on leaving the road or colliding (both end the episode).
    Examples: ``docs/concepts/environment.md``.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 50}

    def __init__(self, render_mode: str | None = None, config: EnvConfig | None = None, **overrides: Any) -> None:
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be None or one of {self.metadata['render_modes']}, got {render_mode!r}")
        if config is not None and overrides:
            raise ValueError("pass either config=EnvConfig(...) or keyword overrides, not both")
        self.config = config or EnvConfig.from_kwargs(**overrides)
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "render_fps": self.config.control_hz}

        # The world's managers: what the env's ``world`` setting brings (a scenario's); the env knows none.
        self.world: tuple[WorldManager, ...] = tuple(self.config.world)
        self.model = load_model(sign_geometry=self.config.sign,
                                world_xml="".join(manager.scene_xml() for manager in self.world))
        for manager in self.world:
            manager.bind(self.model)
        self._reset_options = (*RESET_OPTIONS, *(m.option for m in self.world if m.option))
        self.model.opt.timestep = self.config.physics_dt_s
        self.data = mujoco.MjData(self.model)
        self.car = QCar2(self.model, self.config.vehicle)
        #: Body origin to the front bumper along x, m (the car's MJCF).
        self._bumper_ahead_m = float(self.model.site("front_bumper").pos[0])
        self.rig = RGBDCameraRig(self.config.camera)
        self.rig.configure_model(self.model)
        true_pose = self.config.localisation == "true"
        cfg = self.config
        self.lidar: Sensor = (A2M12Lidar(cfg.a2m12, cfg.lidar_hz, cfg.physics_dt_s) if cfg.lidar_model == "a2m12"
                              else Lidar2D(cfg.lidar))
        self._sweeping = isinstance(self.lidar, A2M12Lidar)
        self.sensors: tuple[Sensor, ...] = (
            RGBCamera(self.rig), DepthCamera(self.rig), self.lidar,
            LocalisationFix(self.car, self.config.localiser, fix_period_s=1.0 / self.config.lidar_hz, exact=true_pose),
            VehicleStateSensor(self.car, self.config.odometry, rate_hz=self.config.state_hz))
        lidar_every = self.config.decimation(self.config.lidar_hz)
        self._decimation = {"lidar": lidar_every,
                            "gps": 1 if true_pose else lidar_every,  # a fix per matched scan
                            "state": self.config.decimation(self.config.state_hz)}
        self.observation_space, self.action_space = env_spaces(self.sensors, self.lidar.shape, self.config.vehicle)
        self.contacts = Contacts(self.model, self.world)
        self.stickers = Stickers(self.model, len(stop_signs(self.config.sign)))
        self._viewer, self._collision_with, self._moving = None, None, ()
        # Crates stand on the map only in their own episodes (as a test operator would place one).
        self._crates = [(self.model.body(obstacle_body(o.index)).id, self.model.body(obstacle_body(o.index)).pos.copy())
                        for o in obstacles()]
        # The truth follows a target's body wherever a manager moved it (``racf.sim.env.truth``).
        self.truth = WorldTruth(self.model, self.config.sign, self.rig.intrinsics)
        first = stop_signs(self.config.sign)[0]
        self._path: Path = first.path
        self._targets: tuple[RouteTarget, ...] = (RouteTarget(first, first.stop_s, first.stop_s),)
        self._slot = 0
        self._stamps, self._beam_times = np.zeros(len(TIMESTAMP_FIELDS)), np.zeros(self.lidar.shape)
        self._obs: dict[str, np.ndarray] = {}
        self.radio, self._radio_rows = Radio(self.config.radio), empty_rows()
        # Physics steps and camera frames since the reset; the noise generators (drawn at each reset).
        self._step = self._substep = self._frames = 0
        self._route_s = 0.0
        self._sensor_rng, self._nav_rng = np.random.default_rng(), np.random.default_rng()

    # -- gymnasium API --------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        super().reset(seed=seed)
        options = dict(options or {})
        unknown = sorted(set(options) - set(self._reset_options))
        if unknown:
            raise ValueError(f"unknown reset option(s) {unknown}; allowed: {list(self._reset_options)}")
        plan = plan_route(options, sign_geometry=self.config.sign, bumper_ahead_m=self._bumper_ahead_m,
                          max_speed_mps=self.config.vehicle.max_speed_mps,
                          cruise_speeds_mps=self.config.cruise_speeds_mps, rng=self.np_random)
        path, targets, crate, start_s, pose, speed = (plan.path, plan.targets, plan.crate, plan.start_s,
                                                      plan.start_pose, plan.cruise_mps)

        # One generator for the cameras' and the LiDAR's noise and one for the fix's and the
        # odometry's, both derived from the env's seeded generator.
        self._sensor_rng = np.random.default_rng(self.np_random.integers(2**63))
        self._nav_rng = np.random.default_rng(self.np_random.integers(2**63))
        # The radio's draws: a child of the navigation seed, so that adding it moved no other draw.
        self.radio.reset(np.random.default_rng(self._nav_rng.bit_generator.seed_seq.spawn(1)[0]))
        self._path, self._targets, self._slot = path, targets, 0
        self._cruise_speed = float(speed)
        for i, (body, home) in enumerate(self._crates):
            self.model.body_pos[body] = home if crate == i else home + np.array([0.0, 0.0, -5.0])
        self.hide_sign_patches()  # an env shared by episodes: no sticker outlives its episode
        mujoco.mj_resetData(self.model, self.data)
        self._collision_with = None
        for manager in self.world:
            manager.reset(self.model, self.data, options.get(manager.option) if manager.option else None,
                          self.config.physics_dt_s, self.config.max_episode_s)
        self._moving = tuple(manager for manager in self.world if manager.moving)
        self.rig.invalidate()  # the crates may have moved; the car may start where it started before
        self._route_s = start_s
        self.car.place(self.data, *pose, speed=float(speed))
        mujoco.mj_forward(self.model, self.data)
        self._step = self._substep = self._frames = 0
        self._obs = {}
        self.truth.forget_view()
        for sensor in self.sensors:
            sensor.reset(self._rng_of(sensor))
        self._read_sensors(force=True)
        self._listen()
        return self._observation(), self._info(collision=False, off_road=False)

    def step(self, action):
        action = np.asarray(action, dtype=np.float64)
        if action.shape != self.action_space.shape:
            raise ValueError(f"action must have shape {self.action_space.shape} (speed m/s, steering rad), got {action.shape}")
        if not np.isfinite(action).all():
            raise ValueError(f"action must be finite (speed m/s, steering rad), got {action.tolist()}")
        s_before = self._route_s
        self.car.apply(self.data, float(action[0]), float(action[1]))
        self._advance_physics()
        self._step += 1
        self._read_sensors(force=False)
        self._listen()
        self._update_route_progress()
        collision = self._collided()
        off_road = abs(self._lateral) > self.config.off_road_m
        info = self._info(collision=collision, off_road=off_road)
        reward = self._reward(self._route_s - s_before, collision, off_road)
        terminated = collision or off_road or self._route_s >= self._path.length - 0.05
        truncated = self._step * (1.0 / self.config.control_hz) >= self.config.max_episode_s - 1e-9
        return self._observation(), reward, terminated, truncated, info

    # -- stickers on the stop signs (sim.world.sign_patch) ---------------------------------
    def show_sign_patch(self, sign_index: int, texture: np.ndarray, placement: PatchPlacement) -> None:
        """Prints a sticker on stop sign ``sign_index``: ``texture`` ((H, W, 3) uint8, row 0 its top
        edge as seen from in front; resized to the scene's texture) where ``placement`` says. The
        camera and the LiDAR see it from the next reading on."""
        tex = self.stickers.show(self.model, self.config.sign, sign_index, texture, placement)
        mujoco.mj_kinematics(self.model, self.data)
        self.rig.upload_texture(self.model, tex)
        if self._viewer is not None:
            self._viewer.upload_texture(tex)

    def retake_reset_frame(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """Takes the reset's camera frame again (the world changed before time started: a sticker
        was put up) and returns the reset's observation and info anew."""
        if self._step != 0:
            raise RuntimeError("retake_reset_frame is for the reset's frame; later frames come with time")
        self._take_frame(0.0)
        self.truth.forget_view()
        return self._observation(), self._info(collision=False, off_road=False)

    def hide_sign_patches(self) -> None:
        """Takes every sticker off (back to the group no sensor sees)."""
        self.stickers.hide(self.model)
        self.rig.invalidate()

    def render(self):
        if self.render_mode != "rgb_array":
            return None
        if self._viewer is None:
            self._viewer = ChaseView(self.model, self.config.render_width, self.config.render_height)
        return self._viewer.render(self.data)

    def close(self) -> None:
        for s in self.sensors:
            s.close()
        if self._viewer is not None:
            self._viewer.close()
            self._viewer = None

    def _reward(self, progress_m: float, collision: bool, off_road: bool) -> float:
        return float(progress_m - 0.1 * abs(self._lateral) - 10.0 * (collision or off_road))

    def _collided(self) -> bool:
        """Whether the car touches anything; the first thing it touched is kept for ``collision_with``."""
        hit = self.contacts.touching(self.data)
        if hit is not None:
            self._collision_with = self._collision_with or hit
        return hit is not None

    # -- internals ------------------------------------------------------------------------
    def _rng_of(self, sensor: Sensor) -> np.random.Generator:
        return self._nav_rng if sensor.name in _NAV_SENSORS else self._sensor_rng

    def _frames_due(self, substep: int) -> int:
        """Camera frames due by the end of physics step ``substep`` (frame 0 at the reset)."""
        return math.floor(substep * self.config.physics_dt_s * self.config.camera_hz + 1e-6) + 1

    def _advance_physics(self, frames: bool = True) -> None:
        """One control step of physics; the swept LiDAR and (unless ``frames`` is False, for the
        speed bench) the camera act between physics steps."""
        end = self._substep + self.config.substeps
        while self._substep < end:
            # Step to the next physics step where a sensor acts (every one while the LiDAR sweeps).
            nxt = self._substep + 1
            if not self._sweeping and not self._moving:  # a moving world acts every physics step
                while nxt < end and (not frames or self._frames_due(nxt) == self._frames):
                    nxt += 1
            for manager in self._moving:
                manager.before_physics(self.data, self._substep)
            mujoco.mj_step(self.model, self.data, nstep=nxt - self._substep)
            self._substep = nxt
            if self._sweeping:
                self.lidar.sweep(self.model, self.data, self._substep)
            if frames and self._frames_due(self._substep) > self._frames:
                self._take_frame(self._substep * self.config.physics_dt_s)

    def _take_frame(self, now: float) -> None:
        for sensor in self.sensors[:2]:  # rgb, depth: one render
            self._obs[sensor.name] = sensor.read(self.model, self.data, self._sensor_rng)
            self._stamps[_STAMP_SLOT[sensor.name]] = now
        # The ground truth of the frame (its mask) needs the frame's clean depth and camera pose.
        depth = self.rig.render(self.model, self.data)[1]
        pos, mat = self.car.camera_pose(self.model, self.data)
        self.truth.hold_frame(self.data, depth, pos, mat)
        self._frames = self._frames_due(self._substep)

    def _read_sensors(self, force: bool) -> None:
        now = self._step / self.config.control_hz
        if force:
            self._take_frame(now)
            if self._sweeping:
                self.lidar.begin(self.model, self.data, now)
        for sensor in self.sensors[2:]:
            if self._sweeping and sensor is self.lidar:
                if self.lidar.has_new_scan():
                    self._obs["lidar"] = self.lidar.read(self.model, self.data, self._sensor_rng)
                    self._stamps[_STAMP_SLOT["lidar"]] = self.lidar.scan_time
                    self._beam_times = self.lidar.beam_times
            elif force or self._step % self._decimation[sensor.name] == 0:
                self._obs[sensor.name] = sensor.read(self.model, self.data, self._rng_of(sensor))
                self._stamps[_STAMP_SLOT[sensor.name]] = now
                if sensor is self.lidar:
                    self._beam_times = np.full(self.lidar.shape, now)

    def _listen(self) -> None:
        """The radio's step: what the world's vehicles broadcast now is sent; what arrived is the car's."""
        said = tuple(b for manager in self.world for b in manager.broadcasts(self._substep))
        self._radio_rows = self.radio.tick(self._step / self.config.control_hz, said,
                                           tuple(self.data.qpos[self.car.root_qpos:self.car.root_qpos + 2]))

    def _observation(self) -> dict[str, np.ndarray]:
        rows, times = self._radio_rows
        return {**{k: v.copy() for k, v in self._obs.items()}, "lidar_beam_times": self._beam_times.copy(),
                "timestamps": self._stamps.copy(), "radio": rows.copy(), "radio_times": times.copy()}

    def _update_route_progress(self) -> None:
        x, y = self.data.qpos[self.car.root_qpos : self.car.root_qpos + 2]
        self._route_s, self._lateral = self._path.project(np.array([x, y]), s_hint=self._route_s, window_m=0.5)
        # Served and passed: the next target of a drive becomes current (the rule the car applies to its own pose).
        self._slot = current_slot(self._targets, self._slot, self._route_s + self._bumper_ahead_m)

    def _info(self, collision: bool, off_road: bool) -> dict[str, Any]:
        if self._step == 0:
            self._update_route_progress()
        state = self.car.state(self.data)
        cam_pos, cam_mat = self.car.camera_pose(self.model, self.data)
        view, centre = self.truth.view(self._sign, (self._frames, self._slot), self.data, cam_pos, cam_mat)
        return {
            "target_kind": "obstacle" if isinstance(self._sign, Obstacle) else "stop_sign",
            "target_sign": self._sign.index,
            "target_stands": bool(centre[2] > 0.0),  # a body taken off the floor (parked below it) stands nowhere
            "target_slot": self._slot,
            "lidar_time": float(self._stamps[_STAMP_SLOT["lidar"]]),
            "cruise_speed": self._cruise_speed,
            "d_true": view.d_true,
            "d_true_euclid": view.d_euclid,
            "sign_bearing": view.bearing,
            "sign_mask": view.mask.copy(),  # the frame's, held: each info gets its own
            "sign_in_view": view.in_view,
            "pose": np.array([state.x, state.y, state.yaw]),
            "speed": state.speed,
            "route_s": self._route_s,
            "lateral_error": self._lateral,
            "dist_to_stop_line": self._targets[self._slot].stop_s - (self._route_s + self._bumper_ahead_m),
            "collision": collision,
            "collision_with": self._collision_with,
            "off_road": off_road,
            "time": self._step / self.config.control_hz,
            "radio_sent": self.radio.sent, "radio_delivered": self.radio.delivered,
            **{key: value for manager in self.world for key, value in manager.info(self._substep).items()},
        }

    # Route and sign, for controllers and experiments that plan on the road graph.
    @property
    def _sign(self) -> StopSign | Obstacle:
        return self._targets[self._slot].target

    @property
    def target_sign(self) -> StopSign | Obstacle:
        """The current target: a stop sign, or a crate (``options['obstacle']`` / ``options['crate']``)."""
        return self._sign

    @property
    def route_targets(self) -> tuple[RouteTarget, ...]:
        """Every target of the episode in the order the route meets them (map knowledge)."""
        return self._targets

    @property
    def route_path(self) -> Path:
        """The episode's lane-centre path (an approach's route, or a drive's)."""
        return self._path

    def frame_sign_masks(self) -> list[np.ndarray]:
        """Every stop sign's visible face in the held camera frame, (H, W) bool each (ground truth, for
        evaluation like ``info``: the frame the observation's ``rgb`` shows, older than the step when
        the camera runs slower than the loop)."""
        return self.truth.sign_masks(stop_signs(self.config.sign))

    def sensor_observation(self) -> dict[str, np.ndarray]:
        """The current sensor readings as the env returned them, before any wrapper changed them (for
        evaluation, e.g. the protocol's d_clean under an attack, like ``info``)."""
        return self._observation()
