"""``racf replay-bag``: the car's software run on a recording, with no simulator.

A :class:`BagEnv` plays the recording back as the env's observations, step by step (the car's
actions reach nothing: the recording already happened), so the car
(:class:`racf.experiments.car.software.Car`: perception, the LiDAR tracker, localisation, the
defence, the braker) and observation-space attacks run on it exactly as in an episode. The
per-step log has the episode's columns; the referee's are there only where the bag carries
ground truth (``/racf/ground_truth/...``, a bag racf wrote), and the log says which are absent.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import gymnasium as gym
import numpy as np
import pandas as pd

from racf.errors import UserError
from racf.experiments.bags import messages as m
from racf.experiments.bags.frames import ReplayFrames
from racf.experiments.bags.mapping import Mapping
from racf.experiments.bags.mount import LidarMountCheck
from racf.experiments.bags.recording import Recording
from racf.experiments.bags.topics import SCAN_DELIVERED, SCAN_TIMES, SIGN_MASK, TRUTH_PREFIX
from racf.experiments.episode.plan import car_calibration, plan_episode
from racf.experiments.episode.record import REFEREE, columns_of, step_row
from racf.experiments.episode.runner import ActionLine, car_columns, grant_white_box
from racf.experiments.episode.spec import TrialSpec, parse_setting, setting_name
from racf.experiments.episode.stack import build_car, wrap_attacks
from racf.sim.attacks import ATTACKS
from racf.sim.sensors.camera import CameraIntrinsics
from racf.sim.sensors import TIMESTAMP_FIELDS
from racf.sim.sensors.a2m12 import driver_scan
from racf.sim.sensors.calibration import car_build
from racf.sim.sensors.state import OdometryConfig

__all__ = ["BagEnv", "Replay", "replay_bag", "check_attacks", "offline_scores"]

_SLOT = {name: i for i, name in enumerate(TIMESTAMP_FIELDS)}
_DELIVERED_TIMES = "/racf/scan/delivered_times"


def check_attacks(attacks: tuple[str, ...]) -> None:
    """Refuses, in one line, an attack that is not registered or needs the simulator."""
    for name in attacks:
        if name not in ATTACKS:
            raise UserError(f"no attack {name!r}; the attacks: {', '.join(ATTACKS)}")
        why = getattr(ATTACKS[name], "needs_simulator", "")
        if why:
            allowed = [a for a in ATTACKS if not getattr(ATTACKS[a], "needs_simulator", "")]
            raise UserError(f"attack {name!r} cannot act on a recording: {why}; on a recording: {', '.join(allowed)}")


class BagEnv(gym.Env):
    """A recording played back as the env: ``reset`` gives the first step's observation, ``step``
    the next (the action is ignored); truncated at the recording's end. ``info`` holds the step's
    time and, where the bag has them, the referee's ground truth (``d_true``, ``sign_mask``, ...)."""

    metadata = {"render_modes": []}

    def __init__(self, recording: Recording, step_s: float, camera_size: tuple[int, int]) -> None:
        self.recording = recording
        self.mapping = recording.mapping
        self.step_ns = int(round(step_s * 1e9))
        self.hz = round(1.0 / step_s)
        self.width, self.height = camera_size
        self.driver = self.mapping.lidar_driver or ("none" if recording.spec.sensor_profile == "ideal" else "quanser")
        self.m_per_count = OdometryConfig().m_per_count  # the encoder's calibration, counts/s -> m/s
        h, w = self.height, self.width
        self.observation_space = gym.spaces.Dict({
            "rgb": gym.spaces.Box(0, 255, (h, w, 3), np.uint8),
            "depth": gym.spaces.Box(0.0, np.inf, (h, w, 1), np.float32),
            "lidar": gym.spaces.Box(0.0, np.inf, (360,), np.float32),
            "lidar_beam_times": gym.spaces.Box(0.0, np.inf, (360,), np.float64),
            "gps": gym.spaces.Box(-np.inf, np.inf, (3,), np.float32),
            "state": gym.spaces.Box(-np.inf, np.inf, (4,), np.float32),
            "timestamps": gym.spaces.Box(0.0, np.inf, (len(TIMESTAMP_FIELDS),), np.float64)})
        self.action_space = gym.spaces.Box(-np.inf, np.inf, (2,), np.float32)
        self.truth_columns: set[str] = set()

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        self._steps = self.recording.steps(self.step_ns)
        self._next = next(self._steps, None)  # the recording's next step, not yet played
        self._obs: dict = {"timestamps": np.zeros(len(TIMESTAMP_FIELDS))}
        self._truth: dict = {}
        self._mask = np.zeros((self.height, self.width), bool)
        self.frame_size: tuple[int, int] | None = None  # the recorded frames' (width, height), once one is seen
        self._k = -1
        # The car starts once every required stream has spoken (a bag racf wrote: at its first step).
        while not {"rgb", "depth", "lidar", "gps", "state"} <= set(self._obs):
            if self.exhausted:
                raise UserError(f"bag {self.recording.path} never has all of the car's streams at once "
                                f"({', '.join(sorted(self.mapping.topics))})")
            self._play()
        return self._observation(), self._info()

    def step(self, action):
        if self.exhausted:
            raise RuntimeError("the recording has ended")
        self._play()
        return self._observation(), 0.0, False, self.exhausted, self._info()

    @property
    def exhausted(self) -> bool:
        return self._next is None

    def _play(self) -> None:
        self._apply(*self._next)
        self._next = next(self._steps, None)

    def _apply(self, k: int, msgs: dict[str, list]) -> None:
        self._k = k
        topics = self.mapping.topics
        last = {topic: items[-1] for topic, items in msgs.items()}
        colour = [x for x in msgs.get(topics["rgb"], []) if not m.empty_image(x)]
        if colour:
            self._obs["rgb"] = self._camera(m.rgb_from(colour[-1]), cv2.INTER_AREA)
            self._obs["timestamps"][_SLOT["rgb"]] = m.seconds_of(m.stamp_of(colour[-1]))
        depth = [x for x in msgs.get(topics["depth"], []) if not m.empty_image(x)]
        if depth:
            self._obs["depth"] = self._camera(m.depth_from(depth[-1]), cv2.INTER_NEAREST)[..., None]
            self._obs["timestamps"][_SLOT["depth"]] = m.seconds_of(m.stamp_of(depth[-1]))
        if topics["scan"] in last:
            self._scan(last[topics["scan"]], last.get(SCAN_TIMES), last.get(SCAN_DELIVERED), last.get(_DELIVERED_TIMES))
        if topics["imu"] in last or topics["joint"] in last:
            self._state(last.get(topics["imu"]), last.get(topics["joint"]))
        if topics["fix"] in last:
            self._obs["gps"] = m.pose_from(last[topics["fix"]])
            self._obs["timestamps"][_SLOT["gps"]] = m.seconds_of(m.stamp_of(last[topics["fix"]]))
        # racf writes a referee value every step it has one: a step without it has none (NaN).
        self._truth = {key: math.nan for key in self._truth}
        for topic, msg in last.items():
            if topic == SIGN_MASK:
                self._mask = self._camera(m.mask_from(msg).astype(np.uint8), cv2.INTER_NEAREST).astype(bool)
            elif topic.startswith(TRUTH_PREFIX):
                self._truth[topic[len(TRUTH_PREFIX):]] = float(msg.data)
            elif topic == "/racf/attack_active":
                self._truth["attack_active_recorded"] = float(msg.data)
        self.truth_columns |= {t[len(TRUTH_PREFIX):] for t in msgs if t.startswith(TRUTH_PREFIX) and t != SIGN_MASK}

    def _camera(self, image: np.ndarray, interpolation: int) -> np.ndarray:
        if self.frame_size is None:
            self.frame_size = (image.shape[1], image.shape[0])
        crop = self.mapping.camera_crop
        if crop is not None:
            x0, y0, x1, y1 = crop
            h, w = image.shape[:2]
            if x1 > w or y1 > h:  # numpy would cut the crop short without a word
                raise UserError(f"mapping {self.mapping.source}: [camera] crop {list(crop)} reaches beyond the "
                                f"recording's {w}x{h} frames; it must keep x1 <= {w} and y1 <= {h}")
            image = image[y0:y1, x0:x1]
        if image.shape[:2] != (self.height, self.width):
            image = cv2.resize(image, (self.width, self.height), interpolation=interpolation)
        return np.ascontiguousarray(image)

    def _scan(self, scan, times_msg, delivered, delivered_times) -> None:
        stamp = m.seconds_of(m.stamp_of(scan))
        self._obs["timestamps"][_SLOT["lidar"]] = stamp
        if delivered is not None and delivered_times is not None:  # an attack acted after the driver
            self._obs["lidar"] = m.bins_from(delivered)
            self._obs["lidar_beam_times"] = np.asarray(delivered_times.data, np.float64).copy()
            return
        quantum = self.mapping.lidar_quantum_m
        ranges = m.scan_from(scan, (0.001 if self.driver == "quanser" else 0.0) if quantum is None else quantum)
        n = ranges.size
        if times_msg is not None and len(times_msg.data) == n:
            times = np.asarray(times_msg.data, np.float64)
        else:  # a driver's stamp is taken as the revolution ends: sample i was (n - 1 - i) increments before
            times = stamp - (n - 1 - np.arange(n)) * float(scan.time_increment)
        if self.driver == "quanser":
            self._obs["lidar"], self._obs["lidar_beam_times"] = driver_scan(
                ranges, times, self.mapping.read_per_rev, 360, 1.1, self.mapping.lidar_yaw_deg)
        else:
            to_car = (int(round(self.mapping.lidar_yaw_deg * n / 360.0)) - np.arange(n)) % n
            lidar = np.full(n, np.inf, np.float32)
            lidar[to_car] = np.where(ranges > 0, ranges, np.inf)
            beam_times = np.empty(n)
            beam_times[to_car] = times
            self._obs["lidar"], self._obs["lidar_beam_times"] = lidar, beam_times

    def _state(self, imu, joint) -> None:
        state = self._obs.get("state", np.full(4, np.nan, np.float32)).copy()
        if joint is not None:
            state[0] = np.float32(float(joint.velocity[0]) * self.m_per_count)
            self._obs["timestamps"][_SLOT["state"]] = m.seconds_of(m.stamp_of(joint))
        if imu is not None:
            state[2] = np.float32(imu.angular_velocity.z)
            state[3] = np.float32(imu.linear_acceleration.x)
        state[1] = np.nan  # the servo's angle: no QCar 2 topic carries it
        self._obs["state"] = state

    def _observation(self) -> dict:
        return {k: np.array(v, copy=True) for k, v in self._obs.items()}

    def _info(self) -> dict:
        info = {"time": self._k / self.hz, "sign_mask": self._mask.copy(), **self._truth}
        info.setdefault("speed", float(self._obs["state"][0]))
        info.setdefault("dist_to_stop_line", math.nan)
        return info


