"""The driving score: a stop sign run costs x 0.80, a crash into another car x 0.60 more."""

import pytest

from racf.experiments.episode import TrialSpec, run_trial
from racf.experiments.scorecard.battery import PENALTIES
from racf.experiments.scorecard.drives import drive_score


def test_a_missed_stop_into_cross_traffic_pays_both_penalties():
    spec = TrialSpec("attack", 3, 1.5, 2, rho=(1.0, 1.0), t_atk=(20.0, 20.0), target="cross_traffic", scenario_params={"cars": 1}, stable_steps=3)
    _, log = run_trial(spec, clean_pass=False)
    score = drive_score(log, 1, PENALTIES)
    assert score["infractions"] == {"ran_stop_sign": 1, "hit_static_object": 0, "hit_vehicle": 1}
    assert score["penalty"] == pytest.approx(0.80 * 0.60)
    # The same episode on the empty map: the line is run, nothing is hit.
    _, empty = run_trial(TrialSpec("attack", 3, 1.5, 2, rho=(1.0, 1.0), t_atk=(20.0, 20.0), stable_steps=3),
                         clean_pass=False)
    assert drive_score(empty, 1, PENALTIES)["infractions"]["hit_vehicle"] == 0
