"""Offline scoring rules against hand-computed cases (docs/protocol.md)."""

import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings, strategies as st

from racf.experiments.offline.methods import split_arrays
from racf.experiments.offline.metrics import auprc, auroc, bounded_degradation, hold_last, mae, resilience_gain, rmse
from racf.experiments.offline.scoring import (bootstrap_rmse, diagnostic_scores, error_sources, horizon_scores,
                                         recovery_scores)
from racf.odca.align import Alignment


def test_rmse_and_mae_by_hand_ignoring_nan_and_honouring_the_mask():
    est = np.array([1.0, 2.0, np.nan, 4.0])
    ref = np.array([1.5, 1.0, 3.0, 4.0])
    # Finite pairs: errors -0.5, 1.0, 0.0.
    assert rmse(est, ref) == pytest.approx(math.sqrt((0.25 + 1.0) / 3))
    assert mae(est, ref) == pytest.approx(1.5 / 3)
    assert rmse(est, ref, mask=[True, False, True, False]) == pytest.approx(0.5)
    assert rmse(np.full(3, np.nan), np.ones(3)) is None and mae([], []) is None
    with pytest.raises(ValueError, match="same shape"):
        rmse([1.0], [1.0, 2.0])


def test_auroc_and_auprc_by_hand_and_nan_scores_left_out():
    score = np.array([0.1, 0.4, 0.35, 0.8])
    label = np.array([0, 0, 1, 1])
    # Pairs (pos, neg): (0.35 > 0.1), (0.35 < 0.4), (0.8 > both) -> 3/4.
    assert auroc(score, label) == pytest.approx(0.75)
    # Ranked 0.8(+), 0.4(-), 0.35(+), 0.1(-): AP = 1/2 * (1/1) + 1/2 * (2/3).
    assert auprc(score, label) == pytest.approx(0.5 * 1.0 + 0.5 * 2 / 3)
    with_nan = np.r_[score, np.nan, np.nan]
    assert auroc(with_nan, np.r_[label, 1, 0]) == pytest.approx(0.75)
    assert auprc(with_nan, np.r_[label, 1, 0]) == pytest.approx(auprc(score, label))
    assert auroc([0.2, 0.3], [1, 1]) is None and auprc([np.nan, 0.3], [0, 1]) is None
    assert auroc([0.5, 0.5, 0.5, 0.5], label) == pytest.approx(0.5)  # no information
    with pytest.raises(ValueError, match="labels"):
        auroc([0.1, 0.2], [0, 2])


def test_bounded_degradation_and_resilience_gain_by_hand():
    assert bounded_degradation(0.1, 0.3) == pytest.approx(2.0)
    assert bounded_degradation(None, 0.3) is None and bounded_degradation(0.0, 0.3) is None
    ours = {"weak": 0.1, "mid": 0.2, "strong": 0.3}
    chronos = {"weak": 0.2, "mid": 0.4, "strong": 0.3}
    assert resilience_gain(ours, chronos) == pytest.approx((0.5 + 0.5 + 0.0) / 3)
    assert resilience_gain(chronos, chronos) == pytest.approx(0.0)
    assert resilience_gain({"weak": None}, {"weak": 0.2}) is None


def _arrays(d_meas, d_clean, lidar=None, series=None, label=None, speed=None, d_true=None):
    n = len(d_meas)
    frame = pd.DataFrame({"series_id": series or ["a"] * n, "d_meas": d_meas, "c_meas": np.ones(n),
                          "lidar": lidar if lidar is not None else np.full(n, np.nan),
                          "speed": speed if speed is not None else np.ones(n),
                          "label": label if label is not None else np.zeros(n, int), "d_clean": d_clean,
                          "d_true": d_true if d_true is not None else d_clean})
    return split_arrays(frame, Alignment())


def test_steps_before_the_first_measurement_are_scored_for_no_method():
    a = _arrays([np.nan, np.nan, 1.0, np.nan, 0.8], [1.2, 1.1, 1.0, 0.9, 0.8])
    np.testing.assert_array_equal(a.scored, [False, False, True, True, True])
    np.testing.assert_allclose(a.raw[2:], [1.0, 1.0, 0.8])  # a blackout counts as the last valid value
    scores = recovery_scores(a.raw, a)
    assert scores["n"] == 3 and scores["rmse"] == pytest.approx(math.sqrt(0.01 / 3))


def test_moving_block_uses_only_samples_above_the_standstill_bound():
    a = _arrays([1.0, 1.0, 1.0], [1.0, 1.2, 1.4], speed=[0.0, 0.04, 1.0])
    scores = recovery_scores(a.raw, a)
    assert scores["n_moving"] == 1 and scores["rmse_moving"] == pytest.approx(0.4)


