"""The one step loop: env -> perception -> estimator -> braking -> lane follower.

Trials, dataset collection and the demo all run episodes through :func:`run_trial`. Per
step it records every signal of the protocol (d_true, d_clean, d_meas, c_meas, l,
d_fused, the gate w under ODCA), the controller's state and brake command, the reference
controller's (``ideal_brake``, which defines t*), pose and speed. The result row comes
from :func:`experiments.episode.scoring.score_log` on that log, so a stored log can be
rescored without running anything.

Timing: the controller runs every ``round(50 / control_hz)`` steps and holds its action between;
with ``delay_ms`` its actions reach the car that much later (a FIFO of whole 20 ms steps).
Both are off by default. The reference controller runs every step without delay.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import asdict, dataclass
from typing import Callable

import gymnasium as gym
import numpy as np
import pandas as pd

from controllers import Phase
from experiments.episode.car import map_bearing, route_follower
from experiments.episode.scoring import score_log
from experiments.episode.spec import TrialSpec
from experiments.episode.stack import Stack, default_env
from sim.attacks import PatchAttack
from sim.attacks.base import AttackWrapper
from sim.env.qcar2_env import PASS_LINE_M
from sim.sensors import STATE_FIELDS

__all__ = ["TrialResult", "StepHook", "run_trial", "reset_options", "scan_fov", "SCAN_FOV_HALF_BEAMS",
           "RUN_THROUGH_M"]

#: An episode ends once the bumper is this far past the last target's line.
RUN_THROUGH_M = 0.5
#: Half-width of the LiDAR sector kept in the logs, in beams of the 360-beam scan (1 deg each).
SCAN_FOV_HALF_BEAMS = 40

StepHook = Callable[[gym.Env, dict, dict, dict], None]


def scan_fov(ranges: np.ndarray, half_beams: int = SCAN_FOV_HALF_BEAMS) -> np.ndarray:
    """The forward sector of a scan: beams -half..+half (entry j at (j - half) beam steps CCW
    from forward), float32 m, inf = no return. For 360 beams that is -40..+40 deg."""
    ranges = np.asarray(ranges, np.float32)
    return np.concatenate([ranges[-half_beams:], ranges[:half_beams + 1]])


def reset_options(spec: TrialSpec) -> dict:
    """The env's reset options for a spec: an approach to one target, or a drive."""
    drive = spec.drive
    if drive is not None:
        return drive.reset_options()
    return {spec.target: spec.sign, "cruise_speed": spec.speed}


@dataclass(frozen=True)
class TrialResult:
    """The result row of one episode; the timing fields are the first target's (NaN: none).

    ``trigger_delay_s`` = t(brake) - t*; ``dt_brake_s``: t* to braking within 0.60 m of
    the line (the paper's latency); ``failure``: where a failed first target went wrong.
    ``attack_start_s`` and ``t_atk_s`` are the first window of the attack that began first
    (the patch on a tie; NaN: no attack began); ``rho`` is the patch's (NaN: no patch).
    """

    trial_id: str
    setting: str
    estimator: str
    target: str
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
    t_star_s: float
    t_brake_s: float
    trigger_delay_s: float
    dt_brake_s: float
    failure: str | None
    duration_s: float
    n_targets: int = 1
    targets_served: int = 0

    def to_dict(self) -> dict:
        """Strict-JSON-ready: NaN becomes None."""
        return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in asdict(self).items()}


def run_trial(spec: TrialSpec, estimator=None, make_env: Callable[[TrialSpec], gym.Env] | None = None,
              on_step: StepHook | None = None, clean_pass: bool = True) -> tuple[TrialResult, pd.DataFrame]:
    """Runs one episode; returns its result row and per-step log.

    Args:
        spec: the episode.
        estimator: overrides the spec's estimator (an object with the ``DistanceEstimator`` protocol).
        make_env: builds the env (default :func:`~experiments.episode.stack.default_env`).
        on_step: called as ``on_step(env, obs, info, row)`` after each step's decision
            (figures, viewers); it must not change anything.
        clean_pass: under attack, also run perception on the env's own unattacked readings
            to log ``d_clean``. It is a diagnostic the car never sees: without it the log's
            ``d_clean`` is NaN under attack and everything else, the result row included, is
            the same. Sweeps that keep no per-step log skip it.
    """
    env = make_env(spec) if make_env is not None else default_env(spec)
    try:
        log = _run(env, spec, Stack(env, spec, estimator), on_step, clean_pass)
        return _result(spec, env, log), log
    finally:
        env.close()


