"""``RACF/QCar2-v3``: the QCar 2 on the indoor map, approaching a stop sign.

Plumbing only: step order, seeding, spaces, sensor scheduling and the reward and
termination hooks. The world, the car and the sensors are built by their own modules.

Step order: validate action -> write controls -> ``substeps`` physics steps, after each of
which the swept LiDAR casts the samples whose time has come and the camera takes a frame
if one falls due -> read the other sensors that are due (each holds its last reading and
its timestamp between readings) -> ground truth -> reward and flags.

v3 (from v2): sensor profiles (``qcar2``, the default: the A2M12 swept over its revolution
and delivered through Quanser's driver, the camera at 30 Hz; ``ideal``: v2's sensors and
the true pose); the observation gains ``lidar_beam_times``.

v2 (from v1): the observation gains ``gps`` (the localiser's fix) and ``timestamps``;
``state`` is what the encoder and the IMU measure (quantised, noisy, biased) and loses the
lateral speed, which no sensor on the car measures.
"""

from __future__ import annotations

import math
from typing import Any

import cv2
import gymnasium as gym
import numpy as np
from gymnasium import spaces

from racf.sim._gl import ensure_gl_backend, gl_context_class
from racf.sim.env.config import RESET_OPTIONS, EnvConfig
from racf.sim.world.manager import WorldManager
from racf.sim.env.ground_truth import Motion, SignView, obstacle_view, sign_view, target_centre, with_centre_from
from racf.sim.sensors import (TIMESTAMP_FIELDS, DepthCamera, Lidar2D, LocalisationFix, RGBCamera, RGBDCameraRig, Sensor,
                         VehicleStateSensor)
