"""The stop rule judges only the targets that stood all along: a sign that stood for part of an
episode (taken away, or a picture that came and went) is no target to stop for."""

import numpy as np
import pandas as pd

from racf.experiments.episode.criteria import StopRule, NoNeedlessStop, standing_outcomes


class _Episode:
    def __init__(self, log):
        self.log = log


def _log(stands: list[bool]) -> pd.DataFrame:
    n = len(stands)
    return pd.DataFrame({"t": np.arange(n) * 0.02, "slot": 0, "sign_stands": stands, "speed": 1.0, "brake": False, "dist_to_stop_line": 1.0, "ideal_brake": False, "confirmed": False,
                         "target": "sign1"})


def test_a_sign_that_stood_for_part_of_the_episode_is_no_stop_rule_target():
    part = _Episode(_log([True] * 5 + [False] * 5))
    assert not StopRule().applies(part) and standing_outcomes(part.log) == []
    assert NoNeedlessStop().applies(part)
    whole = _Episode(_log([True] * 10))
    assert StopRule().applies(whole) and not NoNeedlessStop().applies(whole)


def test_a_trial_s_headline_says_what_each_criterion_that_applied_says():
    from racf.experiments.episode.criteria import verdict_line
    from racf.experiments.scenarios.lead_vehicle import KeepsHeadway, NoLeadCollision, NoNeedlessHardBrake

    criteria = (NoLeadCollision, KeepsHeadway, NoNeedlessHardBrake)
    kept = {"no_lead_collision": True, "keeps_headway": False, "no_needless_hard_brake": True, "min_gap_m": 0.2436,
            "min_ttc_s": 1.31}
    assert verdict_line(kept, criteria) == "followed without contact, min_gap 0.244 m, min_ttc 1.31 s"
    assert verdict_line({**kept, "no_lead_collision": False, "min_ttc_s": float("nan")}, criteria) == \
        "touched the car ahead, min_gap 0.244 m"
    stop = (StopRule, NoNeedlessStop)
    assert verdict_line({"stop_rule": False, "no_needless_stop": None, "failure": "braked_late"}, stop) == \
        "no success (braked_late)"
    assert verdict_line({"stop_rule": True}, stop) == "success" and verdict_line({}, stop) == ""
