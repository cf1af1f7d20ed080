"""Episodes with cross-traffic: a stop yields, a missed stop is a crash, and the same seed gives the same log."""

import pandas as pd
import pytest

from racf.experiments.episode import TrialSpec, run_trial
from racf.experiments.episode.plan import plan_episode
from racf.experiments.episode.runner import RUN_THROUGH_M, run_through_m


@pytest.fixture(scope="module")
def missed():
    # The patch from the 3rd step of sight over the whole approach: raw depth loses the sign and never brakes.
    spec = TrialSpec("attack", 3, 1.5, 2, rho=(1.0, 1.0), t_atk=(20.0, 20.0), target="cross_traffic", scenario_params={"cars": 1},
                     stable_steps=3)
    return run_trial(spec, clean_pass=False)


def test_a_stop_at_the_line_yields_to_the_crossing_car():
    result, log = run_trial(TrialSpec("clean", 3, 1.5, 2, target="cross_traffic", scenario_params={"cars": 1}))
    assert result.success and result.conflict == "yielded" and not result.collision
    assert log["traffic0_x"].notna().all() and log["traffic1_x"].isna().all()


def test_a_missed_stop_is_a_crash_with_the_crossing_car(missed):
    result, log = missed
    assert not result.success and result.failure in ("never_confirmed", "confirmed_lost")
    assert result.conflict == "collision" and result.collision_with == "traffic0" and result.min_ttc_s == 0.0
    assert log["collision_with"].iloc[-1] == "traffic0"


def test_the_same_seed_gives_the_same_log_with_traffic(missed):
    spec = TrialSpec("attack", 3, 1.5, 2, rho=(1.0, 1.0), t_atk=(20.0, 20.0), target="cross_traffic", scenario_params={"cars": 1},
                     stable_steps=3)
    result, log = run_trial(spec, clean_pass=False)
    assert result.to_dict() == missed[0].to_dict()
    pd.testing.assert_frame_equal(log, missed[1])


def test_with_traffic_the_episode_runs_on_past_the_conflict_point():
    plain, crossed = plan_episode(TrialSpec("clean", 1, 1.5, 0)), plan_episode(TrialSpec("clean", 1, 1.5, 0,
                                                                                          target="cross_traffic", scenario_params={"cars": 1}))
    assert run_through_m(plain) == RUN_THROUGH_M
    assert run_through_m(crossed) > crossed.conflict.ego_s - crossed.mission.targets[0].stop_s
    # The car's mission is the same: it is told nothing of the other cars.
    assert crossed.mission == plain.mission and "traffic" in crossed.reset_options


def test_traffic_needs_a_stop_sign_approach():
    with pytest.raises(ValueError, match="scenario .obstacle. has no parameter"):
        TrialSpec("clean", 0, 1.5, 0, target="obstacle", scenario_params={"cars": 1})
    with pytest.raises(ValueError, match="parameter .gap_s. must be a float in \\[-5.0, 5.0\\]"):
        TrialSpec("clean", 0, 1.5, 0, target="cross_traffic", scenario_params={"cars": 1, "gap_s": 9.0})
