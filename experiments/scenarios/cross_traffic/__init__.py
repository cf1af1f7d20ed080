"""Cross-traffic at a stop sign: other cars cross where the ego car's path meets theirs, timed from
the ego car's plan so that a missed stop meets them (issue 37's scenario).

Everything cross-traffic is lives here and in its world: the scenario (:class:`CrossTraffic`),
its metric (``conflict``: :mod:`.metric`, from the pure scorer :mod:`.conflict`), its end (run on
until the whole car has cleared the conflict point, then watch for the post-encroachment time),
and on the simulator's side the other cars (``racf.sim.world.traffic``) and their world manager
(``racf.sim.world.traffic_manager``), which logs their poses and the conflict point. The engine
names none of it. The ``--traffic-cars``/``--traffic-gap``/``--traffic-speed`` flags and a sweep
spec's ``[traffic]`` table are this scenario's parameters by older names (:attr:`CrossTraffic.aliases`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from racf.controllers import Phase
from racf.experiments.car.software import route_follower
from racf.experiments.episode.criteria import TARGET_CRITERIA, NoContact
from racf.experiments.scenarios.base import RUN_THROUGH_M, Param, Scenario
from racf.experiments.scenarios.cross_traffic.conflict import NEAR_MISS_S
from racf.sim.world.traffic import CAR_FOOTPRINT_M, MAX_TRAFFIC_CARS, conflict_of, cross_traffic
from racf.sim.world.traffic_manager import TrafficManager, traffic_option

__all__ = ["CrossTraffic", "NoVehicleCollision", "arrival_s", "run_through_m"]


class NoVehicleCollision(NoContact):
    """Touch no other car (CARLA's ``CollisionTest`` against vehicles: x 0.60, and the route ends)."""

    name = "no_vehicle_collision"
    checks = "the car touched no other car"
    penalty = 0.60

    def guards(self, touched: str) -> bool:
        return touched.startswith("traffic")  # the manager's names for its cars: traffic0, traffic1, ...


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
    criteria = (*TARGET_CRITERIA, NoVehicleCollision)
    aliases = {"traffic_cars": "cars", "traffic_gap": "gap_s", "traffic_speed": "speed"}
    table, control = "traffic", {"cars": 0}

    def world(self, spec: Any, values: dict[str, Any]) -> tuple:
        return (TrafficManager(values["cars"]),)

    def plan(self, spec, values, draft):
        # Timed from the plan: where the ego car starts and how fast it goes.
        mission = draft.mission
        conflict = conflict_of(spec.sign)
        t_ego = arrival_s(mission.path, draft.start_s_m, mission.cruise_mps, conflict.ego_s)
        cars = cross_traffic(spec.sign, t_ego, gap_s=values["gap_s"], speed_mps=values["speed"], cars=values["cars"])
        options = {**draft.reset_options, "traffic": traffic_option(cars, conflict.xy)}
        return self.replace(draft, reset_options=options, extras={**draft.extras, "cars": cars, "conflict": conflict})

    def report(self, frame, summary: dict) -> tuple[list[str], dict]:
        from racf.experiments.scenarios.cross_traffic.report import report

        return report(frame, summary)

    def over(self, plan, rows: list[dict]) -> bool:
        """Over once the car stopped for good at its last target, or the whole car has cleared the
        conflict point (a missed stop there is scored by what it meets, not by the line) and the
        post-encroachment time has been watched for (``NEAR_MISS_S`` more)."""
        run_through = run_through_m(plan)
        linger = round(NEAR_MISS_S / plan.control_dt_s)
        last = len(plan.mission.targets) - 1
        if rows[-1]["slot"] == last and rows[-1]["phase"] == Phase.DONE.value:
            return True
        past = 0
        for row in reversed(rows[-(linger + 1):]):
            if row["slot"] != last or row["dist_to_stop_line"] >= -run_through:
                break
            past += 1
        return past > linger


def run_through_m(plan) -> float:
    """How far past the last line the bumper runs before the episode ends, m: far enough for the
    whole car to clear the conflict point."""
    conflict = plan.extras["conflict"]
    past_line = conflict.ego_s - plan.mission.targets[-1].stop_s
    return max(RUN_THROUGH_M, past_line + CAR_FOOTPRINT_M[0] + 0.1)


def arrival_s(path, start_s: float, cruise_mps: float, s_target: float) -> float:
    """When a car that never brakes for the sign would bring its body origin from ``start_s`` to
    ``s_target`` along ``path``, s: at the car's own speed reference (the cruise speed, capped in
    curves by its lane follower's profile)."""
    profile = route_follower(path, cruise_mps, start_s).profile
    s = path.arclength[(path.arclength > start_s) & (path.arclength < s_target)]
    knots = np.concatenate([[start_s], s, [s_target]])
    speeds = np.array([profile.at(k, cruise_mps) for k in knots])
    return float(np.sum(np.diff(knots) / np.maximum(0.5 * (speeds[1:] + speeds[:-1]), 0.05)))
