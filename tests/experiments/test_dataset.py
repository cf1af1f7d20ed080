"""The dataset: a small collection checked for counts, columns, units, split, bytes and resume."""

import json
import shutil

import numpy as np
import pandas as pd
import pytest

from experiments.cli import main
from experiments.dataset import COLUMNS, SPLIT_SHARES, collect, collection_specs, load_dataset, make_split


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    out = tmp_path_factory.mktemp("ds")
    collect(out, runs=1, seed=3, workers=2, progress=False)
    return out


def test_counts_columns_units_and_files(small):
    ds = load_dataset(small)
    df = ds.frame
    assert list(df.columns) == list(COLUMNS)
    assert df["series_id"].nunique() == 18 and len(df) > 18 * 100
    assert sorted(df["speed_set"].unique()) == [1.0, 1.5, 2.0]
    assert sorted(df["target"].unique()) == ["obstacle0", "obstacle1", "sign0", "sign1", "sign2", "sign3"]
    for sid, s in df.groupby("series_id"):
        np.testing.assert_allclose(np.diff(s["t"]), 0.02, atol=1e-9)  # 50 Hz, contiguous
        assert s["t"].iloc[0] == 0.0
    # Units: metres, m/s, radians.
    assert df["speed"].max() < 2.3 and df["speed"].min() > -0.1
    assert np.abs(df["steering"]).max() <= np.radians(31)
    assert 0.1 < df["d_clean"].min() and df["d_clean"].max() < 4.0
    assert ((df["c_clean"] >= 0) & (df["c_clean"] <= 1)).all()
    scans = np.stack(df["scan_fov_mm"].to_numpy())
    assert scans.shape[1] == 81 and scans.dtype == np.uint16
    for name in ("dataset_card.md", "series.png", "split.json"):
        assert (small / name).stat().st_size > 500


def test_d_clean_tracks_d_true(small):
    df = load_dataset(small).frame
    both = df[df["detected"] & df["sign_in_view"]]
    assert len(both) > 300
    assert np.sqrt(np.mean((both["d_clean"] - both["d_true"]) ** 2)) < 0.05


def test_split_is_by_series_disjoint_and_70_10_20():
    ids = [s.trial_id for s in collection_specs(runs=10, seed=1)]
    assert len(ids) == 180
    split = make_split(ids, seed=1)
    sets = [set(split[k]) for k in ("train", "val", "test")]
    assert set.union(*sets) == set(ids) and sum(map(len, sets)) == len(ids)
    assert [len(s) for s in sets] == [round(SPLIT_SHARES[0] * 180), round(SPLIT_SHARES[1] * 180), 180 - 126 - 18]
    assert make_split(ids, seed=1) == split and make_split(ids, seed=2) != split


def test_loader_gives_splits_and_labelled_corruption(small):
    ds = load_dataset(small)
    train = ds.clean("train")
    assert set(train["series_id"]) == set(ds.split["train"])
    bad = ds.corrupted("strong")
    assert {"d_meas", "c_meas", "label", "kind"} <= set(bad.columns) and len(bad) == len(ds.frame)
    assert 0.2 < bad["label"].mean() < 0.5
    again = ds.corrupted("strong")
    pd.testing.assert_frame_equal(bad, again)
    outside = bad["label"] == 0
    pd.testing.assert_series_equal(bad.loc[outside, "d_meas"], bad.loc[outside, "d_clean"], check_names=False)
    with pytest.raises(ValueError, match="split must be one of"):
        ds.clean("holdout")


def test_same_seed_same_bytes_and_resume_redoes_nothing(tmp_path, small, monkeypatch):
    import experiments.trials as trials_module

    a = tmp_path / "a"
    # Copy the finished runs of the module's collection, then "resume": nothing may be re-run.
    shutil.copytree(small / "_runs", a / "_runs")
    monkeypatch.setattr(trials_module, "_run_and_save", lambda *args: pytest.fail("re-ran a finished series"))
    collect(a, runs=1, seed=3, workers=1, progress=False)
    assert (a / "dataset.parquet").read_bytes() == (small / "dataset.parquet").read_bytes()
    assert (a / "split.json").read_bytes() == (small / "split.json").read_bytes()


def test_fresh_recording_gives_identical_bytes(tmp_path):
    for name in ("x", "y"):
        collect(tmp_path / name, runs=1, seed=5, workers=1, progress=False, signs=(2,), speeds=(1.5,),
                obstacles=(1,))
    assert (tmp_path / "x" / "dataset.parquet").read_bytes() == (tmp_path / "y" / "dataset.parquet").read_bytes()


def test_cli_summary_json_and_missing_dataset_error(small, capsys, tmp_path):
    assert main(["collect", "--out", str(small), "--runs", "1", "--seed", "3", "--summary"]) == 0
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert {"n_series", "n_samples", "speeds", "rmse_clean_vs_true"} <= set(summary)
    assert summary["n_series"] == 18
    with pytest.raises(FileNotFoundError, match="racf collect"):
        load_dataset(tmp_path / "nothing")