def test_horizon_score_stays_inside_its_series_and_on_scored_steps():
    a = _arrays([1.0, 1.0, 1.0, 2.0, 2.0], [1.0, 1.1, np.nan, 2.0, 2.0], series=["a", "a", "a", "b", "b"])
    origins = np.array([0, 3])
    paths = np.array([[1.0, 1.0, 1.0], [2.5, 2.5, 2.5]])
    out = horizon_scores(origins, paths, a)
    # Origin 0: steps 0 (err 0), 1 (err -0.1); step 2 is unscored. Origin 3: steps 3, 4 (err 0.5 each).
    assert out["n_h3"] == 4
    assert out["rmse_h3"] == pytest.approx(math.sqrt((0.0 + 0.01 + 0.25 + 0.25) / 4))


def test_diagnostics_xs_and_chg_separate_attacked_steps():
    # Steps 2-3 are biased by +1 m; the LiDAR tells the truth throughout.
    d_clean = np.array([2.0, 1.9, 1.8, 1.7, 1.6, 1.5])
    label = np.array([0, 0, 1, 1, 0, 0])
    a = _arrays(d_clean + label, d_clean, lidar=d_clean, label=label)
    raw = diagnostic_scores(a.raw, a)
    assert raw["auroc_xs"] == pytest.approx(1.0) and raw["auroc_chg"] == pytest.approx(0.5)
    repaired = diagnostic_scores(d_clean, a)  # a perfect repair changes exactly the attacked steps
    assert repaired["auroc_chg"] == pytest.approx(1.0) and repaired["auprc_chg"] == pytest.approx(1.0)


def test_bootstrap_interval_brackets_the_rmse_and_is_seeded():
    rng = np.random.default_rng(0)
    n = 600
    series = [f"s{i // 100}" for i in range(n)]
    d_clean = rng.uniform(0.5, 3.0, n)
    a = _arrays(d_clean + rng.normal(0, 0.1, n), d_clean, series=series)
    lo, hi = bootstrap_rmse(a.raw, a, 500, seed=1)
    assert lo <= recovery_scores(a.raw, a)["rmse"] <= hi
    assert bootstrap_rmse(a.raw, a, 500, seed=1) == [lo, hi]


@settings(max_examples=40, deadline=None)
@given(st.lists(st.one_of(st.floats(0.1, 5.0), st.just(float("nan"))), min_size=1, max_size=40),
       st.integers(0, 39))
def test_hold_last_is_causal_and_only_repeats_past_values(values, cut):
    held = hold_last(values)
    cut = min(cut, len(values))
    changed = list(values[:cut]) + [9.9] * (len(values) - cut)
    np.testing.assert_array_equal(hold_last(changed)[:cut], held[:cut])
    for i, h in enumerate(held):
        assert math.isnan(h) or h in values[:i + 1]


def test_error_sources_split_the_squared_error_by_segment_kind_and_lidar():
    d_clean = np.array([2.0, 1.9, 1.8, 1.7])
    frame = pd.DataFrame({"series_id": "a", "d_meas": [2.0, 2.9, np.nan, 1.7], "c_meas": 1.0,
                          "lidar": [2.0, 1.9, np.nan, np.nan], "speed": 1.0, "label": [0, 1, 1, 0],
                          "kind": [0, 1, 2, 0], "d_clean": d_clean, "d_true": d_clean})
    a = split_arrays(frame, Alignment())
    out = error_sources(a.raw, a)  # errors 0, +1.0 (bias, LiDAR on), +1.1 (blackout held, no LiDAR), 0
    assert out["bias|lidar"] == {"n": 1, "sse": pytest.approx(1.0), "rmse": pytest.approx(1.0)}
    assert out["blackout|no_lidar"]["rmse"] == pytest.approx(1.1)
    assert out["none|lidar"]["n"] == 1 and out["none|no_lidar"]["n"] == 1
    assert out["degradation|lidar"] == {"n": 0, "sse": 0.0, "rmse": None}
    assert sum(v["n"] for v in out.values()) == int(a.scored.sum())


def test_the_interval_resamples_drives_and_draws_together():
    from racf.experiments.offline.scoring import bootstrap_rmse_draws

    count = np.full((6, 5), 100.0)
    same = np.full((6, 5), 4.0)  # every drive and draw: RMSE 0.2
    low, high = bootstrap_rmse_draws(same, count, 200, seed=0)
    assert low == pytest.approx(0.2) and high == pytest.approx(0.2)
    # Drives alike, draws apart: the interval must open (a drives-only bootstrap would not).
    by_draw = np.tile(np.array([1.0, 4.0, 9.0, 16.0, 25.0]), (6, 1))
    low, high = bootstrap_rmse_draws(by_draw, count, 400, seed=0)
    assert low < 0.3 - 0.02 and high > 0.3 + 0.02  # the mean of 0.1 ... 0.5 is 0.3