def _run(env: gym.Env, spec: TrialSpec, stack: Stack, on_step: StepHook | None, clean_pass: bool) -> pd.DataFrame:
    obs, info = env.reset(seed=spec.seed, options=reset_options(spec))
    u = env.unwrapped
    dt = 1.0 / u.config.control_hz
    every = max(1, int(round(u.config.control_hz / spec.control_hz))) if spec.control_hz else 1
    delay_steps = int(round(spec.delay_ms / 1000.0 / dt))
    targets = u.route_targets
    follower = route_follower(u.route_path, info["cruise_speed"], info["route_s"])
    car = stack.calibration
    bumper_ahead_of_axle = car.bumper_x_m - follower.steering.config.front_axle_m
    attacked = _find_wrapper(env, AttackWrapper) is not None
    estimator = stack.estimator
    half_fov = car.camera.half_hfov_rad

    slot = 0
    perception, braker, ideal = stack.begin(targets[slot])
    scan_time = -math.inf
    pending: deque = deque()
    action = None
    decision = sample = None
    d_fused = d_clean = math.nan
    rows: list[dict] = []
    for step in range(int(round(u.config.max_episode_s / dt))):
        # The car's own localisation and the map say which target is next (as the env's rule does).
        while (slot + 1 < len(targets)
               and follower.progress_m + bumper_ahead_of_axle - targets[slot].stop_s > PASS_LINE_M):
            slot += 1
            perception, braker, ideal = stack.begin(targets[slot])
            decision = None
        speed = float(obs["state"][0])
        # A scan is handed to the tracker once, on the step it arrives (the LiDAR runs at 10 Hz).
        scan_new = info["lidar_time"] != scan_time
        scan_time = info["lidar_time"]
        control = decision is None or step % every == 0
        if control:
            bearing = map_bearing(car, targets[slot], info["pose"])
            sample = perception.process(obs["rgb"], obs["depth"][..., 0], obs["lidar"] if scan_new else None,
                                        speed=speed, yaw_rate=float(obs["state"][2]),
                                        lateral_speed=float(obs["state"][4]), dt=dt * every, map_bearing=bearing)
            if not attacked:
                d_clean = sample.d_meas
            elif clean_pass:  # d_clean: the same pipeline on the env's own, unattacked readings
                clean = u.sensor_observation()
                # An image the attack left alone has the detection perception just made.
                unchanged = np.array_equal(clean["rgb"], obs["rgb"])
                detection = perception.last_raw_detection if unchanged else perception.detector.detect(clean["rgb"])
                d_clean = perception.depth.estimate(clean["depth"][..., 0], detection)[0]
            d_fused = float(estimator.estimate(sample, speed, dt * every))
            in_fov = math.isfinite(bearing) and abs(bearing) <= half_fov
            decision = braker.step(sample.detected, d_fused, speed, dt * every, expected_in_view=in_fov)
        # The reference: perfect perception (d_true while the target is in view) at every step.
        in_view = bool(info["sign_in_view"])
        ideal_decision = ideal.step(in_view, float(info["d_true"]) if in_view else math.nan, speed, dt)
        x, y, yaw = info["pose"]
        if control:
            action = np.array(follower.act(x, y, yaw, speed, dt * every, decision.speed_cap_mps), np.float32)
        pending.append(action)
        applied = pending.popleft() if len(pending) > delay_steps else pending[0]
        track = perception.lidar.state.position  # camera-relative; + the camera's body position
        cam_xy = perception.lidar.config.camera_position_m
        rows.append({
            "t": info["time"], "slot": slot, "target": targets[slot].name, "control": control,
            "d_true": info["d_true"], "d_clean": d_clean, "d_meas": sample.d_meas,
            "c_meas": sample.c_meas, "lidar": sample.lidar_m, "d_fused": d_fused,
            "w": math.nan, **estimator.diagnostics(), "detected": sample.detected,
            "det_confidence": sample.detection_confidence, "bearing": sample.bearing_rad,
            **dict(zip(("det_x0", "det_y0", "det_x1", "det_y1"),
                       sample.detection.box if sample.detection is not None else (-1, -1, -1, -1))),
            "sign_in_view": in_view, "confirmed": decision.confirmed, "phase": decision.phase.value,
            "brake": decision.brake, "ideal_brake": ideal_decision.brake, "speed_cap": decision.speed_cap_mps,
            "speed_cmd": float(applied[0]), "steer_cmd": float(applied[1]), "x": x, "y": y, "yaw": yaw,
            "speed": info["speed"], "dist_to_stop_line": info["dist_to_stop_line"],
            "lateral_error": info["lateral_error"],
            "attack_active": bool(info.get("attack_active", False)), "attack": "+".join(info.get("attack", ())),
            # The vehicle state as the car measures it, and the LiDAR's forward sector (compact scan).
            **{f"state_{name}": float(v) for name, v in zip(STATE_FIELDS, obs["state"])},
            "scan_new": scan_new, "scan_fov": scan_fov(obs["lidar"]),
            # The LiDAR reference's tracked point in the body frame (NaN without a track), for viewers.
            "track_x": track[0] + cam_xy[0], "track_y": track[1] + cam_xy[1],
        })
        if on_step is not None:
            on_step(env, obs, info, rows[-1])
        if slot == len(targets) - 1 and (decision.phase is Phase.DONE or info["dist_to_stop_line"] < -RUN_THROUGH_M):
            break
        obs, _, terminated, truncated, info = env.step(applied)
        if terminated or truncated:
            break
    log = pd.DataFrame(rows)
    log.insert(0, "trial_id", spec.trial_id)
    return log


