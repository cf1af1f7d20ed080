"""The dataset of drives: a small collection checked for counts, columns, units, splits, bytes and resume."""

import json
import shutil

import numpy as np
import pandas as pd
import pytest

from racf.errors import UserError
from racf.experiments.cli import main
from racf.experiments.data.dataset import (COLUMNS, SPLIT_SHARES, collect, collection_specs, load_dataset, make_split,
                                 make_target_split)

#: Short drives keep the test collection small (the default drives last 20-60 s).
SHORT = (10.0, 20.0)


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    out = tmp_path_factory.mktemp("ds")
    collect(out, drives=3, seed=3, workers=1, progress=False, duration_s=SHORT)  # in this process: no spawn
    return out


@pytest.mark.slow  # the small dataset takes 15 s to collect; CI's slow stage runs it
def test_counts_columns_units_and_files(small):
    ds = load_dataset(small)
    df = ds.frame
    assert list(df.columns) == list(COLUMNS)
    assert df["series_id"].nunique() == 3 and len(df) > 3 * 300
    assert sorted(df["speed_set"].unique()) == [1.0, 1.5, 2.0]
    for sid, s in df.groupby("series_id"):
        np.testing.assert_allclose(np.diff(s["t"]), 0.02, atol=1e-9)  # 50 Hz, contiguous
        assert s["t"].iloc[0] == 0.0
        assert s["slot"].max() >= 1 and (np.diff(s["slot"]) >= 0).all()  # >= 2 targets, met in order
    # Units: metres, m/s, radians; the LiDAR scans at 10 Hz.
    assert df["speed"].max() < 2.5 and df["speed"].min() > -0.1
    assert np.abs(df["steering"]).max() <= np.radians(31)
    assert 0.1 < df["d_clean"].min() and df["d_clean"].max() < 4.0
    assert ((df["c_clean"] >= 0) & (df["c_clean"] <= 1)).all()
    assert df["scan_new"].mean() == pytest.approx(0.2, abs=0.01)
    scans = np.stack(df["scan_fov_mm"].to_numpy())
    assert scans.shape[1] == 81 and scans.dtype == np.uint16
    for name in ("dataset_card.md", "series.png"):
        assert (small / name).stat().st_size > 500
    split = json.loads((small / "split.json").read_text())
    assert {"by_series", "leave_target_out"} <= set(split)


@pytest.mark.slow  # the small dataset takes 15 s to collect; CI's slow stage runs it
def test_start_poses_differ_between_series(small):
    starts = load_dataset(small).frame.groupby("series_id")[["x", "y", "yaw"]].first().to_numpy()
    gaps = np.abs(starts[:, None] - starts[None])
    assert (gaps.max(axis=2) + np.eye(len(starts)) > 0.01).all()


@pytest.mark.slow  # the small dataset takes 15 s to collect; CI's slow stage runs it
def test_d_clean_and_the_lidar_reference_track_d_true(small):
    df = load_dataset(small).frame
    both = df[df["detected"] & df["sign_in_view"]]
    assert len(both) > 200
    # The typical error, and few detections of something else (a red lamp on the sign's bearing
    # can pass the map check for a frame, and one such frame alone lifts the RMSE to 0.09 m).
    err = (both["d_clean"] - both["d_true"]).abs()
    assert err.mean() < 0.02 and err.quantile(0.95) < 0.05
    assert (err > 0.1).mean() < 0.01
    ref = df[np.isfinite(df["lidar"])]
    assert len(ref) > 200
    assert np.sqrt(np.mean((ref["lidar"] - ref["d_true"]) ** 2)) < 0.05


def test_by_series_split_is_disjoint_and_70_10_20():
    ids = [f"s{k}" for k in range(180)]
    split = make_split(ids, seed=1)
    sets = [set(split[k]) for k in ("train", "val", "test")]
    assert set.union(*sets) == set(ids) and sum(map(len, sets)) == len(ids)
    assert [len(s) for s in sets] == [round(SPLIT_SHARES[0] * 180), round(SPLIT_SHARES[1] * 180), 180 - 126 - 18]
    assert make_split(ids, seed=1) == split and make_split(ids, seed=2) != split


def test_leave_target_out_puts_every_series_meeting_the_target_in_test():
    frame = pd.DataFrame({"series_id": ["a"] * 3 + ["b"] * 2 + ["c"] * 2 + ["d"] * 2,
                          "target": ["sign0", "sign1", "sign1", "sign2", "sign1", "sign2", "sign3", "sign0", "sign3"]})
    split = make_target_split(frame, "sign1", seed=0)
    assert split["test"] == ["a", "b"] and sorted(split["train"] + split["val"]) == ["c", "d"]
    with pytest.raises(ValueError, match="held_out must be a target"):
        make_target_split(frame, "sign9", seed=0)


