"""Episodes with cross-traffic: a stop yields, a missed stop is a crash, the same seed gives the same log,
and the scenario, not the engine, says when its episode is over."""

import pandas as pd
import pytest

from racf.experiments.episode import TrialSpec, run_trial
from racf.experiments.episode.plan import plan_episode
from racf.experiments.scenarios import Scenario
from racf.experiments.scenarios.base import RUN_THROUGH_M
from racf.experiments.scenarios.cross_traffic import CrossTraffic, run_through_m
from racf.experiments.scenarios.cross_traffic.conflict import NEAR_MISS_S


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
    # The scenario's own criterion judged it: the crash fails no_vehicle_collision and costs its penalty.
    assert result.no_vehicle_collision is False and result.stop_rule is False
    assert result.driving_score == pytest.approx(0.80 * 0.60)


def test_the_same_seed_gives_the_same_log_with_traffic(missed):
    spec = TrialSpec("attack", 3, 1.5, 2, rho=(1.0, 1.0), t_atk=(20.0, 20.0), target="cross_traffic", scenario_params={"cars": 1},
                     stable_steps=3)
    result, log = run_trial(spec, clean_pass=False)
    assert result.to_dict() == missed[0].to_dict()
    pd.testing.assert_frame_equal(log, missed[1])


def test_with_traffic_the_episode_runs_on_past_the_conflict_point():
    plain, crossed = plan_episode(TrialSpec("clean", 1, 1.5, 0)), plan_episode(TrialSpec("clean", 1, 1.5, 0,
                                                                                          target="cross_traffic", scenario_params={"cars": 1}))
    run_through = run_through_m(crossed)
    assert run_through > crossed.extras["conflict"].ego_s - crossed.mission.targets[0].stop_s > RUN_THROUGH_M
    # The car's mission is the same: it is told nothing of the other cars.
    assert crossed.mission == plain.mission and "traffic" in crossed.reset_options
    # A plain approach ends just past the line; cross-traffic runs on past the conflict point, then
    # watches NEAR_MISS_S more for the post-encroachment time.
    past_line = [{"slot": 0, "phase": "braking", "dist_to_stop_line": -RUN_THROUGH_M - 0.01}]
    assert Scenario().over(plain, past_line) and not CrossTraffic().over(crossed, past_line)
    linger = round(NEAR_MISS_S / crossed.control_dt_s)
    past_point = [{"slot": 0, "phase": "braking", "dist_to_stop_line": -run_through - 0.01}] * (linger + 1)
    assert not CrossTraffic().over(crossed, past_point[:-1]) and CrossTraffic().over(crossed, past_point)


def test_traffic_needs_a_stop_sign_approach():
    with pytest.raises(ValueError, match="scenario .obstacle. has no parameter"):
        TrialSpec("clean", 0, 1.5, 0, target="obstacle", scenario_params={"cars": 1})
    with pytest.raises(ValueError, match="parameter .gap_s. must be a float in \\[-5.0, 5.0\\]"):
        TrialSpec("clean", 0, 1.5, 0, target="cross_traffic", scenario_params={"cars": 1, "gap_s": 9.0})


def test_a_car_done_with_its_last_target_ends_any_episode_by_default():
    crossed = plan_episode(TrialSpec("clean", 1, 1.5, 0, target="cross_traffic", scenario_params={"cars": 1}))
    done = [{"slot": 0, "phase": "done", "dist_to_stop_line": 0.3}]
    assert Scenario().over(crossed, done) and CrossTraffic().over(crossed, done)
    assert not Scenario().over(crossed, [{**done[0], "phase": "stopped"}])
