"""The lead_vehicle scenario: its plan, its refusals, its scorer and its episodes."""

import math
from dataclasses import replace

import numpy as np
import pandas as pd
import pytest

from racf.experiments.episode import TrialSpec, run_trial
from racf.experiments.episode.plan import plan_episode
from racf.experiments.scenarios.lead_vehicle import LeadVehicle, lead_rest_s
from racf.experiments.scenarios.lead_vehicle.following import (MIN_HEADWAY_S, NEEDLESS_TTC_S, hard_brakes,
                                                             needless_hard_brakes, score_following)
from racf.sim.world.traffic import CAR_FOOTPRINT_M


def spec(**params) -> TrialSpec:
    return TrialSpec("clean", 1, 1.0, 0, target="lead_vehicle", scenario_params=params)


def test_its_plan_puts_the_lead_its_gap_ahead_and_tells_the_car_to_follow():
    plan = plan_episode(spec(gap_m=0.8, profile="hard_brake", speed=0.6, decel=3.0, brake_t=3.0))
    lead = plan.extras["lead"]
    assert plan.mission.stages == ("following",)
    assert plan.reset_options["lead"] == {**lead.to_options(), "broadcast": False}
    assert plan_episode(spec(broadcast="on")).reset_options["lead"]["broadcast"] is True
    # The rules of its road, stated to the car: the hardest the lead brakes and pulls away.
    assert (plan.mission.target_decel_mps2, plan.mission.target_accel_mps2) == (6.0, 2.0)
    assert lead.start_s - plan.start_s_m == pytest.approx(0.8 + CAR_FOOTPRINT_M[0])
    assert lead.stop_s == pytest.approx(plan.mission.targets[-1].stop_s - plan.calibration.bumper_x_m)
    assert plan.extras["lead_rest_s"] == pytest.approx(3.0 + 0.6 / 3.0, abs=0.03)
    assert plan_episode(TrialSpec("clean", 1, 1.0, 0)).mission.stages == ()


def test_it_refuses_what_it_cannot_run_saying_what_is_allowed():
    with pytest.raises(ValueError, match="leaves the lead no road"):
        plan_episode(TrialSpec("clean", 3, 1.0, 0, target="lead_vehicle", scenario_params={"gap_m": 2.0}))
    with pytest.raises(ValueError, match="profile.*must be one of"):
        spec(profile="swerve")
    with pytest.raises(ValueError, match="no --estimator-endpoint"):
        TrialSpec("clean+odca", 1, 1.0, 0, target="lead_vehicle", estimator_endpoint="tcp://127.0.0.1:5555")


def log_of(gap, ego, lead, touched=None, dt=0.02) -> pd.DataFrame:
    n = len(gap)
    x = np.zeros(n)
    return pd.DataFrame({"t": np.arange(n) * dt, "x": x, "y": x, "yaw": x, "lead_x": np.asarray(gap) + CAR_FOOTPRINT_M[0],
                         "lead_y": x, "lead_yaw": x, "speed": ego, "lead_speed": lead,
                         "collision_with": touched or [""] * n})


def test_the_scorer_reads_gap_time_to_collision_and_headway():
    out = score_following(log_of([1.0, 0.8, 0.6, 0.45], [1.0] * 4, [0.0, 0.0, 0.0, 0.5]))
    assert out.min_gap_m == pytest.approx(0.45) and out.min_ttc_s == pytest.approx(0.6)
    # Under 0.5 s of headway at 1 m/s: the last step only.
    assert out.headway_violation_s == pytest.approx(0.02) and not out.lead_collision
    hit = score_following(log_of([0.2, 0.0], [1.0, 1.0], [0.0, 0.0], ["", "lead"]))
    assert hit.lead_collision and hit.min_ttc_s == 0.0
    # Creeping up at 0.05 m/s, 2 cm behind: under the moving speed, no headway to keep.
    creeping = score_following(log_of([0.3, 0.02], [0.05, 0.05], [0.0, 0.0]))
    assert creeping.headway_violation_s == 0.0
    apart = score_following(log_of([1.0, 1.1], [0.5, 0.5], [1.0, 1.0]))
    assert math.isnan(apart.min_ttc_s) and apart.headway_violation_s == 0.0 and MIN_HEADWAY_S == 0.5


