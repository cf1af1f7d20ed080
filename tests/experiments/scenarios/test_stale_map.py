"""The stale-map scenario's plans: what the car's map says against what stands (racf.experiments.scenarios.stale_map)."""

import numpy as np
import pytest

from racf.experiments.episode import TrialSpec
from racf.experiments.episode.plan import plan_episode
from racf.experiments.scenarios.stale_map import CASES


def _plan(case, sign=2, **params):
    return plan_episode(TrialSpec("clean", sign, 1.0, 0, target="stale_map", scenario_params={"case": case, **params}))


@pytest.mark.parametrize("case", CASES)
def test_the_world_and_the_map_each_case_sets(case):
    plan = _plan(case)
    (target,) = plan.mission.targets
    props = plan.reset_options["sign_props"]
    assert props["remove"] == (2 if case in ("removed", "phantom") else None)
    assert props["phantom"] == (2 if case == "phantom" else None)
    assert target.mapped == (case not in ("temporary", "phantom"))
    assert plan.env_kwargs["world"] and plan.start_s_m == _plan("mapped").start_s_m


@pytest.mark.parametrize("shift", [-1.2, 0.7])
def test_a_moved_sign_is_listed_shift_m_from_where_it_stands_along_the_lane(shift):
    (real,) = _plan("mapped").mission.targets
    (listed,) = _plan("moved", shift_m=shift).mission.targets
    assert listed.stop_s == pytest.approx(real.stop_s - shift) and listed.target_s == pytest.approx(real.target_s - shift)
    moved = np.hypot(*(np.subtract(listed.target.position, real.target.position)))
    assert moved == pytest.approx(abs(shift), rel=0.05)  # along a straight lane, as far as it moved


def test_a_move_too_small_to_matter_is_refused():
    with pytest.raises(ValueError, match="shift_m"):
        TrialSpec("clean", 0, 1.0, 0, target="stale_map", scenario_params={"case": "moved", "shift_m": 0.05})
    with pytest.raises(ValueError, match="case"):
        TrialSpec("clean", 0, 1.0, 0, target="stale_map", scenario_params={"case": "gone"})


def test_a_move_beyond_its_range_is_refused_naming_it():
    with pytest.raises(ValueError, match=r"parameter 'shift_m' must be a float in \[-1.5, 1.5\] m, got 2.0"):
        TrialSpec("clean", 0, 1.0, 0, target="stale_map", scenario_params={"case": "moved", "shift_m": 2.0})


@pytest.mark.parametrize("case", ["removed", pytest.param("phantom", marks=pytest.mark.slow)])  # 1.4 s each
def test_where_no_sign_stands_there_is_no_scr_and_no_broken_stop_rule_but_needless_stops(case, caplog):
    """The referee's world has no sign (its body is under the floor): the stop rule does not apply, the
    needless-stop rule does, and the driving score is that rule's."""
    from racf.experiments.episode import run_trial

    result, log = run_trial(TrialSpec("clean+vote", 2, 1.0, 0, target="stale_map", scenario_params={"case": case}),
                            clean_pass=False)
    assert "raised" not in caplog.text  # every metric knew the rule does not apply; none fell over
    row = result.to_dict()
    assert not log["sign_stands"].any() and not log["sign_in_view"].any()
    assert row["success"] is None and row["failure"] is None and row["robustness_m"] is None
    assert row["stop_rule"] is None and row["no_needless_stop"] is (not row["needless_stop"])
    assert row["driving_score"] == (0.7 if row["needless_stop"] else 1.0)
