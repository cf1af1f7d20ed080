"""The one step loop: env -> the car (:mod:`~racf.experiments.car.software`) -> env, with the referee
(:mod:`~racf.experiments.episode.referee`) watching.

Trials, dataset collection and the demo all run episodes through :func:`run_trial`. The car
gets the observation only; the referee gets everything and feeds nothing back. Per step the
log records every signal of the protocol (d_true, d_clean, d_meas, c_meas, l, d_fused, the
gate w under ODCA), the controller's state and brake command, the reference controller's
(``ideal_brake``, which defines t*), the car's pose estimate (``x_est``, ``y_est``,
``yaw_est``) beside the true pose (``x``, ``y``, ``yaw``) and speed. The result row comes
from :func:`racf.experiments.episode.scoring.score_log` on that log, so a stored log can be
rescored without running anything.

Timing: the controller runs every ``round(50 / control_hz)`` steps and holds its action between;
with ``delay_ms`` its actions reach the car that much later (a FIFO of whole 20 ms steps).
Both are off by default. The reference controller runs every step without delay.
"""

from __future__ import annotations

import logging
import math
from collections import deque
from dataclasses import dataclass
from typing import Callable

import gymnasium as gym
import numpy as np
import pandas as pd

from racf.controllers import DistanceEstimator
from racf.experiments.episode.record import stage_columns, step_row, world_columns
from racf.experiments.episode.referee import Referee
from racf.experiments.episode.spec import TrialSpec
from racf.experiments.episode.plan import EpisodePlan, plan_episode
from racf.experiments.episode.stack import build_car, default_env
from racf.plugins import METRICS
from racf.sim.attacks.base import AttackWrapper, find_wrapper
from racf.sim.sensors import STATE_FIELDS

__all__ = ["TrialResult", "IDENTITY", "Episode", "StepHook", "run_trial", "scan_fov", "SCAN_FOV_HALF_BEAMS",
           "car_columns", "grant_white_box", "ActionLine", "late_steps", "SCENARIO_PREFIX", "scenario_columns"]

#: A result row's scenario parameter ``name`` is its column ``scenario_<name>``.
SCENARIO_PREFIX = "scenario_"
#: Half-width of the LiDAR sector kept in the logs, in beams of the 360-beam scan (1 deg each).
SCAN_FOV_HALF_BEAMS = 40

StepHook = Callable[[gym.Env, dict, dict, dict], None]
_log = logging.getLogger(__name__)


def scan_fov(ranges: np.ndarray, half_beams: int = SCAN_FOV_HALF_BEAMS) -> np.ndarray:
    """The forward sector of a scan: beams -half..+half (entry j at (j - half) beam steps CCW
    from forward), float32 m, inf = no return. For 360 beams that is -40..+40 deg."""
    ranges = np.asarray(ranges, np.float32)
    return np.concatenate([ranges[-half_beams:], ranges[:half_beams + 1]])


@dataclass(frozen=True)
class Episode:
    """What a metric (``racf.experiments.metrics``) scores: the spec, the plan, the per-step log and
    the env as it ran (its attack wrappers' schedules say when an attack acted)."""

    spec: TrialSpec
    plan: EpisodePlan
    log: pd.DataFrame
    env: gym.Env


#: The result row's first columns: which episode it is (the metrics' fields come after them).
IDENTITY = ("trial_id", "setting", "estimator", "target", "sign", "speed", "seed")


class TrialResult:
    """The result row of one episode: which episode it is (``IDENTITY``), then the fields of every
    metric it scored (``racf.plugins.METRICS``, in their ``order``; ``racf list metrics`` says what
    each field means). Fields read as attributes (``result.success``); :meth:`to_dict` is the row."""

    def __init__(self, row: dict) -> None:
        object.__setattr__(self, "_row", dict(row))

    def __getattr__(self, name: str):
        try:
            return self._row[name]
        except KeyError:
            raise AttributeError(f"the result row has no field {name!r}; its fields: {list(self._row)}") from None

    def __setattr__(self, name: str, value) -> None:
        raise AttributeError("a result row is read-only")

    def __eq__(self, other: object) -> bool:
        return isinstance(other, TrialResult) and self.to_dict() == other.to_dict()

    def __repr__(self) -> str:
        return f"TrialResult({self._row!r})"

    def to_dict(self) -> dict:
        """Strict-JSON-ready: NaN becomes None."""
        return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in self._row.items()}