from racf.sim.sensors.a2m12 import A2M12Lidar
from racf.sim.vehicle import QCar2
from racf.sim.world.drives import RouteTarget
from racf.sim.world.route_plan import current_slot, plan_route
from racf.sim.world.road_graph import Path
from racf.sim.world.scene import (HIDDEN_GEOM_GROUP, PROP_GEOM_GROUP, load_model, obstacle_body, patch_geom,
                                  patch_texture, sign_body)
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
    car's forward (the last complete revolution: on ``qcar2`` swept over 0.1 s and delivered
    through Quanser's driver, see ``racf.sim.sensors.a2m12``); ``lidar_beam_times`` (360,)
    float64, when each bin was measured, s; ``gps`` (3,) float32, the localiser's
    fix (x, y m, yaw rad, map frame): with ``localisation="qcar2"`` (the default) one per
    LiDAR scan, with Quanser's drift and noise (``racf.sim.sensors.localiser``), with
    ``localisation="true"`` the true pose at every step; ``state`` (4,) float32, the
    encoder's speed, the steering servo's angle and the IMU's yaw rate and acceleration (see
    ``racf.sim.sensors.STATE_FIELDS``); ``timestamps`` (5,) float64, the time (s) each held
    reading was taken, in the order of ``TIMESTAMP_FIELDS``. Action (``Box``): [speed
    command m/s, steering rad].

    ``reset(options=...)`` sets up one of two kinds of episode:

    - an approach: ``sign`` (0..3) or ``obstacle`` (0..1, a crate on a lane with a virtual
      stop line before it), ``cruise_speed`` (m/s; the car starts moving at it) and
      ``run_up_m`` (distance from the front bumper to the stop line at the start);
    - a drive (``racf.sim.world.drives``): ``route`` (road-graph nodes), ``start_s_m`` (start
      along the route's path), ``lateral_offset_m``, ``heading_error_rad``, ``crate`` (a
      crate index to place on the route, which ends the drive, or None) and
      ``cruise_speed``. Its targets are the stop signs whose stop lines the route crosses
      in their direction (and the crate); the next becomes current once the bumper is
      ``route_plan.PASS_LINE_M`` past the current one's stop line (``info["target_slot"]``).

    Ground truth is in ``info`` (the ``sign_*`` keys describe the current target, sign or
    crate; ``target_kind`` says which), read from the world after every manager acted (the
    target's body pose, not the map's record: ``racf.sim.env.ground_truth``): ``d_true``
    (target depth along the camera axis, m), ``d_true_euclid``, ``sign_bearing``,
    ``sign_mask``, ``sign_in_view``, ``target_stands`` (its body stands on the floor: False for a
    sign taken away), ``pose``, ``speed``, ``route_s``, ``lateral_error``,
    ``dist_to_stop_line`` (front bumper to the stop line along the route, m; negative once past
    it), ``collision``, ``collision_with`` (what the car first touched: a world manager's name for
    its body, else a geom's name; None), ``off_road``, and what each world manager reports.

    World managers (the setting ``world``: ``racf.sim.world.manager``) add bodies, read a reset
    option each and log their own ground truth; the env knows none of them (other cars are one:
    ``racf.sim.world.traffic_manager``).
    ``info["lidar_time"]`` repeats the LiDAR's timestamp (the LiDAR scans at ``lidar_hz``,
    10 Hz by default, like the A2M12). ``sign_mask`` and ``sign_in_view`` describe the
    held camera frame, ``d_true`` and ``sign_bearing`` the car's pose now. The car's side
    reads the observation only.

    Reward per step: metres of route progress, minus 0.1 x lateral error (m), minus 10
    on leaving the road or colliding (both end the episode).

    Example:
        >>> import gymnasium as gym, sim
        >>> env = gym.make("RACF/QCar2-v3", camera_width=160, camera_height=120)
        >>> obs, info = env.reset(seed=0, options={"sign": 2, "cruise_speed": 1.0})
        >>> obs["rgb"].shape, obs["lidar"].shape, obs["gps"].shape
        ((120, 160, 3), (360,), (3,))
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
        self.observation_space = spaces.Dict({
            **{s.name: spaces.Box(low=s.low, high=s.high, shape=s.shape, dtype=s.dtype) for s in self.sensors},
            "lidar_beam_times": spaces.Box(low=0.0, high=np.inf, shape=self.lidar.shape, dtype=np.float64),
            "timestamps": spaces.Box(low=0.0, high=np.inf, shape=(len(TIMESTAMP_FIELDS),), dtype=np.float64)})
        v = self.config.vehicle
        self.action_space = spaces.Box(low=np.array([-v.max_reverse_mps, -v.max_steer_rad], np.float32),
                                       high=np.array([v.max_speed_mps, v.max_steer_rad], np.float32),
                                       dtype=np.float32)
        self._chassis_geom = self.model.geom("chassis").id
        self._wheel_geoms = {self.model.geom(w).id for w in ("wheel_fl", "wheel_fr", "wheel_rl", "wheel_rr")}
        self._floor_geoms = {self.model.geom("mat").id, self.model.geom("lab_floor").id}
        n_signs = len(stop_signs(self.config.sign))
        self._patch_geoms = [self.model.geom(patch_geom(i)).id for i in range(n_signs)]
        self._patch_textures = [self.model.texture(patch_texture(i)).id for i in range(n_signs)]
        self._viewer = None
        self._collision_with: str | None = None
        self._moving: tuple[WorldManager, ...] = ()
        # Crates stand on the map only in their own episodes (as a test operator would place one).
        self._crates = [(self.model.body(obstacle_body(o.index)).id, self.model.body(obstacle_body(o.index)).pos.copy())
                        for o in obstacles()]
        # Each target's body and its map pose (the MJCF's): the truth follows a body a manager moved.
        self._bodies = {**{("stop_sign", s.index): self.model.body(sign_body(s.index)).id
                           for s in stop_signs(self.config.sign)},
                        **{("obstacle", o.index): body for o, (body, _) in zip(obstacles(), self._crates)}}
        home = mujoco.MjData(self.model)
        mujoco.mj_kinematics(self.model, home)
        self._home = {key: (home.xpos[body].copy(), home.xmat[body].copy()) for key, body in self._bodies.items()}
        self._frame_xpos, self._frame_xmat = home.xpos.copy(), home.xmat.copy()
        first = stop_signs(self.config.sign)[0]
        self._path: Path = first.path
        self._targets: tuple[RouteTarget, ...] = (RouteTarget(first, first.stop_s, first.stop_s),)
        self._slot = 0
        self._stamps = np.zeros(len(TIMESTAMP_FIELDS))
        self._beam_times = np.zeros(self.lidar.shape)
        self._obs: dict[str, np.ndarray] = {}
        self._step = 0
        self._substep = 0  # physics steps since the reset
        self._frames = 0  # camera frames taken since the reset
        self._frame_depth = np.zeros((self.config.camera.height, self.config.camera.width), np.float32)
        self._frame_cam = (np.zeros(3), np.eye(3))
        self._view: tuple[tuple[int, int], SignView] | None = None
        self._route_s = 0.0
        self._sensor_rng = np.random.default_rng()
        self._nav_rng = np.random.default_rng()

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
        self._view = None
        for sensor in self.sensors:
            sensor.reset(self._rng_of(sensor))
        self._read_sensors(force=True)
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
        if sign_index not in range(len(self._patch_geoms)):
            raise ValueError(f"sign_index must be 0..{len(self._patch_geoms) - 1}, got {sign_index!r}")
        if not isinstance(placement, PatchPlacement):
            raise TypeError(f"placement must be a PatchPlacement, got {type(placement).__name__}")
        texture = np.asarray(texture)
        if texture.ndim != 3 or texture.shape[2] != 3 or texture.dtype != np.uint8:
            raise ValueError(f"texture must be an (H, W, 3) uint8 image, got shape {texture.shape} dtype {texture.dtype}")
        geom, tex = self._patch_geoms[sign_index], self._patch_textures[sign_index]
        size = (int(self.model.tex_width[tex]), int(self.model.tex_height[tex]))
        if texture.shape[:2] != size[::-1]:
            texture = cv2.resize(texture, size, interpolation=cv2.INTER_AREA)
        adr, n = int(self.model.tex_adr[tex]), int(self.model.tex_nchannel[tex])
        self.model.tex_data[adr:adr + texture.size // 3 * n] = texture.reshape(-1) if n == 3 else \
            np.concatenate([texture, np.full(texture.shape[:2] + (1,), 255, np.uint8)], 2).reshape(-1)
        corners = placement.corners_local(self.config.sign)
        self.model.geom_pos[geom] = [corners[0, 0] - self.model.geom_size[geom][0], *corners[:, 1:].mean(axis=0)]
        self.model.geom_size[geom][1:] = placement.side_m / 2
        self.model.geom_group[geom] = PROP_GEOM_GROUP
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
        self._view = None
        return self._observation(), self._info(collision=False, off_road=False)

    def hide_sign_patches(self) -> None:
        """Takes every sticker off (back to the group no sensor sees)."""
        for geom in self._patch_geoms:
            self.model.geom_group[geom] = HIDDEN_GEOM_GROUP
        self.rig.invalidate()

    def render(self):
        if self.render_mode != "rgb_array":
            return None
        if self._viewer is None:
            self._viewer = _ChaseView(self.model, self.config.render_width, self.config.render_height)
        return self._viewer.render(self.data)

    def close(self) -> None:
        for s in self.sensors:
            s.close()
        if self._viewer is not None:
            self._viewer.close()
            self._viewer = None

    # -- hooks ----------------------------------------------------------------------------
    def _reward(self, progress_m: float, collision: bool, off_road: bool) -> float:
        return float(progress_m - 0.1 * abs(self._lateral) - 10.0 * (collision or off_road))

    def _collided(self) -> bool:
        """A contact of the chassis with anything, or of a wheel with anything but the floor; the
        first such contact's other party is kept for ``info["collision_with"]``."""
        for i in range(self.data.ncon):
            g1, g2 = int(self.data.contact.geom1[i]), int(self.data.contact.geom2[i])
            other = g2 if g1 == self._chassis_geom or g1 in self._wheel_geoms else g1
            if self._chassis_geom in (g1, g2) or (
                    (g1 in self._wheel_geoms or g2 in self._wheel_geoms) and other not in self._floor_geoms):
                self._collision_with = self._collision_with or self._name_of(other)
                return True
        return False

    def _name_of(self, geom: int) -> str:
        """What a geom belongs to: what a world manager calls its body (``WorldManager.owner_of``), else
        the geom's (or its body's) name."""
        body = int(self.model.geom_bodyid[geom])
        root = int(self.model.body_rootid[body])
        for manager in self.world:
            owner = manager.owner_of(root)
            if owner is not None:
                return owner
        return self.model.geom(geom).name or self.model.body(body).name or f"geom{geom}"

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
        self._frame_depth[:] = self.rig.render(self.model, self.data)[1]
        pos, mat = self.car.camera_pose(self.model, self.data)
        self._frame_cam = (np.array(pos, dtype=np.float64), np.array(mat, dtype=np.float64).reshape(3, 3))
        self._frame_xpos[:], self._frame_xmat[:] = self.data.xpos, self.data.xmat  # where the frame saw the bodies
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

    def _observation(self) -> dict[str, np.ndarray]:
        return {**{k: v.copy() for k, v in self._obs.items()}, "lidar_beam_times": self._beam_times.copy(),
                "timestamps": self._stamps.copy()}

    def _update_route_progress(self) -> None:
        x, y = self.data.qpos[self.car.root_qpos : self.car.root_qpos + 2]
        self._route_s, self._lateral = self._path.project(np.array([x, y]), s_hint=self._route_s, window_m=0.5)
        # Served and passed: the next target of a drive becomes current (the rule the car applies to its own pose).
        self._slot = current_slot(self._targets, self._slot, self._route_s + self._bumper_ahead_m)

    def _info(self, collision: bool, off_road: bool) -> dict[str, Any]:
        if self._step == 0:
            self._update_route_progress()
        state = self.car.state(self.data)
        # The target's mask as the held frame shows it, where the frame saw its body (once per frame and target) ...
        if self._view is None or self._view[0] != (self._frames, self._slot):
            view_of = obstacle_view if isinstance(self._sign, Obstacle) else sign_view
            motion = self._motion(self._sign, self._frame_xpos, self._frame_xmat)
            self._view = ((self._frames, self._slot),
                          view_of(self._sign, *self._frame_cam, self.rig.intrinsics, self._frame_depth, motion))
        # ... and its depth and bearing from where the camera and the body are now.
        cam_pos, cam_mat = self.car.camera_pose(self.model, self.data)
        centre = target_centre(self._sign, self._motion(self._sign, self.data.xpos, self.data.xmat))
        view = with_centre_from(self._view[1], centre, np.asarray(cam_pos, np.float64),
                                np.asarray(cam_mat, np.float64).reshape(3, 3))
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
        """Every stop sign's visible face in the held camera frame, (H, W) bool each (ground truth).

        For evaluation, like ``info``: the masks belong to the frame the observation's ``rgb``
        shows, which is older than the step when the camera runs slower than the loop.
        """
        return [sign_view(s, *self._frame_cam, self.rig.intrinsics, self._frame_depth,
                          self._motion(s, self._frame_xpos, self._frame_xmat)).mask
                for s in stop_signs(self.config.sign)]

    def _motion(self, target: StopSign | Obstacle, xpos: np.ndarray, xmat: np.ndarray) -> Motion | None:
        """How ``target``'s body stands off its map pose in body poses ``xpos``/``xmat`` (None: at it)."""
        key = ("obstacle" if isinstance(target, Obstacle) else "stop_sign", target.index)
        body = self._bodies[key]
        return Motion.between(*self._home[key], xpos[body], xmat[body])

    def sensor_observation(self) -> dict[str, np.ndarray]:
        """The current sensor readings as the env returned them, before any wrapper changed them.

        For evaluation (e.g. the protocol's d_clean under an attack), like ``info``.
        """
        return self._observation()



class _ChaseView:
    """Offscreen third-person view behind the car (for ``render()``)."""

    def __init__(self, model: mujoco.MjModel, width: int, height: int) -> None:
        self._gl = gl_context_class()(width, height)
        self._gl.make_current()
        self._con = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_100.value)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN.value, self._con)
        self._scene = mujoco.MjvScene(model, maxgeom=2000)
        self._cam = mujoco.MjvCamera()
        self._cam.type = mujoco.mjtCamera.mjCAMERA_FIXED
        self._cam.fixedcamid = model.camera("chase").id
        self._opt = mujoco.MjvOption()
        self._model = model
        self._rect = mujoco.MjrRect(0, 0, width, height)
        self._rgb = np.empty((height, width, 3), np.uint8)

    def upload_texture(self, texture_id: int) -> None:
        self._gl.make_current()
        mujoco.mjr_uploadTexture(self._model, self._con, texture_id)

    def render(self, data: mujoco.MjData) -> np.ndarray:
        self._gl.make_current()
        mujoco.mjv_updateScene(self._model, data, self._opt, None, self._cam, mujoco.mjtCatBit.mjCAT_ALL.value, self._scene)
        mujoco.mjr_render(self._rect, self._scene, self._con)
        mujoco.mjr_readPixels(self._rgb, None, self._rect, self._con)
        return self._rgb[::-1].copy()

    def close(self) -> None:
        self._con.free()
        self._gl.free()