def test_the_scorer_averages_the_time_gap_while_moving_and_says_when_the_episode_ended():
    out = score_following(log_of([1.0, 0.8, 0.6, 0.6], [1.0, 0.5, 0.05, 0.0], [0.0] * 4))
    # Moving at 1 and 0.5 m/s: gaps 1.0 and 0.8 are 1.0 and 1.6 s of headway; the rest stands.
    assert out.mean_time_gap_s == pytest.approx(1.3) and out.finish_s == pytest.approx(0.06)
    assert math.isnan(score_following(log_of([1.0, 1.0], [0.0, 0.0], [0.0, 0.0])).mean_time_gap_s)


def test_a_hard_brake_is_counted_once_per_run_of_braking():
    t = np.arange(0, 3, 0.02)
    v = np.where(t < 1, 1.0, np.maximum(1.0 - 5.0 * (t - 1), 0.0))
    assert hard_brakes(pd.DataFrame({"t": t, "speed": v})) == 1
    assert hard_brakes(pd.DataFrame({"t": t, "speed": np.ones_like(t)})) == 0


def test_a_hard_brake_is_needless_only_when_the_real_lead_asked_for_none():
    t = np.arange(0, 2, 0.02)
    v = np.where(t < 1, 1.0, np.maximum(1.0 - 5.0 * (t - 1), 0.0))  # one hard brake at 1 s
    n = len(t)

    def braking(gap_m, lead_mps):
        frame = log_of([gap_m] * n, v, [lead_mps] * n)
        frame["t"] = t
        return frame

    # The lead 1.5 m ahead at the car's own speed: nothing asked for a brake (a phantom did).
    assert needless_hard_brakes(braking(1.5, 1.0)) == 1 and score_following(braking(1.5, 1.0)).needless_hard_brakes == 1
    # Closing at 1 m/s from 1.5 m: 1.5 s to collision, under NEEDLESS_TTC_S; the brake was asked for.
    assert needless_hard_brakes(braking(1.5, 0.0)) == 0 and NEEDLESS_TTC_S == 3.0
    # 0.4 m behind at 1 m/s: under the minimum headway, the brake was asked for.
    assert needless_hard_brakes(braking(0.4, 1.0)) == 0
    # The lead at the car's speed 1.5 m ahead brakes hard itself 0.5 s before: the car's hard brake answers it.
    lead = np.where(t < 0.5, 1.0, np.maximum(1.0 - 6.0 * (t - 0.5), 0.0))
    answering = log_of([1.5] * n, v, lead)
    answering["t"] = t
    assert needless_hard_brakes(answering) == 0
    # The same lead braking 1.5 s before the car's brake (past ANSWER_S): the car's brake answers nothing.
    late = np.where(t < 1.0, 1.0, 1.0)  # the lead never braked
    assert needless_hard_brakes(log_of([1.5] * n, v, late).assign(t=t)) == 1
    # No lead at all: every hard brake is needless.
    no_lead = braking(1.5, 1.0).assign(lead_x=np.nan)
    assert needless_hard_brakes(no_lead) == 1 and hard_brakes(no_lead) == 1


def test_the_gap_is_the_supervisor_s_clear_gap_in_a_bend_too():
    from racf.sim.sensors.calibration import car_build

    build = car_build(320, 240)
    # The lead 1 m ahead of the ego's origin, turned 30 degrees: its rear centre lies 0.2125 m behind its
    # origin along its own heading; the ego's bumper 0.2125 m ahead of its origin.
    assert build.bumper_x_m == pytest.approx(0.2125)
    frame = log_of([0.0], [0.0], [0.0]).assign(lead_x=1.0, lead_yaw=math.radians(30))
    rear_x, rear_y = 1.0 - 0.2125 * math.cos(math.radians(30)), -0.2125 * math.sin(math.radians(30))
    expected = math.hypot(rear_x - 0.2125, rear_y)
    assert score_following(frame).min_gap_m == pytest.approx(expected)


def test_a_lead_that_never_stops_rests_at_the_horizon():
    lead = plan_episode(spec(profile="cruise")).extras["lead"]
    assert lead_rest_s(lead, 30.0) < 30.0  # a cruising lead still stops at the sign's line
    assert LeadVehicle().run_up(spec()) == pytest.approx(7.0)


