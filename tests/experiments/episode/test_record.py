"""The step log's one declaration: the runner's rows, the scorer and the dataset all follow it."""

import math

import pytest

from racf.experiments.data.dataset import COLUMNS
from racf.experiments.episode import TrialSpec, run_trial
from racf.experiments.episode.record import STEP_COLUMNS, STEP_LOG, columns_of, step_row
from racf.experiments.episode.scoring import LOG_COLUMNS

_VALUES = {c.name: 0.0 for c in STEP_COLUMNS if c.name not in ("trial_id", "w", "flag")}


def test_every_column_has_a_unit_a_meaning_and_a_side():
    assert len(STEP_LOG) == len(STEP_COLUMNS)
    for column in STEP_COLUMNS:
        assert column.meaning and column.side in ("car", "referee", "episode"), column
    assert {"d_true", "x", "dist_to_stop_line", "ideal_brake"} <= set(columns_of("referee"))
    assert {"d_meas", "d_fused", "x_est", "brake"} <= set(columns_of("car"))


def test_a_row_keeps_the_declared_order_and_takes_the_estimators_diagnostics():
    row = step_row(_VALUES, {"w": 0.5, "odca_source": 2})
    assert list(row)[:len(STEP_COLUMNS) - 1] == [c.name for c in STEP_COLUMNS[1:]]
    assert row["w"] == 0.5 and math.isnan(row["flag"]) and row["odca_source"] == 2


@pytest.mark.parametrize("change, message", [
    (lambda v: v.pop("d_meas"), "missing \\['d_meas'\\]"),
    (lambda v: v.update(speed_of_light=3e8), "undeclared \\['speed_of_light'\\]"),
])
def test_a_row_that_leaves_out_or_adds_a_column_is_refused(change, message):
    values = dict(_VALUES)
    change(values)
    with pytest.raises(ValueError, match=message):
        step_row(values, {})


def test_diagnostics_cannot_overwrite_a_declared_column():
    with pytest.raises(ValueError, match="d_true"):
        step_row(_VALUES, {"d_true": 1.0})


def test_the_scorer_and_the_dataset_read_declared_columns_with_the_declared_units():
    assert set(LOG_COLUMNS) <= set(STEP_LOG)
    assert COLUMNS["lidar"] == (STEP_LOG["lidar"].unit, STEP_LOG["lidar"].meaning)
    assert COLUMNS["yaw_rate"][0] == STEP_LOG["state_yaw_rate_radps"].unit == "rad/s"


def test_a_logged_episode_has_exactly_the_declared_columns_and_the_estimators_own():
    _, log = run_trial(TrialSpec("clean+odca", 1, 2.0, 0), clean_pass=False)
    assert list(log.columns[:len(STEP_COLUMNS)]) == [c.name for c in STEP_COLUMNS]
    assert set(log.columns[len(STEP_COLUMNS):]) == {"odca_source", "d_kin"}
