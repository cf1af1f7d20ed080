"""``racf bench traffic``: what another car does to the clean pipeline, paired with the empty map.

Three placements (issue 37), each an ordinary clean approach run twice on the same seed, once
with one other car driven past the place that tests the pipeline and once without it:

- ``between``: at sign 1 a car drives north on the lane between the ego car and the sign,
  and crosses the line of sight to the sign when the ego car's bumper is 1 m before its line;
- ``behind_sign``: at sign 3 the crossing car passes behind the sign, on the line of sight,
  then (its returns and its body come at the sign's bearing);
- ``red_car``: at sign 2 a red car comes the other way on the next lane, 15 degrees left of
  the sign and further away then (a red body in view beside the sign).

The other car is put in through the env's reset options; the car's side is told nothing. Per
setting the table gives SCR (Wilson interval), the detector's recall over the steps the sign is
in view, and the share of those steps on which the depth distance or the LiDAR reference was
more than ``OFF_M`` from d_true (the referee's ground truth: a measurement, never fed back).
"""

from __future__ import annotations

from dataclasses import dataclass

import gymnasium as gym
import numpy as np
import pandas as pd

from racf.experiments.episode import TrialSpec, run_trial
from racf.experiments.episode.plan import plan_episode
from racf.experiments.scenarios.cross_traffic import arrival_s
from racf.experiments.episode.stack import default_env
from racf.stats import wilson_interval
from racf.sim.world.road_graph import qcar2_road_graph
from racf.sim.world.traffic import TrafficCar
from racf.sim.world.traffic_manager import TrafficManager

__all__ = ["CASES", "TrafficCase", "measure_case", "OFF_M"]

#: A distance this far from d_true is a wrong one, m.
OFF_M = 0.3


@dataclass(frozen=True)
class TrafficCase:
    """One placement: the sign, the other car's route and where on it the car stands in the ego
    camera's view when the ego car's bumper is ``at_m`` before its line: on the line of sight to
    the sign (``t`` = the share of the way to it, below 1: between; above 1: behind), turned
    ``turn_deg`` to the left of it."""

    name: str
    sign: int
    route: tuple[int, ...]
    t_range: tuple[float, float]
    colour: str
    about: str
    turn_deg: float = 0.0
    at_m: float = 1.0


CASES = {
    "between": TrafficCase("between", 1, (8, 23, 21), (0.2, 0.9), "blue",
                           "a car between the ego car and the sign (sign 1: on the lane beside it)"),
    "behind_sign": TrafficCase("behind_sign", 3, (1, 7, 14, 16), (1.1, 4.0), "blue",
                               "a car crossing just behind the sign (sign 3)", at_m=0.5),
    "red_behind": TrafficCase("red_behind", 0, (14, 20, 22), (1.2, 8.0), "red",
                              "a red car coming the other way behind the sign, as the ego car stops (sign 0)",
                              at_m=0.4),
    "red_car": TrafficCase("red_car", 2, (15, 5, 3), (1.5, 8.0), "red",
                           "a red car coming the other way on the next lane, in view beside the sign (sign 2)",
                           turn_deg=22.0, at_m=0.5),
}


def _place_s(case: TrafficCase, spec: TrialSpec) -> tuple[float, float]:
    """(arclength along the other car's route of its place, when the ego car gets there s)."""
    plan = plan_episode(spec)
    target, cal = plan.mission.targets[0], plan.calibration
    start_s = target.stop_s - spec.run_up_m - cal.bumper_x_m  # the body origin's start
    at_s = target.stop_s - case.at_m - cal.bumper_x_m
    when = arrival_s(plan.mission.path, start_s, plan.mission.cruise_mps, at_s)
    x, y, yaw = plan.mission.path.pose_at(at_s)
    c, s = np.cos(yaw), np.sin(yaw)
    (cx, cy) = cal.camera_xy_m
    cam = np.array([x + c * cx - s * cy, y + s * cx + c * cy])
    sight = np.asarray(target.target.position) - cam
    turn = np.radians(case.turn_deg)
    sight = np.array([[np.cos(turn), -np.sin(turn)], [np.sin(turn), np.cos(turn)]]) @ sight
    path = qcar2_road_graph().route_path(list(case.route))
    rel = path.points - cam
    t = rel @ sight / (sight @ sight)
    off = np.abs(rel[:, 0] * sight[1] - rel[:, 1] * sight[0]) / np.linalg.norm(sight)
    off[(t < case.t_range[0]) | (t > case.t_range[1])] = np.inf
    if not np.isfinite(off).any():
        raise ValueError(f"case {case.name}: route {case.route} never crosses the view it is meant for")
    return float(path.arclength[int(np.argmin(off))]), when


def _other_car(case: TrafficCase, spec: TrialSpec, speed_mps: float = 1.0) -> dict:
    """The other car's reset option: at its place when the ego car's bumper is ``at_m`` before its line."""
    place, when = _place_s(case, spec)
    length = qcar2_road_graph().route_path(list(case.route)).length
    start = place - speed_mps * when
    depart = max(0.0, -start / speed_mps)
    return TrafficCar(case.route, max(0.0, start), speed_mps, length, case.colour, depart).to_options()


class _WithCar(gym.Wrapper):
    """Adds the other car to every reset's options (the experimenter's hand, not the car's)."""

    def __init__(self, env: gym.Env, car: dict) -> None:
        super().__init__(env)
        self._car = car

    def reset(self, **kwargs):
        options = {**(kwargs.pop("options", None) or {}), "traffic": [self._car]}
        return self.env.reset(options=options, **kwargs)


def _row(results: list, logs: list[pd.DataFrame]) -> dict:
    steps = pd.concat(logs)
    seen = steps[steps["sign_in_view"].astype(bool)]
    n, k = len(results), sum(r.success for r in results)
    d_off = (seen["d_meas"] - seen["d_true"]).abs() > OFF_M
    l_off = (seen["lidar"] - seen["d_true"]).abs() > OFF_M
    return {"n": n, "scr": k / n, "scr_ci": list(wilson_interval(k, n)),
            "collisions": int(sum(r.collision for r in results)),
            "recall": float(seen["detected"].astype(bool).mean()), "steps_in_view": int(len(seen)),
            "depth_off_share": float(d_off.mean()), "lidar_off_share": float(l_off.mean())}


def measure_case(case: TrafficCase, seeds: int = 10, estimator: str = "raw") -> dict:
    """The case's two settings (``empty``, ``traffic``) over ``seeds`` paired clean approaches at 1 m/s."""
    setting = "clean" + ("" if estimator == "raw" else f"+{estimator}")
    out: dict = {"case": case.name, "about": case.about, "sign": case.sign, "estimator": estimator}
    runs: dict[str, tuple[list, list]] = {"empty": ([], []), "traffic": ([], [])}
    for seed in range(seeds):
        spec = TrialSpec(setting, case.sign, 1.0, seed, run_up_m=2.0)
        car = _other_car(case, spec)
        for name, make in (("empty", None),
                           ("traffic", lambda s: _WithCar(default_env(s, world=(TrafficManager(1),)), car))):
            result, log = run_trial(spec, make_env=make, clean_pass=False)
            runs[name][0].append(result)
            runs[name][1].append(log)
    for name, (results, logs) in runs.items():
        out[name] = _row(results, logs)
    return out