def run_trial(spec: TrialSpec, estimator: DistanceEstimator | None = None, make_env: Callable[[TrialSpec], gym.Env] | None = None,
              on_step: StepHook | None = None, clean_pass: bool = True) -> tuple[TrialResult, pd.DataFrame]:
    """Runs one episode; returns its result row and per-step log.

    Args:
        spec: the episode.
        estimator: overrides the spec's estimator (an object with the ``DistanceEstimator`` protocol).
        make_env: builds the env (default :func:`~racf.experiments.episode.stack.default_env`); it
            must be the env the plan describes (``plan_episode(spec).env_kwargs``).
        on_step: called as ``on_step(env, obs, info, row)`` after each step's decision
            (figures, viewers); it must not change anything.
        clean_pass: under attack, also run perception on the env's own unattacked readings
            to log ``d_clean``. It is a diagnostic the car never sees: without it the log's
            ``d_clean`` is NaN under attack and everything else, the result row included, is
            the same. Sweeps that keep no per-step log skip it.
    """
    plan = plan_episode(spec)  # pure: a plan the spec cannot have fails before the simulator is built
    env = make_env(spec) if make_env is not None else default_env(spec)
    try:
        log = _run(env, spec, plan, estimator, on_step, clean_pass)
        return _result(spec, plan, env, log), log
    finally:
        env.close()


def _run(env: gym.Env, spec: TrialSpec, plan: EpisodePlan, estimator, on_step: StepHook | None,
         clean_pass: bool) -> pd.DataFrame:
    obs, info = env.reset(seed=spec.seed, options=plan.reset_options)
    dt = plan.control_dt_s
    delay_steps = int(round(spec.delay_ms / 1000.0 / dt))
    # The car gets its build and its mission before it starts, then only observations.
    car = build_car(spec, plan, estimator, env)
    grant_white_box(env, car.estimator)
    scenario = spec.scenario
    # The world's own ground truth: every column the env's world managers declare, logged by name.
    truth_columns = world_columns(env.unwrapped.world)
    # The car's stages' columns, on its side, before the truth's.
    declared = stage_columns(car.stages) + truth_columns
    referee = Referee(car.calibration, spec.braking, dt, find_wrapper(env, AttackWrapper) is not None, clean_pass,
                      tuple(c.name for c in truth_columns))
    ending = tuple(c() for c in scenario.criteria if c.terminates)
    actions = ActionLine(delay_steps)
    rows: list[dict] = []
    try:
        for _ in range(plan.max_steps):
            step = car.step(obs)
            applied = actions.push(step.action, late_steps(car.estimator, dt) if step.control else 0)
            truth = referee.observe(env, obs, info, step, car.target, car.perception)
            rows.append(step_row({**car_columns(car, step, obs, info["time"], applied), **truth},
                                 car.estimator.diagnostics(), declared))
            if on_step is not None:
                on_step(env, obs, info, rows[-1])
            if scenario.over(plan, rows) or any(c.fails_at(rows[-1]) for c in ending):
                break
            obs, _, terminated, truncated, info = env.step(applied)
            if terminated or truncated:
                if info.get("collision_with"):  # the contact that ended it belongs to the last row's step
                    rows[-1]["collision_with"] = info["collision_with"]
                break
    finally:
        close = getattr(car.estimator, "close", None)
        if estimator is None and callable(close):  # a defence racf opened (a service's session) ends with it
            close()
    log = pd.DataFrame(rows)
    log.insert(0, "trial_id", spec.trial_id)
    return log


class ActionLine:
    """The actions on their way to the wheels: each arrives ``delay_steps`` (the spec's fixed
    delay) plus its own ``late`` steps after it was decided, and the wheels take the newest that has
    arrived (an older one arriving after it is dropped). Before any has arrived they take the first
    decided. With ``late`` always 0 this is the fixed FIFO delay.
    """

    def __init__(self, delay_steps: int) -> None:
        self.delay = int(delay_steps)
        self._pending: deque = deque()
        self._k = 0
        self._applied = None
        self._applied_index = -1

    def push(self, action: np.ndarray, late: int = 0) -> np.ndarray:
        """This step's decided action; returns the one the wheels take this step."""
        k = self._k
        self._pending.append((k + self.delay + late, k, action))
        arrived = [p for p in self._pending if p[0] <= k]
        if arrived:
            _, index, newest = max(arrived, key=lambda p: p[1])
            if index > self._applied_index:
                self._applied, self._applied_index = newest, index
            self._pending = deque(p for p in self._pending if p[1] > index)
        elif self._applied is None:
            self._applied = self._pending[0][2]
        self._k += 1
        return self._applied