def _result(spec: TrialSpec, env: gym.Env, log: pd.DataFrame) -> TrialResult:
    outcomes = score_log(log)
    first = outcomes[0]
    patch = _find_wrapper(env, PatchAttack)
    windows = _first_attack_windows(env)
    lost = int((log["attack_active"] & log["sign_in_view"] & ~log["detected"]).sum())
    n_targets = len(env.unwrapped.route_targets)
    served = sum(o.success for o in outcomes)
    return TrialResult(
        spec.trial_id, spec.setting, spec.estimator, spec.target, spec.sign, spec.speed, spec.seed,
        patch.rho if patch is not None else math.nan,
        windows[0][1] - windows[0][0] if windows else math.nan, windows[0][0] if windows else math.nan, lost,
        bool(served == n_targets), not math.isnan(first.rest_distance_m), first.rest_distance_m,
        first.t_star_s, first.t_brake_s, first.trigger_delay_s, first.dt_brake_s, first.failure,
        float(log["t"].iloc[-1]), n_targets, served)


def _first_attack_windows(env: gym.Env) -> list[tuple[float, float]]:
    """The attack windows (start, end s) of the attack that began first (the patch on a tie)."""
    attacks = []
    while isinstance(env, gym.Wrapper):
        if isinstance(env, AttackWrapper) and env.schedule.windows:
            attacks.append(env)
        env = env.env
    if not attacks:
        return []
    return min(attacks, key=lambda a: (a.schedule.windows[0][0], not isinstance(a, PatchAttack))).schedule.windows


def _find_wrapper(env: gym.Env, kind: type) -> gym.Env | None:
    while isinstance(env, gym.Wrapper):
        if isinstance(env, kind):
            return env
        env = env.env
    return None
