"""One closed-loop stop-sign trial: env -> perception -> estimator -> braking -> lane follower.

Settings: ``clean`` (no attack) and ``attack`` (the patch attack of the protocol with no
defence; ``rho`` and ``t_atk`` are uniform ranges, the strong regime by default).

Per step the runner records every signal of the protocol (d_true, d_clean, d_meas, c_meas,
l, d_fused), the controller's state and brake command, pose and speed. The result row
holds success, the stop distance and the braking latency, defined as in
``shared/reference/protocol.md``:

- success: the car comes to rest (speed < 0.05 m/s) with its front bumper 0 to 0.60 m
  before the stop line;
- latency: t(brake command) - t*, where t* is the first step at which the same braking
  controller fed d_true while the sign is in view (detected exactly then, no distance
  otherwise) would have commanded the brake. It runs beside the real one on the same trajectory.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Callable

import gymnasium as gym
import numpy as np
import pandas as pd

import sim
from controllers import (BrakingConfig, DistanceEstimator, ObstacleDetector, Perception, Phase, RawDepthEstimator,
                         StopSignBraker)
from experiments.closed_loop import camera_model, map_bearing, route_follower, sign_depth_at_line
from sim.env.qcar2_env import PASS_LINE_M
from sim.world.drives import DriveSpec, draw_drive
from sim.attacks import PatchAttack
from sim.attacks.base import AttackWrapper
from sim.attacks.schedule import as_range
from sim.sensors import STATE_FIELDS

__all__ = ["TrialSpec", "TrialResult", "StepHook", "run_trial", "default_env", "STRONG_RHO", "STRONG_T_ATK_S", "SETTINGS", "SUCCESS_BAND_M", "RUN_THROUGH_M"]

#: Settings the runner knows: no attack, and the patch attack with no defence.
SETTINGS = ("clean", "attack")
#: What a trial approaches (``TrialSpec.sign`` is the index): the four stop signs or the two
#: crates; or a ``drive`` (index 0), a random route drawn from the seed that meets >= 2 targets.
TARGETS = {"sign": 4, "obstacle": 2, "drive": 1}
#: How long a drive is drawn to last, s, and its episode time limit.
DRIVE_S = (20.0, 60.0)
DRIVE_MAX_EPISODE_S = 120.0
#: The protocol's strong regime.
STRONG_RHO = (0.9, 1.0)
STRONG_T_ATK_S = (0.5, 3.0)
#: The protocol's success band: front bumper this far before the stop line, metres.
SUCCESS_BAND_M = (0.0, 0.60)
#: A trial ends once the bumper is this far past the line.
RUN_THROUGH_M = 0.5
_AT_REST_MPS = 0.05
#: Half-width of the LiDAR sector kept in the logs, in beams of the 360-beam scan (1 deg each).
SCAN_FOV_HALF_BEAMS = 40


def scan_fov(ranges: np.ndarray, half_beams: int = SCAN_FOV_HALF_BEAMS) -> np.ndarray:
    """The forward sector of a scan: beams -half..+half (entry j at (j - half) beam steps CCW
    from forward), float32 m, inf = no return. For 360 beams that is -40..+40 deg."""
    ranges = np.asarray(ranges, np.float32)
    return np.concatenate([ranges[-half_beams:], ranges[:half_beams + 1]])


@dataclass(frozen=True)
class TrialSpec:
    """One trial: setting, target sign, cruise speed (m/s), seed, and for ``attack`` the
    patch's coverage ``rho`` and duration ``t_atk`` (each a (low, high) uniform range)."""

    setting: str
    sign: int
    speed: float
    seed: int
    rho: tuple[float, float] = STRONG_RHO
    t_atk: tuple[float, float] = STRONG_T_ATK_S
    target: str = "sign"
    drive_s: tuple[float, float] = DRIVE_S

    def __post_init__(self) -> None:
        if self.setting not in SETTINGS:
            raise ValueError(f"setting must be one of {SETTINGS}, got {self.setting!r}")
        if self.target not in TARGETS:
            raise ValueError(f"target must be one of {tuple(TARGETS)}, got {self.target!r}")
        if self.sign not in range(TARGETS[self.target]):
            raise ValueError(f"{self.target} index must be 0..{TARGETS[self.target] - 1}, got {self.sign!r}")
        if not 0.1 <= self.speed <= 3.0:
            raise ValueError(f"speed must be in [0.1, 3.0] m/s, got {self.speed!r}")
        object.__setattr__(self, "rho", as_range("rho", self.rho, 0.0, 1.0))
        object.__setattr__(self, "t_atk", as_range("t_atk", self.t_atk, 0.0, 60.0))
        object.__setattr__(self, "drive_s", as_range("drive_s", self.drive_s, 5.0, 100.0))

    @property
    def drive(self) -> DriveSpec | None:
        """The drive this spec's seed draws (``target == "drive"``; ``speed`` is the nominal speed)."""
        if self.target != "drive":
            return None
        return draw_drive(np.random.default_rng(self.seed), *self.drive_s, nominal_speed_mps=self.speed)

    @property
    def trial_id(self) -> str:
        base = f"{self.setting}_{self.target}{self.sign}_v{self.speed:.2f}_seed{self.seed}"
        if self.target == "drive" and self.drive_s != DRIVE_S:
            base += "_d{:.0f}-{:.0f}".format(*self.drive_s)
        if self.setting == "clean":
            return base
        return base + "_rho{:.2f}-{:.2f}_t{:.2f}-{:.2f}".format(*self.rho, *self.t_atk)