@pytest.mark.slow  # the small dataset takes 15 s to collect; CI's slow stage runs it
def test_loader_gives_both_splits_and_labelled_corruption(small):
    ds = load_dataset(small)
    assert ds.scheme == "by_series" and set(ds.clean("train")["series_id"]) == set(ds.split["train"])
    lto = load_dataset(small, split="leave_target_out")
    held = lto.splits["leave_target_out"]["held_out"]
    test = lto.clean("test")
    assert set(test["series_id"]) == set(lto.frame.loc[lto.frame["target"] == held, "series_id"])
    assert held not in set(lto.clean("train")["target"])
    bad = ds.corrupted("strong")
    assert {"d_meas", "c_meas", "label", "kind"} <= set(bad.columns) and len(bad) == len(ds.frame)
    assert 0.2 < bad["label"].mean() < 0.5
    pd.testing.assert_frame_equal(bad, ds.corrupted("strong"))
    # A draw depends on what a series is (its drive's seed), not on its id (which hashes the code).
    renamed = ds.frame.assign(series_id=ds.frame["series_id"] + "-renamed")
    again = type(ds)(renamed, {k: [i + "-renamed" for i in v] for k, v in ds.split.items()}, ds.path).corrupted("strong")
    np.testing.assert_array_equal(again["d_meas"].to_numpy(), bad["d_meas"].to_numpy())
    assert not np.array_equal(ds.corrupted("strong", draw=1)["label"].to_numpy(), bad["label"].to_numpy())
    assert set(bad["drive_seed"]) == {300000, 300001, 300002}
    outside = bad["label"] == 0
    pd.testing.assert_series_equal(bad.loc[outside, "d_meas"], bad.loc[outside, "d_clean"], check_names=False)
    with pytest.raises(ValueError, match="split must be one of"):
        ds.clean("holdout")
    with pytest.raises(ValueError, match="split must be one of"):
        load_dataset(small, split="random")


@pytest.mark.slow  # the small dataset takes 15 s to collect; CI's slow stage runs it
def test_same_seed_same_bytes_and_resume_redoes_nothing(tmp_path, small, monkeypatch):
    import racf.experiments.sweeps.executors as executors_module

    a = tmp_path / "a"
    # Copy the finished runs of the module's collection, then "resume": nothing may be re-run.
    shutil.copytree(small / "_runs", a / "_runs")
    monkeypatch.setattr(executors_module, "run_episode", lambda *a, **k: pytest.fail("re-ran a finished series"))
    collect(a, drives=3, seed=3, workers=1, progress=False, duration_s=SHORT)
    assert (a / "dataset.parquet").read_bytes() == (small / "dataset.parquet").read_bytes()
    assert (a / "split.json").read_bytes() == (small / "split.json").read_bytes()


@pytest.mark.slow
def test_fresh_recording_gives_identical_bytes(tmp_path, small):
    collect(tmp_path / "x", drives=3, seed=3, workers=2, progress=False, duration_s=SHORT)
    assert (tmp_path / "x" / "dataset.parquet").read_bytes() == (small / "dataset.parquet").read_bytes()


def test_specs_cycle_speeds_and_differ_by_seed():
    specs = collection_specs(drives=6, seed=1)
    assert [s.speed for s in specs] == [1.0, 1.5, 2.0] * 2
    assert len({s.drive for s in specs}) == 6
    with pytest.raises(ValueError, match="drives must be >= 1"):
        collection_specs(drives=0)


@pytest.mark.slow  # the small dataset takes 15 s to collect; CI's slow stage runs it
def test_cli_summary_json_and_missing_dataset_error(small, capsys, tmp_path, monkeypatch):
    import racf.experiments.data.dataset as dataset_module

    # The CLI resumes the module's collection (its drives are the short ones).
    monkeypatch.setattr(dataset_module, "DRIVE_S", SHORT)
    real = dataset_module.collect
    monkeypatch.setattr(dataset_module, "collect", lambda out, **kw: real(out, **kw, duration_s=SHORT))
    assert main(["collect", "--out", str(small), "--drives", "3", "--seed", "3", "--summary"]) == 0
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert {"n_series", "n_samples", "targets_per_series", "distinct_start_poses", "standstill_share",
            "lidar_reference", "split"} <= set(summary)
    assert summary["n_series"] == 3 and summary["distinct_start_poses"] == 3
    assert set(summary["split"]) == {"by_series", "leave_target_out"}
    with pytest.raises(UserError, match="racf collect"):
        load_dataset(tmp_path / "nothing")