@dataclass
class Replay:
    """A replay's per-step log, what it ran, and which referee columns the bag could not give."""

    log: pd.DataFrame
    spec: TrialSpec
    absent: tuple[str, ...]
    attacks: tuple[str, ...] = ()
    scores: dict = field(default_factory=dict)
    frames: object = None
    #: What the replayed data has seen, as a setting: the recording's own attacks, those the replay
    #: added, and the defence that ran (``spec.setting`` names only what the replay applies).
    setting: str = ""
    #: What looks wrong with the recording's mapping, a line each (a LiDAR mount that seldom agrees
    #: with the depth: ``racf.experiments.bags.mount``).
    warnings: tuple[str, ...] = ()


def replay_bag(path: str | Path, mapping: Mapping | None = None, defence: str | None = None,
               attacks: tuple[str, ...] = (), attack_params: dict | None = None, on_step=None,
               record: bool = False) -> Replay:
    """Runs the car's software on the bag at ``path``.

    Args:
        mapping: how the bag's streams reach the car (None: a bag racf wrote).
        defence: the estimator (None: the bag's own, or ``raw`` for a bag racf did not write).
        attacks: observation-space attacks to apply to the recording (refused: those needing the simulator).
        attack_params: per attack, its settings (``TrialSpec.attack_params``).
        on_step: ``on_step(env, obs, info, row)`` after each step.
        record: keep frames for a rerun recording (``Replay.frames``, for ``write_rrd``).
    """
    check_attacks(attacks)
    recording = Recording.open(path, mapping)
    spec = recording.spec
    recording_attacks, bag_estimator = parse_setting(spec.setting)
    estimator = defence or bag_estimator
    # The recording already holds the attacks it was made under; the replay adds only those asked for.
    setting = setting_name(tuple(attacks), estimator) if attacks or defence else spec.setting
    try:
        spec = TrialSpec.from_dict({**spec.to_dict(), "setting": setting, "attack_params": attack_params or {},
                                    "estimator_options": {} if defence and defence != bag_estimator
                                    else spec.estimator_options})
    except ValueError as err:
        raise UserError(str(err)) from None
    plan = plan_episode(spec)
    size = recording.mapping.camera_size or (plan.calibration.camera.width, _height(plan))
    if size != (plan.calibration.camera.width, _height(plan)):
        plan = _with_camera(plan, size)
    env: gym.Env = BagEnv(recording, plan.control_dt_s, size)
    if attacks:
        env = wrap_attacks(env, spec)
    bag = env.unwrapped
    obs, info = env.reset(seed=spec.seed)
    plan = _declared_build(plan, recording.mapping, bag.frame_size, size)
    car = build_car(spec, plan, None)
    grant_white_box(env, car.estimator)
    k = plan.calibration.camera
    frames = ReplayFrames(plan.calibration, CameraIntrinsics(size[0], size[1], k.fx, k.fy or k.fx, k.cx,
                                                             k.cy if k.cy is not None else (size[1] - 1) / 2.0)
                          ) if record else None
    build = car_build(*size)
    mount = LidarMountCheck(plan.calibration, build.lidar_height_m - build.camera_height_m)
    actions = ActionLine(int(round(spec.delay_ms / 1000.0 / plan.control_dt_s)))
    rows: list[dict] = []
    referee = columns_of(REFEREE)
    while True:
        step = car.step(obs)
        applied = actions.push(step.action)
        truth = {c: info.get(c, math.nan) for c in referee}
        truth["attack_active"] = bool(info.get("attack_active", False)) if attacks else \
            info.get("attack_active_recorded", math.nan)
        truth["attack"] = "+".join(info.get("attack", ()))
        truth["collision_with"] = ""
        rows.append(step_row({**car_columns(car, step, obs, info["time"], applied), **truth},
                             car.estimator.diagnostics()))
        for hook in (frames, mount, on_step):
            if hook is not None:
                hook(env, obs, info, rows[-1])
        if bag.exhausted:
            break
        obs, _, _, _, info = env.step(applied)
    log = pd.DataFrame(rows)
    log.insert(0, "trial_id", f"replay:{Path(path).name}")
    present = bag.truth_columns | ({"attack_active", "attack"} if attacks else set()) | (
        {"attack_active"} if "/racf/attack_active" in recording.topics else set())
    absent = tuple(c for c in referee if c not in present)
    log = log.drop(columns=list(absent))
    log.attrs["absent_ground_truth"] = list(absent)
    seen = setting_name(tuple(dict.fromkeys(recording_attacks + tuple(attacks))), estimator)
    return Replay(log, spec, absent, tuple(attacks), offline_scores(log), frames, seen,
                  tuple(filter(None, [mount.warning(recording.mapping)])))


