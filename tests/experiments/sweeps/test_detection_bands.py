"""The detector's recall by distance band, from kept step logs."""

import numpy as np
import pandas as pd
import pytest

from racf.experiments.sweeps.detection_bands import band_labels, recall_rows


def _log(path, d_true, detected, attack_active=True, frame_new=True, in_view=True):
    n = len(d_true)
    pd.DataFrame({"frame_new": np.full(n, frame_new), "control": True, "sign_in_view": np.full(n, in_view),
                  "d_true": d_true, "detected": detected, "attack_active": np.full(n, attack_active)}).to_parquet(path)


def test_recall_is_counted_per_band_over_frames_in_view_that_the_attack_acted_on(tmp_path):
    _log(tmp_path / "a.parquet", [0.5, 0.6, 1.5, 1.6, 3.0, 5.0], [True, False, True, True, False, False])
    _log(tmp_path / "b.parquet", [0.5, 1.5], [True, True], attack_active=False)  # not attacked: left out
    _log(tmp_path / "c.parquet", [1.5, 1.5], [False, False], in_view=False)  # not in view: left out
    frame = pd.DataFrame({"attack": "physical_patch", "attack_params": "", "estimator": "raw",
                          "trial_id": ["a", "b", "c", "missing"]})
    (row,) = recall_rows(frame, tmp_path)
    near, mid, far = (row["bands"][b] for b in band_labels())
    assert (near["recall"], near["n"]) == (0.5, 2) and (mid["recall"], mid["n"]) == (1.0, 2)
    assert (far["recall"], far["n"]) == (0.0, 1)  # 5 m lies beyond every band
    assert mid["recall_ci"][0] < 1.0 == pytest.approx(mid["recall_ci"][1])


def test_no_logs_no_rows(tmp_path):
    frame = pd.DataFrame({"attack": "none", "attack_params": "", "estimator": "raw", "trial_id": ["a"]})
    assert recall_rows(frame, tmp_path) == [] and recall_rows(frame, tmp_path / "absent") == []
