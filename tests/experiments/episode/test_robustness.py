"""The stop rule's STL robustness: signed, in metres, and it agrees with what the car did."""

import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from racf.experiments.episode.robustness import REST_WITHIN_S, WINDOW_M, robustness, target_robustness

STEP = 0.02


def _log(gap, speed, slot=0) -> pd.DataFrame:
    n = len(gap)
    return pd.DataFrame({"t": np.arange(n) * STEP, "slot": slot, "speed": speed, "dist_to_stop_line": gap})


def _approach(v0: float, rest_gap: float, run_up: float = 3.0) -> pd.DataFrame:
    """Constant speed, then a hard stop at ``rest_gap`` before the line (negative: past it)."""
    n = int((run_up - rest_gap) / (v0 * STEP)) + 1
    gap = run_up - v0 * STEP * np.arange(n)
    tail = 20
    return _log(np.r_[gap, np.full(tail, gap[-1])], np.r_[np.full(n, v0), np.zeros(tail)])


@settings(max_examples=40, deadline=None)
@given(st.floats(0.5, 2.0), st.floats(-0.5, 1.0))
def test_a_stop_before_the_line_is_robust_by_its_gap_and_a_run_past_it_violates_by_how_far(v0, rest_gap):
    log = _approach(v0, rest_gap)
    rest = log["dist_to_stop_line"].iloc[-1]
    assert robustness(log) == pytest.approx(min(rest, 1.0), abs=1e-9)
    assert (robustness(log) < 0) == (rest < 0)


def test_a_stop_in_the_window_is_robust_by_its_gap_however_the_speed_crosses_the_rest_threshold():
    """The rest clause sees the car at rest, not only the first step under 0.05 m/s: a stop 0.3 m
    before the line reads 0.3 m whether the speed fell to 0.049 or to 0 at that step."""
    for last in (0.049, 0.0):
        gap = np.r_[np.linspace(2.0, 0.3, 80), np.full(30, 0.3)]
        speed = np.r_[np.linspace(1.5, 0.2, 79), [last], np.zeros(30)]
        assert robustness(_log(gap, speed)) == pytest.approx(0.3)


def test_crawling_in_the_window_longer_than_the_rule_allows_is_a_violation():
    n_in = int((REST_WITHIN_S + 1.0) / STEP)
    gap = np.r_[np.linspace(2.0, WINDOW_M - 0.1, 60), np.full(n_in, WINDOW_M - 0.1), [WINDOW_M - 0.1]]
    speed = np.r_[np.full(60, 1.5), np.full(n_in, 0.1), [0.0]]
    assert robustness(_log(gap, speed)) < 0  # never past the line, but never at rest in time
    quick = int((REST_WITHIN_S - 1.0) / STEP)
    gap = np.r_[np.linspace(2.0, WINDOW_M - 0.1, 60), np.full(quick, WINDOW_M - 0.1), [WINDOW_M - 0.1]]
    speed = np.r_[np.full(60, 1.5), np.full(quick, 0.1), [0.0]]
    assert robustness(_log(gap, speed)) == pytest.approx(WINDOW_M - 0.1)


def test_driving_on_after_the_stop_is_lawful_and_the_lowest_target_counts():
    stop = _approach(1.5, 0.3)
    after = _log(np.linspace(0.3, -2.0, 50), np.full(50, 1.0))  # after its rest the car goes on
    first = pd.concat([stop, after.assign(t=after["t"] + stop["t"].iloc[-1] + STEP)], ignore_index=True)
    assert robustness(first) == pytest.approx(0.3)
    second = _approach(1.0, 0.1).assign(slot=1)
    both = pd.concat([first, second.assign(t=second["t"] + first["t"].iloc[-1] + STEP)], ignore_index=True)
    assert robustness(both) == pytest.approx(0.1)


def test_no_stop_line_reads_as_no_robustness_and_a_bad_log_is_a_clear_error():
    assert math.isnan(target_robustness(_log(np.full(5, np.nan), np.ones(5))))
    with pytest.raises(ValueError, match="dist_to_stop_line"):
        robustness(pd.DataFrame({"t": [0.0], "slot": [0], "speed": [1.0]}))
