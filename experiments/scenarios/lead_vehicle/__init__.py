"""The car ahead: a second QCar 2 leads the ego car down its lane towards a stop sign, with a speed
profile (cruise, slow down, hard brake to a stop, stop and go), and the ego car must follow it
without touching it (issue 59's scenario).

Everything lead-vehicle is lives here and in its world: the scenario (:class:`LeadVehicle`), its
criteria (a collision with the lead ends the episode, CARLA's vehicle penalty x 0.60; the
following measures: the smallest gap and time-to-collision, the time under the minimum headway,
hard brakes: :mod:`.following`), its end (the lead at rest for good and the car at rest behind it),
and on the simulator's side the lead (``racf.sim.world.lead``) and its world manager
(``racf.sim.world.lead_manager``). The car's side follows it with its own perception
(``racf.controllers.following``); nothing here reaches the car.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from racf.experiments.episode.criteria import Criterion, NoContact
from racf.experiments.episode.fields import Field
from racf.experiments.scenarios.base import Param, Scenario
from racf.experiments.scenarios.lead_vehicle.following import MIN_HEADWAY_S, NEEDLESS_TTC_S, score_following
from racf.sim.world.lead import LAUNCH_MPS2, LEAD_PROFILES, LeadCar
from racf.sim.world.lead_manager import LeadManager
from racf.sim.world.traffic import CAR_FOOTPRINT_M, TRAFFIC_COLOURS

__all__ = ["LeadVehicle", "NoLeadCollision", "KeepsHeadway", "NoNeedlessHardBrake", "RefusesForeignMessages",
           "lead_rest_s", "REST_BEHIND_S"]

#: The hardest the scenario says a lead pulls away, m/s^2 (twice its stop-and-go launch).
STATED_ACCEL_MPS2 = 2.0 * LAUNCH_MPS2
#: The episode ends once the lead is at rest for good and the car has stood this long, s.
REST_BEHIND_S = 1.0
#: The episode's time limit, s (the longest profile: a stop-and-go lead that then stops at the line).
LEAD_MAX_EPISODE_S = 30.0
_AT_REST_MPS = 0.05


class NoLeadCollision(NoContact):
    """Touch not the car ahead (CARLA's ``CollisionTest`` against vehicles: x 0.60, and the route ends)."""

    name = "no_lead_collision"
    checks = "the car never touched the car ahead"
    penalty = 0.60
    said = ("followed without contact", "touched the car ahead")
    card = ("collision-free", True)

    def guards(self, touched: str) -> bool:
        return touched == "lead"


class KeepsHeadway(Criterion):
    """Keep at least ``MIN_HEADWAY_S`` of headway to the car ahead while moving (informative: it costs
    no driving score), with the following measures."""

    name = "keeps_headway"
    checks = f"the car never followed closer than {MIN_HEADWAY_S} s of headway while moving"
    optional = True
    headline = ("min_gap_m", "min_ttc_s")
    fields = (
        Field("min_gap_m", unit="m", meaning="the smallest clear gap to the car ahead", summary="median"),
        Field("min_ttc_s", unit="s", meaning="the smallest time-to-collision with the car ahead (0: contact; "
                                               "NaN: they never closed)", summary="median"),
        Field("headway_violation_s", 0.0, "s", f"time spent under {MIN_HEADWAY_S} s of headway while moving",
              summary="median"),
        Field("hard_brakes", 0, "", "decelerations past 3 m/s^2 (each run of steps once)", summary="median"),
        Field("needless_hard_brakes", 0, "", f"hard brakes begun while the real lead asked for none (time-to-"
                                             f"collision over {NEEDLESS_TTC_S} s, headway at least {MIN_HEADWAY_S} s)",
              summary="median"),
        Field("mean_time_gap_s", unit="s", meaning="the headway to the car ahead averaged over the steps the car "
                                                   "moves (NaN: it never moved behind it)", summary="median"),
        Field("finish_s", unit="s", meaning="when the episode ended: the lead at rest for good and the car stood "
                                            "behind it (or a contact, or the time limit)", summary="median"),
    )

    def passed(self, episode) -> bool:
        return score_following(episode.log).headway_violation_s == 0.0

    def measures(self, episode) -> dict[str, Any]:
        out = score_following(episode.log).to_dict()
        return {f.name: out[f.name] for f in self.fields}


class NoNeedlessHardBrake(Criterion):
    """Brake hard only when the real lead asks for it (informative: a phantom's cost, on the scorecard)."""

    name = "no_needless_hard_brake"
    checks = "the car began no hard brake while the real lead asked for none"
    optional = True
    card = ("needless hard brake", False)

    def passed(self, episode) -> bool:
        return score_following(episode.log).needless_hard_brakes == 0


class RefusesForeignMessages(Criterion):
    """The car's receiver took none of an attacker's messages and refused none of the genuine ones
    (informative: it applies where an attacker sent any; ``racf.experiments.car.broadcast``). Each
    step the receiver says which radio slots it accepted and the referee which held a message the
    world's radio delivered: a foreign message accepted and a genuine one refused are counted apart
    (one message numbered 2^32 - 1 once had the genuine lead's next 46 refused while a count of
    refusals said all was well)."""

    name = "refuses_foreign_messages"
    checks = "the car took none of an attacker's broadcast messages and refused none of the lead's own"
    optional = True
    card = ("foreign messages refused", True)
    fields = (
        Field("bc_injected", 0, "", "broadcast messages an attacker put on the air (forged, replayed, a stolen "
                                    "key's)", summary="median"),
        Field("bc_refused", 0, "", "broadcast messages the car's receiver refused (each for a reason of "
                                   "racf.sim.radio.message.REFUSALS)", summary="median"),
        Field("bc_foreign_accepted", 0, "", "messages the car accepted that the world's radio did not deliver "
                                            "then (an attacker's)", summary="median"),
        Field("bc_genuine_refused", 0, "", "messages the world's radio delivered that the car refused",
              summary="median"),
    )

    def applies(self, episode) -> bool:
        return "radio_injected" in episode.log and bool(episode.log["radio_injected"].sum() > 0)

    def passed(self, episode) -> bool:
        measured = self.measures(episode)
        return measured["bc_foreign_accepted"] == 0 and measured["bc_genuine_refused"] == 0

    def measures(self, episode) -> dict[str, Any]:
        log = episode.log
        refused = int(log["lead_bc_refused"].max()) if "lead_bc_refused" in log else 0
        accepted = _masks(log, "lead_bc_slots")
        genuine = _masks(log, "radio_genuine_slots")
        return {"bc_injected": int(log["radio_injected"].sum()), "bc_refused": refused,
                "bc_foreign_accepted": sum(bin(a & ~g).count("1") for a, g in zip(accepted, genuine)),
                "bc_genuine_refused": sum(bin(g & ~a).count("1") for a, g in zip(accepted, genuine))}


def _masks(log, column: str) -> list[int]:
    """A bit-mask column as ints (zeros where the log has none)."""
    if column not in log:
        return [0] * len(log)
    return [int(v) if v == v else 0 for v in log[column]]


class LeadVehicle(Scenario):
    """A lead car in the ego car's lane, ``gap_m`` ahead of its bumper at the start, driving its profile."""

    name = "lead_vehicle"
    meaning = "follow a car ahead in the lane (cruise, slow down, hard brake, stop and go) without touching it"
    target = "sign"
    params = (
        Param("profile", "hard_brake", choices=LEAD_PROFILES, meaning="the lead's speed profile"),
        Param("gap_m", 0.8, 0.3, 2.0, unit="m", meaning="the clear gap from the car's bumper to the lead's rear at the start"),
        Param("speed", 0.6, 0.2, 1.5, unit="m/s", meaning="the lead's cruise speed"),
        Param("decel", 3.0, 0.5, 6.0, unit="m/s^2", meaning="how hard the lead brakes (slow_down, hard_brake, stop_and_go)"),
        Param("brake_t", 3.0, 0.5, 10.0, unit="s", meaning="when the lead brakes, after the start"),
        Param("colour", "white", choices=tuple(TRAFFIC_COLOURS), meaning="the lead's paint"),
        Param("broadcast", "off", choices=("off", "on"), meaning="the lead broadcasts its own state, signed, over "
                                                              "the radio (racf.sim.radio)"),
    )
    criteria = (NoLeadCollision, KeepsHeadway, NoNeedlessHardBrake, RefusesForeignMessages)

    def check(self, spec, values) -> None:
        if spec.estimator_endpoint is not None:
            raise ValueError("scenario 'lead_vehicle' runs the defence in the car (a served defence answers for one "
                             "distance, the sign's); allowed: no --estimator-endpoint")

    def run_up(self, spec: Any) -> float | None:
        """The approach's run-up: the longest the sign allows (the lead needs road ahead of the car)."""
        from racf.experiments.episode.plan import longest_run_up

        return math.floor(longest_run_up("sign", spec.sign, spec.sign_geometry) * 10) / 10

    def env_settings(self, spec, values) -> dict:
        return {"max_episode_s": LEAD_MAX_EPISODE_S}

    def world(self, spec, values) -> tuple:
        return (LeadManager(),)

    def plan(self, spec, values, draft):
        mission = draft.mission
        # Both cars' body origins sit midway along them: one car length plus the gap apart.
        start = draft.start_s_m + values["gap_m"] + CAR_FOOTPRINT_M[0]
        # A lawful lead: it stops with its bumper at the sign's line.
        stop = mission.targets[-1].stop_s - draft.calibration.bumper_x_m
        route = tuple(int(n) for n in spec_route(spec))
        if start >= stop:
            raise ValueError(f"scenario 'lead_vehicle': a gap of {values['gap_m']} m leaves the lead no road before "
                             f"sign {spec.sign}'s line; allowed: gap_m < {stop - draft.start_s_m - CAR_FOOTPRINT_M[0]:.2f} m")
        lead = LeadCar(route, start, values["speed"], stop, values["profile"], values["decel"], values["brake_t"],
                       values["colour"])
        options = {**draft.reset_options, "lead": {**lead.to_options(), "broadcast": values["broadcast"] == "on"}}
        max_s = draft.max_steps * draft.control_dt_s
        # The car is told it drives in traffic: its following stage is engaged.
        # The car is told the lead may brake as hard as this scenario's decel allows (its a_max), and pulls
        # away no harder than twice its launch (the rules of this road, as RSS states its own).
        stated = next(p.high for p in self.params if p.name == "decel")
        mission = dataclasses.replace(mission, stages=(*mission.stages, "following"), target_decel_mps2=stated,
                                      target_accel_mps2=STATED_ACCEL_MPS2)
        return self.replace(draft, reset_options=options, mission=mission,
                            extras={**draft.extras, "lead": lead, "lead_rest_s": lead_rest_s(lead, max_s)})

    def over(self, plan, rows: list[dict]) -> bool:
        """Over once the lead is at rest for good and the car has stood ``REST_BEHIND_S`` behind it (or,
        the lead gone, the car is done with the sign)."""
        if super().over(plan, rows):
            return True
        if rows[-1]["t"] < plan.extras["lead_rest_s"]:
            return False
        stood = round(REST_BEHIND_S / plan.control_dt_s)
        recent = rows[-stood:]
        return len(recent) == stood and all(abs(r["speed"]) < _AT_REST_MPS for r in recent)


def spec_route(spec) -> tuple[int, ...]:
    """The road-graph nodes of the spec's approach (the lead drives the ego car's lane)."""
    from racf.sim.world.stop_signs import stop_signs

    return stop_signs()[spec.sign].route


def lead_rest_s(lead: LeadCar, horizon_s: float) -> float:
    """When the lead comes to rest for good, s (``horizon_s`` if it never does before it)."""
    t = np.arange(0.0, horizon_s, 0.02)
    _, v = lead.profile_at(t)
    moving = np.flatnonzero(v > 1e-6)
    if not moving.size:
        return 0.0
    last = int(moving[-1])
    return float(t[last + 1]) if last + 1 < len(t) else horizon_s