def reset_options(spec: TrialSpec) -> dict:
    """The env's reset options for a spec: an approach to one target, or a drive."""
    drive = spec.drive
    if drive is not None:
        return drive.reset_options()
    return {spec.target: spec.sign, "cruise_speed": spec.speed}


def default_env(spec: TrialSpec, **env_kwargs) -> gym.Env:
    """The env of a setting: the plain env, or wrapped in the patch attack."""
    if spec.target == "drive":
        env_kwargs.setdefault("max_episode_s", DRIVE_MAX_EPISODE_S)
    env = gym.make(sim.ENV_ID, **env_kwargs)
    if spec.setting == "attack":
        env = PatchAttack(env, rho=spec.rho, duration_s=spec.t_atk)
    return env


@dataclass(frozen=True)
class TrialResult:
    """The result row of one trial."""

    trial_id: str
    setting: str
    sign: int
    speed: float
    seed: int
    rho: float
    t_atk_s: float
    attack_start_s: float
    lost_frames: int
    success: bool
    stopped: bool
    stop_distance_m: float
    t_brake_s: float
    t_ideal_s: float
    latency_s: float
    duration_s: float
    outcome: str
    n_targets: int = 1
    targets_served: int = 0

    def to_dict(self) -> dict:
        return asdict(self)


StepHook = Callable[[gym.Env, dict, dict, dict], None]


def run_trial(spec: TrialSpec, estimator: DistanceEstimator | None = None,
              braking: BrakingConfig | None = None,
              make_env: Callable[[TrialSpec], gym.Env] | None = None,
              on_step: StepHook | None = None) -> tuple[TrialResult, pd.DataFrame]:
    """Runs one episode; returns its result row and per-step log.

    Args:
        spec: the trial.
        estimator: the distance source (default raw depth).
        braking: braking parameters.
        make_env: builds the env (default :func:`default_env`: plain, or under the patch attack).
        on_step: called as ``on_step(env, obs, info, row)`` after each step's decision
            (figures, viewers); it must not change anything.
    """
    env = make_env(spec) if make_env is not None else default_env(spec)
    try:
        return _run(env, spec, estimator or RawDepthEstimator(), braking or BrakingConfig(), on_step)
    finally:
        env.close()


@dataclass
class _TargetScore:
    """What one target of an episode came to (filled while the episode runs)."""

    t_brake: float = math.nan
    t_ideal: float = math.nan
    rest_distance: float = math.nan
    outcome: str = "timeout"

    @property
    def success(self) -> bool:
        return SUCCESS_BAND_M[0] <= self.rest_distance <= SUCCESS_BAND_M[1]

    def close(self) -> None:
        """Final outcome once the target is left behind: a rest outside the band names the failure."""
        if not math.isnan(self.rest_distance) and not self.success:
            self.outcome = "stopped_early" if self.rest_distance > SUCCESS_BAND_M[1] else "stopped_past_line"