def late_steps(estimator, dt: float) -> int:
    """Whole control periods a defence's last answer overran (``latency_s``, measured by a remote
    defence): an answer within the period is in time for the step's action. 0 for one in the car."""
    latency = getattr(estimator, "latency_s", None)
    return int(latency // dt) if latency else 0


def car_columns(car, step, obs: dict, t: float, applied: np.ndarray) -> dict:
    """The car's side of one step's row (``racf.experiments.episode.record``): what its software made
    of the observation ``obs`` at time ``t`` (its ``step``) and the action that reached the wheels."""
    sample, decision = step.sample, step.decision
    return {
        "t": t, "slot": step.slot, "target": car.target.name, "control": step.control,
        "d_meas": sample.d_meas, "c_meas": sample.c_meas, "lidar": sample.lidar_m, "d_fused": step.d_fused,
        "d_size": sample.d_size, "size_std": sample.size_std,
        "detected": sample.detected,
        "det_confidence": sample.detection_confidence, "bearing": sample.bearing_rad,
        **dict(zip(("det_x0", "det_y0", "det_x1", "det_y1"),
                   sample.detection.box if sample.detection is not None else (-1, -1, -1, -1))),
        "confirmed": decision.confirmed, "phase": decision.phase.value,
        "brake": decision.brake, "speed_cap": decision.speed_cap_mps,
        "speed_cmd": float(applied[0]), "steer_cmd": float(applied[1]),
        # The car's own pose estimate beside the referee's truth (x, y, yaw).
        "x_est": float(step.pose[0]), "y_est": float(step.pose[1]), "yaw_est": float(step.pose[2]),
        # The localiser's fix as the car received it (held between fixes).
        **{f"fix_{k}": float(v) for k, v in zip(("x", "y", "yaw"), obs["gps"])},
        # The vehicle state as the car measures it, and the LiDAR's forward sector (compact scan).
        **{f"state_{name}": float(v) for name, v in zip(STATE_FIELDS, obs["state"])},
        "frame_new": step.frame_new, "scan_new": step.scan_new, "scan_fov": scan_fov(obs["lidar"]),
        # The LiDAR reference's tracked point in the body frame (NaN without a track), for viewers.
        "track_x": step.tracked_xy[0], "track_y": step.tracked_xy[1],
        # Each engaged car stage's own columns (``CarStage.columns``).
        **{name: value for said in step.stages.values() for name, value in said.values.items()},
    }


def _result(spec: TrialSpec, plan: EpisodePlan, env: gym.Env, log: pd.DataFrame) -> TrialResult:
    """The row: the episode's identity and its scenario's parameters (``scenario_<name>``), then each
    metric that applies to its scenario (``Metric.applies_to``; a field it leaves out takes its default). A metric that raises costs its own
    fields (their defaults, logged in one line naming it), never the episode."""
    episode = Episode(spec, plan, log, env)
    row = {"trial_id": spec.trial_id, "setting": spec.setting, "estimator": spec.estimator, "target": spec.target,
           "sign": spec.sign, "speed": spec.speed, "seed": spec.seed, **scenario_columns(spec.scenario_params)}
    for name in spec.metric_names:
        metric = METRICS[name]()
        if metric.applies_to(spec.scenario):  # a measure the scenario's criteria do not ask for is no column
            row |= metric.defaults() | scored(metric, episode)
    return TrialResult(row)


def scenario_columns(values: dict) -> dict:
    """A scenario's parameter values as result columns: ``scenario_<name>`` each."""
    return {f"{SCENARIO_PREFIX}{name}": value for name, value in values.items()}


def scored(metric, episode: Episode) -> dict:
    """One metric's fields on one episode; a metric that raises gives none (the row keeps its defaults)
    and the fault is logged in one line naming the metric and the episode."""
    try:
        return metric.score(episode)
    except Exception as err:  # a plug-in's fault is its own: the episode's other fields stand
        _log.warning("metric %r raised %s: %s; its fields are null for episode %s", metric.name, type(err).__name__,
                     err, episode.spec.trial_id)
        return {}


def grant_white_box(env: gym.Env, defence) -> None:
    """Hands the defence to every white-box attack in the env's wrappers (their threat model)."""
    while isinstance(env, gym.Wrapper):
        if isinstance(env, AttackWrapper) and env.threat_model == "white box":
            env.attach_defence(defence)
        env = env.env


