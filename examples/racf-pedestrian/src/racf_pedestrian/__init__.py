"""A person crosses the lane at a crosswalk before the stop sign: an example racf scenario.

The crosswalk lies ``ahead_m`` before the sign's stop line. The person walks across the lane, from
``HALF_CROSSING_M`` left of its centre line to as far right, at ``speed_mps``, timed from the car's
plan: they reach the centre line ``gap_s`` after the car's bumper would reach the crosswalk had it
not braked (0: together). Everything the scenario is lives here:

- its world, :class:`Walker`: a person at the car's 1/10 scale (0.18 m tall, below the LiDAR's scan
  plane at 0.193 m) on a mocap body, moved every physics step, logging its own ground truth
  (``pedestrian_x``, ``pedestrian_y``, its velocity and whether it has crossed);
- its criteria: hitting the person ends the episode and costs CARLA's pedestrian penalty (x 0.50);
  the smallest time-to-collision with the person is measured (informative, no penalty);
- its end: the episode runs on until the person has crossed, not only until the car is past the line;
- the car's side: its mission engages the example's own car stage, an automatic emergency brake for
  something upright in the lane (:mod:`.emergency_brake`), so the car stops for the person.

Nothing in racf names it: the entry points ``racf.scenarios: pedestrian_crossing`` and
``racf.car_stages: upright_in_lane`` register it.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from racf.experiments.episode.criteria import Criterion, NoContact
from racf.experiments.metrics import Field
from racf.experiments.scenarios import Param, Scenario
from racf.experiments.scenarios.cross_traffic import arrival_s
from racf.sim.world.manager import TruthColumn, WorldManager

__all__ = ["PedestrianCrossing", "Walker", "NoPedestrianCollision", "PedestrianTimeToCollision", "HALF_CROSSING_M"]

#: The person walks from this far left of the lane's centre line to as far right, m.
HALF_CROSSING_M = 0.3
#: The person: a capsule's radius and height, m (a 1.8 m adult at the car's 1/10 scale).
RADIUS_M, HEIGHT_M = 0.02, 0.18
#: Half the car's width plus the person's radius: closer than this across the car's path is a hit, m.
_HIT_M = 0.096 + RADIUS_M
#: A time-to-collision under this is a near miss, s.
TTC_LIMIT_S = 1.0
_NAN = math.nan
#: The walker's ground-truth columns (name, unit, meaning), in the order of ``Walker._state``.
_COLUMNS = (("pedestrian_x", "m", "ground truth: the person's position, map frame (NaN: none)"),
            ("pedestrian_y", "m", "ground truth: the person's position, map frame (NaN: none)"),
            ("pedestrian_vx", "m/s", "ground truth: the person's velocity, map frame"),
            ("pedestrian_vy", "m/s", "ground truth: the person's velocity, map frame"),
            ("pedestrian_crossed", "bool", "ground truth: the person has reached the far side"))


class Walker(WorldManager):
    """A person on a mocap body, walking a straight line at a constant speed (the reset option
    ``pedestrian``: ``{"from": [x, y], "to": [x, y], "start_s": t0, "speed_mps": v}``; absent: out of
    sight below the floor). Before ``start_s`` they wait at ``from``; after reaching ``to`` they stand."""

    name = option = "pedestrian"

    def scene_xml(self) -> str:
        half = HEIGHT_M / 2 - RADIUS_M
        return f"""
    <body name="pedestrian" mocap="true" pos="0 0 -5">
      <geom name="pedestrian" type="capsule" size="{RADIUS_M} {half}" pos="0 0 {HEIGHT_M / 2}" rgba="0.95 0.55 0.10 1"/>
    </body>"""

    def bind(self, model) -> None:
        self._body = model.body("pedestrian").id
        self._mocap = int(model.body_mocapid[self._body])

    def reset(self, model, data, value, physics_dt_s, max_episode_s) -> None:
        self._dt, self._walk = physics_dt_s, None
        if value is not None:
            start, end = np.asarray(value["from"], float), np.asarray(value["to"], float)
            length = float(np.linalg.norm(end - start))
            self._walk = (start, (end - start) / length, length, float(value["start_s"]), float(value["speed_mps"]))
        self.before_physics(data, 0)

    @property
    def moving(self) -> bool:
        return self._walk is not None

    def _state(self, t: float) -> tuple[float, float, float, float, bool]:
        """(x, y, vx, vy, crossed) at time ``t``."""
        if self._walk is None:
            return _NAN, _NAN, _NAN, _NAN, True
        start, direction, length, t0, speed = self._walk
        walked = min(max(speed * (t - t0), 0.0), length)
        x, y = start + walked * direction
        v = speed * direction if 0.0 < speed * (t - t0) < length else np.zeros(2)
        return float(x), float(y), float(v[0]), float(v[1]), walked >= length

    def before_physics(self, data, substep: int) -> None:
        x, y, *_ = self._state(substep * self._dt)
        data.mocap_pos[self._mocap] = (x, y, 0.0) if x == x else (0.0, 0.0, -5.0)

    def columns(self) -> tuple[TruthColumn, ...]:
        return tuple(TruthColumn(*c) for c in _COLUMNS)

    def info(self, substep: int) -> dict:
        return dict(zip((c[0] for c in _COLUMNS), self._state(substep * self._dt)))

    def owner_of(self, root_body: int) -> str | None:
        return "pedestrian" if root_body == self._body else None


def _person_in(log) -> bool:
    """Whether a person walked in this episode (their columns hold a position)."""
    return "pedestrian_x" in log and bool(np.isfinite(log["pedestrian_x"].to_numpy(float)).any())


class NoPedestrianCollision(NoContact):
    """Touch no person (CARLA's ``CollisionTest`` against pedestrians: x 0.50, and the route ends)."""

    name = "no_pedestrian_collision"
    checks = "the car touched no person"
    penalty = 0.50

    def applies(self, episode) -> bool:
        return _person_in(episode.log)

    def guards(self, touched: str) -> bool:
        return touched == "pedestrian"


def min_time_to_collision(log, bumper_x_m: float) -> float:
    """The smallest time until the car's front bumper would pass within ``_HIT_M`` of the person if
    both kept their velocity, over the steps before any contact, s (NaN: never on a collision course)."""
    touched = np.flatnonzero(log["collision_with"].astype(str).to_numpy() == "pedestrian")
    end = int(touched[0]) if touched.size else len(log)
    yaw = log["yaw"].to_numpy(float)[:end]
    heading = np.column_stack([np.cos(yaw), np.sin(yaw)])
    front = log[["x", "y"]].to_numpy(float)[:end] + bumper_x_m * heading
    p = log[["pedestrian_x", "pedestrian_y"]].to_numpy(float)[:end] - front
    v = log[["pedestrian_vx", "pedestrian_vy"]].to_numpy(float)[:end] - log["speed"].to_numpy(float)[:end, None] * heading
    vv = np.einsum("ij,ij->i", v, v)
    with np.errstate(invalid="ignore", divide="ignore"):
        t = -np.einsum("ij,ij->i", p, v) / vv
        miss = np.linalg.norm(p + t[:, None] * v, axis=1)
    course = (vv > 1e-9) & (t > 0) & (miss < _HIT_M) & np.isfinite(t)
    if touched.size:
        return 0.0
    return float(t[course].min()) if course.any() else _NAN


class PedestrianTimeToCollision(Criterion):
    """The smallest time-to-collision with the person stays at or above ``TTC_LIMIT_S`` (informative:
    it costs no driving score; the near misses it counts are a table's, not a penalty)."""

    name = "pedestrian_ttc"
    checks = f"the time-to-collision with the person stayed at or above {TTC_LIMIT_S:g} s"
    optional = True
    fields = (Field("pedestrian_min_ttc_s", _NAN, "s", "the smallest time-to-collision with the person (NaN: never "
                                                       "on a collision course)", "median"),)

    def applies(self, episode) -> bool:
        return _person_in(episode.log)

    def measures(self, episode) -> dict:
        return {"pedestrian_min_ttc_s": min_time_to_collision(episode.log, episode.plan.calibration.bumper_x_m)}

    def passed(self, episode) -> bool:
        ttc = self.measures(episode)["pedestrian_min_ttc_s"]
        return not ttc < TTC_LIMIT_S


class PedestrianCrossing(Scenario):
    """A stop-sign approach with a person crossing the lane at a crosswalk before the sign."""

    name = "pedestrian_crossing"
    meaning = "a stop-sign approach with a person crossing the lane at a crosswalk before the sign"
    target = "sign"
    params = (
        Param("ahead_m", 1.0, 0.3, 2.0, unit="m", meaning="how far before the stop line the crosswalk lies"),
        Param("gap_s", 0.0, -3.0, 3.0, unit="s",
              meaning="when the person reaches the lane's centre after the car's bumper would reach the crosswalk"),
        Param("speed_mps", 0.3, 0.1, 0.6, unit="m/s", meaning="the person's walking speed"),
        Param("walks", True, meaning="a person crosses (false: the plain approach, with the car's emergency brake on)"),
    )
    criteria = (*Scenario.criteria, NoPedestrianCollision, PedestrianTimeToCollision)

    def world(self, spec, values):
        return (Walker(),)

    def plan(self, spec, values, draft):
        mission = draft.mission
        s_cross = mission.targets[0].stop_s - values["ahead_m"]
        x, y, heading = mission.path.pose_at(s_cross)
        left = np.array([-math.sin(heading), math.cos(heading)])
        start, end = np.array([x, y]) + HALF_CROSSING_M * left, np.array([x, y]) - HALF_CROSSING_M * left
        # Timed from the plan: when the bumper would reach the crosswalk had the car not braked.
        t_car = arrival_s(mission.path, draft.start_s_m, mission.cruise_mps, s_cross - draft.calibration.bumper_x_m)
        start_s = t_car + values["gap_s"] - HALF_CROSSING_M / values["speed_mps"]
        walk = {"from": start.tolist(), "to": end.tolist(), "start_s": start_s, "speed_mps": values["speed_mps"]}
        # The car's own emergency brake for something upright in the lane (this package's car stage).
        mission = dataclasses.replace(mission, stages=(*mission.stages, "upright_in_lane"))
        options = {**draft.reset_options, "pedestrian": walk} if values["walks"] else draft.reset_options
        return self.replace(draft, reset_options=options, mission=mission,
                            extras={**draft.extras, "crosswalk_s": s_cross})

    def over(self, plan, rows: list[dict]) -> bool:
        """Over once the car is past the line (the default) and the person has crossed."""
        return super().over(plan, rows) and bool(rows[-1]["pedestrian_crossed"])
