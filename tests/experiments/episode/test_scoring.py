"""Scoring a per-step log: success, early stop, running the line, never confirmed, and both latencies."""

import math

import numpy as np

import pandas as pd
import pytest

from racf.experiments.episode.scoring import score_log, score_target


def _log(dist, speed, brake, ideal, confirmed, slot=0, dt=0.02):
    n = len(dist)
    return pd.DataFrame({"t": [i * dt for i in range(n)], "slot": [slot] * n, "speed": speed,
                         "dist_to_stop_line": dist, "brake": brake, "ideal_brake": ideal, "confirmed": confirmed})


def test_success_with_both_latencies():
    # Reference brakes at step 2, the controller at step 4; within 0.60 m of the line from step 5.
    dist = [1.2, 1.1, 1.0, 0.9, 0.7, 0.55, 0.45, 0.40, 0.40]
    speed = [1.0, 1.0, 1.0, 1.0, 0.8, 0.5, 0.2, 0.01, 0.0]
    brake = [False] * 4 + [True] * 5
    ideal = [False] * 2 + [True] * 7
    out = score_target(_log(dist, speed, brake, ideal, [True] * 9))
    assert out.success and out.failure is None and out.rest_distance_m == pytest.approx(0.40)
    assert out.t_star_s == pytest.approx(0.04) and out.t_brake_s == pytest.approx(0.08)
    assert out.trigger_delay_s == pytest.approx(0.04) and out.dt_brake_s == pytest.approx(0.06)


def test_early_stop_is_a_failure():
    dist = [2.0, 1.5, 1.2, 1.0, 1.0]
    out = score_target(_log(dist, [1.0, 0.8, 0.3, 0.0, 0.0], [False, True, True, True, True], [False] * 5,
                            [True] * 5))
    assert not out.success and out.failure == "braked_early" and out.rest_distance_m == 1.0
    assert math.isnan(out.t_star_s) and math.isnan(out.dt_brake_s)


def test_running_the_line_unconfirmed_lost_and_late():
    dist = [0.8, 0.4, 0.0, -0.4, -0.8]
    speed = [1.0] * 5
    never = score_target(_log(dist, speed, [False] * 5, [False, True, True, True, True], [False] * 5))
    assert never.failure == "never_confirmed" and never.trigger_delay_s != never.trigger_delay_s  # NaN
    lost = score_target(_log(dist, speed, [False] * 5, [False] * 5, [True, False, False, False, False]))
    assert lost.failure == "confirmed_lost"
    late = score_target(_log(dist, speed, [False, False, True, True, True], [True] * 5, [True] * 5))
    assert late.failure == "braked_late" and late.trigger_delay_s == pytest.approx(0.04)


def test_score_log_gives_one_outcome_per_target_and_names_missing_columns():
    a = _log([1.0, 0.5, 0.3, 0.3], [1.0, 0.5, 0.0, 0.0], [False, True, True, True], [True] * 4, [True] * 4)
    b = _log([1.0, 0.4, -0.6], [1.0, 1.0, 1.0], [False] * 3, [False] * 3, [False] * 3, slot=1)
    b["t"] += 1.0
    outcomes = score_log(pd.concat([a, b], ignore_index=True))
    assert [o.slot for o in outcomes] == [0, 1]
    assert outcomes[0].success and outcomes[1].failure == "never_confirmed"
    with pytest.raises(ValueError, match="ideal_brake"):
        score_target(a.drop(columns=["ideal_brake"]))


def test_largest_jump_is_the_step_change_beyond_the_cars_motion_within_a_target():
    from racf.experiments.episode.scoring import largest_jump

    t = np.arange(8) * 0.02
    log = pd.DataFrame({"t": t, "slot": [0, 0, 0, 0, 1, 1, 1, 1], "control": True,
                        "state_speed_mps": 1.0,
                        "d_fused": [2.0, 1.98, 1.96, 2.26, 0.5, np.nan, 0.46, 0.44]})
    # 1.96 -> 2.26 with the car closing 0.02 m: 0.32 m beyond its motion; the new target's
    # first value (a change of target) and steps around a NaN (no target) do not count.
    assert largest_jump(log) == pytest.approx(0.32)
    assert np.isnan(largest_jump(log.assign(d_fused=np.nan)))