def _run(env: gym.Env, spec: TrialSpec, estimator: DistanceEstimator, braking: BrakingConfig,
         on_step: StepHook | None) -> tuple[TrialResult, pd.DataFrame]:
    obs, info = env.reset(seed=spec.seed, options=reset_options(spec))
    u = env.unwrapped
    dt = 1.0 / u.config.control_hz
    camera = camera_model(env)
    perceptions = {"sign": Perception(camera),
                   "obstacle": Perception(camera, detector=ObstacleDetector(), target="obstacle")}
    targets = u.route_targets
    follower = route_follower(u.route_path, info["cruise_speed"], info["route_s"])
    bumper_ahead_of_axle = float(u.model.site("front_bumper").pos[0]) - follower.steering.config.front_axle_m
    # d_clean under an attack: the same pipeline on the env's own, unattacked readings.
    attacked = _has_attack(env)

    def begin(slot: int):
        depth_at_line = sign_depth_at_line(env, targets[slot])
        estimator.reset()
        perceptions[targets[slot].kind].reset()
        return (perceptions[targets[slot].kind], StopSignBraker(braking, depth_at_line),
                StopSignBraker(braking, depth_at_line), _TargetScore())

    slot = 0
    scan_time = -math.inf
    perception, braker, ideal, score = begin(slot)
    scores = [score]
    rows: list[dict] = []
    max_steps = int(round(u.config.max_episode_s / dt))
    for _ in range(max_steps):
        # The car's own localisation and the map say which target is next (as the env's rule does).
        while (slot + 1 < len(targets) and follower.progress_m + bumper_ahead_of_axle - targets[slot].stop_s
               > PASS_LINE_M):
            score.close()
            slot += 1
            perception, braker, ideal, score = begin(slot)
            scores.append(score)
        speed = float(obs["state"][0])
        # A scan is handed to the tracker once, on the step it arrives (the LiDAR runs at 10 Hz).
        scan_new = info["lidar_time"] != scan_time
        scan_time = info["lidar_time"]
        sample = perception.process(obs["rgb"], obs["depth"], obs["lidar"] if scan_new else None, speed=speed,
                                    yaw_rate=float(obs["state"][2]), lateral_speed=float(obs["state"][4]), dt=dt,
                                    map_bearing=map_bearing(env, targets[slot], info["pose"]))
        if attacked:
            clean = u.sensor_observation()
            d_clean = perception.depth.estimate(clean["depth"], perception.detector.detect(clean["rgb"]))[0]
        else:
            d_clean = sample.d_meas
        d_fused = float(estimator.estimate(sample, speed, dt))
        decision = braker.step(sample.detected, d_fused, speed, dt)
        # Perfect perception: d_true while the sign is in view, no measurement otherwise.
        in_view = bool(info["sign_in_view"])
        ideal_decision = ideal.step(in_view, float(info["d_true"]) if in_view else math.nan, speed, dt)
        if decision.brake and math.isnan(score.t_brake):
            score.t_brake = info["time"]
        if ideal_decision.brake and math.isnan(score.t_ideal):
            score.t_ideal = info["time"]
        x, y, yaw = info["pose"]
        speed_cmd, steer_cmd = follower.act(x, y, yaw, speed, dt, decision.speed_cap_mps)
        rows.append({
            "t": info["time"], "slot": slot, "target": targets[slot].name,
            "d_true": info["d_true"], "d_clean": d_clean, "d_meas": sample.d_meas,
            "c_meas": sample.c_meas, "lidar": sample.lidar_m, "d_fused": d_fused, "detected": sample.detected,
            "det_confidence": sample.detection_confidence, "bearing": sample.bearing_rad,
            **dict(zip(("det_x0", "det_y0", "det_x1", "det_y1"),
                       sample.detection.box if sample.detection is not None else (-1, -1, -1, -1))),
            "sign_in_view": bool(info["sign_in_view"]), "confirmed": decision.confirmed, "phase": decision.phase.value,
            "brake": decision.brake, "ideal_brake": ideal_decision.brake, "speed_cap": decision.speed_cap_mps,
            "speed_cmd": speed_cmd, "steer_cmd": steer_cmd, "x": x, "y": y, "yaw": yaw, "speed": info["speed"],
            "dist_to_stop_line": info["dist_to_stop_line"], "lateral_error": info["lateral_error"],
            "attack_active": bool(info.get("attack_active", False)), "attack": "+".join(info.get("attack", ())),
            # The vehicle state as the car measures it, and the LiDAR's forward sector (compact scan).
            **{f"state_{name}": float(v) for name, v in zip(STATE_FIELDS, obs["state"])},
            "scan_new": scan_new, "scan_fov": scan_fov(obs["lidar"]),
        })
        if on_step is not None:
            on_step(env, obs, info, rows[-1])
        if math.isnan(score.rest_distance) and abs(info["speed"]) < _AT_REST_MPS and info["time"] > 0:
            score.rest_distance = float(info["dist_to_stop_line"])
        last = slot == len(targets) - 1
        if decision.phase is Phase.DONE:
            score.outcome = "stopped"
            if last:
                break
        if info["dist_to_stop_line"] < -RUN_THROUGH_M and score.outcome == "timeout":
            score.outcome = "ran_line"
            if last:
                break
        obs, _, terminated, truncated, info = env.step(np.array([speed_cmd, steer_cmd], np.float32))
        if terminated or truncated:
            if score.outcome == "timeout":
                score.outcome = "collision" if info["collision"] else "off_road" if info["off_road"] else \
                    "ran_line" if info["dist_to_stop_line"] < 0 else "timeout"
            break
    score.close()

    first = scores[0]
    log = pd.DataFrame(rows)
    log.insert(0, "trial_id", spec.trial_id)
    patch = _find_wrapper(env, PatchAttack)
    windows = patch.schedule.windows if patch is not None else []
    lost = int((log["attack_active"] & log["sign_in_view"] & ~log["detected"]).sum())
    served = sum(sc.success for sc in scores)
    result = TrialResult(spec.trial_id, spec.setting, spec.sign, spec.speed, spec.seed,
                         patch.rho if patch is not None else math.nan,
                         windows[0][1] - windows[0][0] if windows else math.nan,
                         windows[0][0] if windows else math.nan, lost,
                         bool(served == len(targets)), not math.isnan(first.rest_distance),
                         first.rest_distance, first.t_brake, first.t_ideal, first.t_brake - first.t_ideal,
                         float(log["t"].iloc[-1]), first.outcome if len(targets) == 1 else
                         ",".join(sc.outcome for sc in scores), len(targets), served)
    return result, log


def _find_wrapper(env: gym.Env, kind: type) -> gym.Env | None:
    while isinstance(env, gym.Wrapper):
        if isinstance(env, kind):
            return env
        env = env.env
    return None


def _has_attack(env: gym.Env) -> bool:
    return _find_wrapper(env, AttackWrapper) is not None