def _declared_build(plan, mapping: Mapping, frame_size: tuple[int, int] | None, size: tuple[int, int]):
    """The plan with the car's build as the recording declares it: the camera's intrinsics (cropped and
    resized with the frames) and the LiDAR's position; what it does not declare stays racf's model."""
    from dataclasses import replace

    from racf.controllers.distance import CameraModel

    calibration = plan.calibration
    declared = mapping.car_intrinsics(*frame_size, size) if frame_size else None
    if declared is not None:
        fx, fy, cx, cy = declared
        if not (0.0 <= cx <= size[0] and 0.0 <= cy <= size[1]):
            raise UserError(f"mapping {mapping.source}: [camera] the principal point lands at ({cx:.1f}, {cy:.1f}) "
                            f"in the car's {size[0]}x{size[1]} frames, outside them: check intrinsics against the "
                            f"recorded {frame_size[0]}x{frame_size[1]} frames and the crop")
        calibration = replace(calibration, camera=CameraModel(width=size[0], fx=fx, cx=cx, fy=fy, cy=cy))
    if mapping.lidar_position_m is not None:
        calibration = replace(calibration, lidar_xy_m=mapping.lidar_position_m)
    return replace(plan, calibration=calibration)



def _height(plan) -> int:
    from racf.sim.env.config import EnvConfig

    return EnvConfig.from_kwargs(**plan.env_kwargs).camera.height


