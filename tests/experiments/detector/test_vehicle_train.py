"""The vehicle segmenter: its views, its training and the shipped checkpoint on held-out views."""

import json

import numpy as np
import pytest

from racf.controllers.vehicle_detector import LearnedVehicleDetector
from racf.experiments.detector.vehicle_train import VehicleTrainConfig, heldout_report, render_views, train_vehicle_segmenter


@pytest.fixture(scope="module")
def views():
    return render_views(60, seed=7)


def test_a_view_s_mask_is_the_car_and_a_view_without_one_has_none(views):
    has = np.isfinite(views["range_m"])
    assert has.any() and (~has).any()
    assert not views["mask"][~has].any()
    # A car near the camera covers more of the frame than one far off.
    seen = has & (views["mask"].sum(axis=(1, 2)) > 20)
    near, far = views["range_m"][seen] < 1.0, views["range_m"][seen] > 2.0
    areas = views["mask"][seen].sum(axis=(1, 2))
    assert areas[near].mean() > 3 * areas[far].mean()


def test_the_shipped_segmenter_finds_cars_it_never_saw_and_nothing_where_none_stands(views):
    report = heldout_report(LearnedVehicleDetector(), views)
    found = sum(r["found"] for r in report["recall"].values())
    total = sum(r["n"] for r in report["recall"].values())
    assert total >= 10 and found / total >= 0.9
    assert report["false_positive"]["frames"] <= 1


@pytest.mark.slow  # 2.6 s of training: the default run keeps under two minutes on 2 cores
def test_training_writes_a_checkpoint_the_detector_loads(tmp_path):
    config = VehicleTrainConfig(n_train=16, n_heldout=4, epochs=1, batch=8)
    _, report = train_vehicle_segmenter(config, tmp_path / "ckpt", progress=False)
    json.dumps(report, allow_nan=False)
    assert report["config"]["n_train"] == 16 and len(report["epoch_loss"]) == 1
    detector = LearnedVehicleDetector(checkpoint=tmp_path / "ckpt")
    assert isinstance(detector.candidates(np.zeros((240, 320, 3), np.uint8)), list)
    with pytest.raises(ValueError, match="n_train"):
        VehicleTrainConfig(n_train=0)
