"""racf's own scenarios, registered the way a user's are (``racf.scenarios`` entry points):
the approach to a stop sign, the approach to a crate, a drive past several targets, and
cross-traffic at a stop sign."""

from __future__ import annotations

from typing import Any

import numpy as np

from racf.experiments.episode.car import route_follower
from racf.experiments.scenarios.base import Param, Scenario
from racf.sim.world.traffic import MAX_TRAFFIC_CARS, conflict_of, cross_traffic

__all__ = ["SignApproach", "ObstacleApproach", "Drive", "CrossTraffic", "arrival_s"]


class SignApproach(Scenario):
    name = "sign"
    meaning = "approach one of the map's four stop signs and stop at its line"
    target = "sign"


class ObstacleApproach(Scenario):
    name = "obstacle"
    meaning = "approach one of the two crates standing in the lane and stop before it"
    target = "obstacle"


class Drive(Scenario):
    name = "drive"
    meaning = "a random route drawn from the seed that meets two or more stop signs or crates"
    target = "drive"


class CrossTraffic(Scenario):
    """Other cars crossing at the stop sign's conflict point, timed from the ego car's plan:
    the first passes ``gap_s`` after the ego car would have, had it not stopped."""

    name = "cross_traffic"
    meaning = "a stop-sign approach with other cars crossing where the ego car's path meets theirs"
    target = "sign"
    params = (
        Param("cars", 1, 1, MAX_TRAFFIC_CARS, unit="cars", meaning="how many other cars cross"),
        Param("gap_s", 0.0, -5.0, 5.0, unit="s",
              meaning="when the first passes the conflict point after the ego car would have (0: together)"),
        Param("speed", 1.0, 0.1, 3.0, unit="m/s", meaning="the other cars' speed"),
    )
    metrics = ("conflict",)

    def env_settings(self, spec: Any, values: dict[str, Any]) -> dict[str, Any]:
        return {"traffic_cars": values["cars"]}

    def plan(self, spec, values, draft):
        # Timed from the plan: where the ego car starts and how fast it goes.
        mission = draft.mission
        conflict = conflict_of(spec.sign)
        t_ego = arrival_s(mission.path, draft.start_s_m, mission.cruise_mps, conflict.ego_s)
        traffic = cross_traffic(spec.sign, t_ego, gap_s=values["gap_s"], speed_mps=values["speed"], cars=values["cars"])
        options = {**draft.reset_options, "traffic": [car.to_options() for car in traffic]}
        return self.replace(draft, reset_options=options, traffic=traffic, conflict=conflict)


def arrival_s(path, start_s: float, cruise_mps: float, s_target: float) -> float:
    """When a car that never brakes for the sign would bring its body origin from ``start_s`` to
    ``s_target`` along ``path``, s: at the car's own speed reference (the cruise speed, capped in
    curves by its lane follower's profile)."""
    profile = route_follower(path, cruise_mps, start_s).profile
    s = path.arclength[(path.arclength > start_s) & (path.arclength < s_target)]
    knots = np.concatenate([[start_s], s, [s_target]])
    speeds = np.array([profile.at(k, cruise_mps) for k in knots])
    return float(np.sum(np.diff(knots) / np.maximum(0.5 * (speeds[1:] + speeds[:-1]), 0.05)))