@pytest.mark.slow  # 2.5-6 s: the default run keeps under two minutes on 2 cores
def test_the_car_follows_a_hard_braking_lead_without_touching_it():
    result, log = run_trial(spec(profile="hard_brake"), clean_pass=False)
    row = result.to_dict()
    assert row["no_lead_collision"] is True and row["min_gap_m"] > 0.1
    # Over once both stood: well before the 30 s limit.
    assert log["t"].iloc[-1] < 10.0 and log["lead_detected"].mean() > 0.5


def test_the_patch_reading_the_lead_far_is_a_real_attack_on_raw_depth():
    result, log = run_trial(TrialSpec("clean+lead_patch", 1, 1.0, 0, target="lead_vehicle", t_atk=6.0), clean_pass=False)
    row = result.to_dict()
    assert row["no_lead_collision"] is False and row["driving_score"] == pytest.approx(0.6)
    assert log["collision_with"].iloc[-1] == "lead"  # the contact ended the episode


def test_the_episode_waits_for_the_lead_to_rest_for_good_then_for_the_car_to_stand_behind_it():
    plan = plan_episode(spec(profile="stop_and_go"))
    rest = plan.extras["lead_rest_s"]
    dt = plan.control_dt_s

    def rows(t_end: float, standing_s: float) -> list[dict]:
        """The car driving, then standing for ``standing_s`` up to ``t_end``, short of the sign's line."""
        n = int(round(t_end / dt))
        stood = int(round(standing_s / dt))
        return [{"t": k * dt, "speed": 0.0 if k >= n - stood else 0.5, "slot": 0, "phase": "approach",
                 "dist_to_stop_line": 1.0} for k in range(n)]

    scenario = LeadVehicle()
    # Standing behind a lead that stopped only for a while (stop and go): not over, however long it stands.
    assert rest > 3.0 and not scenario.over(plan, rows(rest - 0.5, 2.0))
    # Past the lead's last rest: over once the car has stood a second, not before.
    assert scenario.over(plan, rows(rest + 2.0, 1.1)) and not scenario.over(plan, rows(rest + 2.0, 0.5))


def test_foreign_messages_accepted_and_genuine_ones_refused_are_counted_apart():
    """The criterion reads which radio slots the car accepted and which held the world's own messages."""
    from types import SimpleNamespace

    from racf.experiments.scenarios.lead_vehicle import RefusesForeignMessages

    # Step 1: a genuine message in slot 0 accepted, a forgery in slot 1 refused. Step 2: the lead's own
    # message in slot 0 refused (locked out) while a foreign one in slot 1 is taken. Step 3: nothing.
    log = pd.DataFrame({"radio_injected": [1, 1, 0], "lead_bc_refused": [1, 2, 2],
                        "lead_bc_slots": [0b01, 0b10, 0], "radio_genuine_slots": [0b01, 0b01, 0]})
    criterion, episode = RefusesForeignMessages(), SimpleNamespace(log=log)
    assert criterion.applies(episode)
    assert criterion.measures(episode) == {"bc_injected": 2, "bc_refused": 2, "bc_foreign_accepted": 1,
                                           "bc_genuine_refused": 1}
    assert not criterion.passed(episode)
    honest = log.assign(lead_bc_slots=[0b01, 0b01, 0])
    assert criterion.passed(SimpleNamespace(log=honest))
    assert not criterion.applies(SimpleNamespace(log=log.assign(radio_injected=0)))


@pytest.mark.slow
def test_a_stolen_key_s_phantom_is_taken_and_a_key_from_outside_the_fleet_never():
    """Closed loop, the lead broadcasting: a forger outside the fleet has every message refused and the lead's
    own all taken; a thief with vehicle 5's key has its phantom taken (what no receiver can refuse)."""
    base = TrialSpec("clean", 1, 1.0, 3, target="lead_vehicle", t_atk=(3.0, 3.0),
                     scenario_params={"profile": "cruise", "broadcast": "on"})
    forged, _ = run_trial(replace(base, setting="clean+radio_forge"))
    stolen, _ = run_trial(replace(base, setting="clean+radio_stolen_key"))
    forged, stolen = forged.to_dict(), stolen.to_dict()
    assert forged["bc_injected"] > 10 and forged["bc_foreign_accepted"] == 0 and forged["bc_genuine_refused"] == 0
    assert stolen["bc_foreign_accepted"] > 10 and stolen["refuses_foreign_messages"] is False