def _with_camera(plan, size: tuple[int, int]):
    from dataclasses import replace

    return replace(plan, calibration=car_calibration(*size))


def offline_scores(log: pd.DataFrame) -> dict:
    """The offline measures a replay can give: the distance's RMSE and MAE against ``d_true`` where
    the bag has it (all steps with both, and the attacked ones), and the detector's AUROC and AUPRC
    for the attacked steps where it flags and the bag says which steps were attacked. Absent: null."""
    from sklearn.metrics import average_precision_score, roc_auc_score

    out = {"steps": int(len(log)), "rmse_m": None, "mae_m": None, "rmse_attacked_m": None, "auroc": None,
           "auprc": None}
    if "d_true" in log:
        both = log["d_fused"].notna() & log["d_true"].notna()
        err = (log["d_fused"] - log["d_true"])[both]
        if len(err):
            out["rmse_m"], out["mae_m"] = float(np.sqrt((err ** 2).mean())), float(err.abs().mean())
        if "attack_active" in log:
            hit = both & (log["attack_active"] == 1)
            if hit.any():
                out["rmse_attacked_m"] = float(np.sqrt(((log["d_fused"] - log["d_true"])[hit] ** 2).mean()))
    if "attack_active" in log and log["score"].notna().any():
        scored = log["score"].notna() & log["attack_active"].notna()
        y, s = log.loc[scored, "attack_active"].astype(bool), log.loc[scored, "score"]
        if y.nunique() == 2:
            out["auroc"], out["auprc"] = float(roc_auc_score(y, s)), float(average_precision_score(y, s))
    return out
