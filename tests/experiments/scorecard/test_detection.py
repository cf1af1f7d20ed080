"""The detection rows on hand-made logs whose flags are known."""

import math

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings, strategies as st

from racf.experiments.scorecard.detection import detection_rows, label_steps


def _log(active, flag, score=None, err=None, depth=None):
    n = len(active)
    log = pd.DataFrame({"t": np.arange(n) * 0.02, "attack_active": np.asarray(active, bool),
                        "d_meas": np.ones(n) if depth is None else np.asarray(depth, float),
                        "flag": np.asarray(flag, float), "d_true": np.ones(n),
                        "d_fused": 1.0 + (np.zeros(n) if err is None else np.asarray(err, float))})
    if score is not None:
        log["score"] = np.asarray(score, float)
    return log


def test_a_known_flag_gives_the_expected_tpr_fpr_and_auroc():
    # attacked: 10 clean steps (1 flagged), 10 active (8 flagged, the first two missed), 5 after (ignored)
    attacked = _log([0] * 10 + [1] * 10 + [0] * 5, [0] * 9 + [1] + [0, 0] + [1] * 8 + [1] * 5)
    clean = _log([0] * 20, [0] * 19 + [1])  # 20 clean steps, 1 flagged
    row = detection_rows([attacked, clean])
    assert row["n_positive_steps"] == 10 and row["n_negative_steps"] == 30
    assert row["tpr"] == pytest.approx(0.8) and row["fpr"] == pytest.approx(2 / 30)
    # a binary score: AUROC = (TPR + 1 - FPR) / 2
    assert row["auroc_from"] == "flag" and row["auroc"] == pytest.approx((0.8 + 1 - 2 / 30) / 2)
    assert row["time_to_detect_median_s"] == pytest.approx(0.04)  # two steps after the start
    assert row["n_attacked_episodes"] == 1 and row["detected_share"] == 1.0


def test_the_undetected_error_is_read_at_one_percent_false_alarms_on_the_score():
    rng = np.random.default_rng(0)
    clean = [_log([0] * 100, [0] * 100, score=rng.uniform(0, 1, 100)) for _ in range(10)]  # 1 % above 0.99
    # the attack's score climbs 0.5, 1.5, 2.5, ... while its error grows 0.1 m a step
    attacked = _log([0] * 5 + [1] * 5, [0] * 10, score=[0] * 5 + [0.5, 1.5, 2.5, 3.5, 4.5],
                    err=[0] * 5 + [0.1, 0.2, 0.3, 0.4, 0.5])
    row = detection_rows(clean + [attacked])
    assert row["auroc_from"] == "score" and 0.98 < row["threshold"] < 1.0
    assert row["undetected_error_median_m"] == pytest.approx(0.1)  # only the first active step is below it
    assert row["detected_share"] == 0.0 and row["time_to_detect_median_s"] is None  # the flag never came


def test_steps_without_a_depth_are_not_judged():
    # a blackout: the attack hides the depth for 5 steps, then biases it for 5 (flagged)
    log = _log([0] * 5 + [1] * 10, [0] * 10 + [1] * 5, depth=[1.0] * 5 + [math.nan] * 5 + [1.5] * 5)
    row = detection_rows([log])
    assert row["n_positive_steps"] == 5 and row["tpr"] == 1.0


def test_a_defence_with_no_detector_has_no_detection_rows():
    assert detection_rows([_log([0, 1, 1], [math.nan] * 3)]) is None


@settings(max_examples=50, deadline=None)
@given(st.lists(st.tuples(st.booleans(), st.booleans()), min_size=2, max_size=60))
def test_rates_are_shares_and_labels_never_count_after_the_attack(steps):
    active, flag = zip(*steps)
    log = _log(list(active), list(flag))
    labels = label_steps(log).to_numpy()
    if any(active):
        first = int(np.argmax(active))
        assert np.all(labels[:first] == 0) and np.all(labels[np.asarray(active)] == 1)
        assert np.all(np.isnan(labels[first:][~np.asarray(active)[first:]]))
    row = detection_rows([log])
    for key in ("tpr", "fpr"):
        assert row[key] is None or 0.0 <= row[key] <= 1.0
