"""The driving score: a stop sign run costs x 0.80, a crash into a vehicle the world declares x 0.60 more."""

import pytest

from racf.experiments.episode import TrialSpec, run_trial
from racf.experiments.scorecard.battery import PENALTIES
from racf.experiments.scorecard.drives import drive_score
from racf.sim.world.manager import world_targets


def test_a_missed_stop_into_cross_traffic_pays_both_penalties():
    spec = TrialSpec("attack", 3, 1.5, 2, rho=(1.0, 1.0), t_atk=(20.0, 20.0), target="cross_traffic", scenario_params={"cars": 1}, stable_steps=3)
    _, log = run_trial(spec, clean_pass=False)
    vehicles = {t.name for t in world_targets(spec.scenario.world(spec, spec.scenario_params), "vehicle")}
    assert vehicles == {"traffic0"}
    score = drive_score(log, 1, PENALTIES, vehicles)
    assert score["infractions"] == {"ran_stop_sign": 1, "hit_static_object": 0, "hit_vehicle": 1}
    assert score["penalty"] == pytest.approx(0.80 * 0.60)
    # The same episode on the empty map: the line is run, nothing is hit.
    _, empty = run_trial(TrialSpec("attack", 3, 1.5, 2, rho=(1.0, 1.0), t_atk=(20.0, 20.0), stable_steps=3),
                         clean_pass=False)
    assert drive_score(empty, 1, PENALTIES, vehicles)["infractions"]["hit_vehicle"] == 0
    # A contact with the car ahead is a vehicle hit too: whatever a world declares, not a name's prefix.
    lead = log.assign(collision_with=log["collision_with"].replace("traffic0", "lead"))
    assert drive_score(lead, 1, PENALTIES, {"lead"})["infractions"]["hit_vehicle"] == 1
    assert drive_score(lead, 1, PENALTIES, vehicles)["infractions"]["hit_vehicle"] == 0
