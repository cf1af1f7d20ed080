"""Training end to end on synthetic approach series (no simulator): alignment, head, gate, scores."""

import numpy as np
import pandas as pd
import pytest

from racf.odca import LastValuePrior
from racf.odca.synthetic import approach_curve
from racf.odca.train import N_SIGMA_GRID, train_odca

#: Share of samples inside attack segments, and the bias magnitude range (m), per preset.
PRESETS = {"weak": (0.10, (0.10, 0.25)), "mid": (0.20, (0.25, 0.50)), "strong": (0.35, (0.50, 1.00))}


class SyntheticDataset:
    """What ``train_odca`` reads of a dataset: clean series per split, and corrupted copies per preset.

    Clean series are approach curves with a LiDAR that sits 0.1 m behind the depth camera
    and reads 3 % long (alignment alpha = 0.97, beta = -0.1). A preset corrupts each series
    with its own seed: segments of 0.4-1.2 s covering the preset's share, each a bias of
    random sign, a blackout (NaN, confidence 0) or a degradation (confidence x 0.3 plus 0.1 m
    noise); ``label`` is 1 inside a segment.
    """

    def __init__(self, n_series: int = 30, seed: int = 0) -> None:
        rng = np.random.default_rng(seed)
        frames = []
        for i in range(n_series):
            d = approach_curve(rng, 150)
            d = np.where(np.isfinite(d), d, np.nan)
            lidar = (d + 0.1) / 0.97 + rng.normal(0, 0.01, d.size)  # the depth camera sits ahead of the LiDAR
            speed = np.clip(-np.gradient(pd.Series(d).ffill().bfill().to_numpy(), 0.02), 0, 3)
            frames.append(pd.DataFrame({"series_id": f"s{i}", "t": np.arange(d.size) * 0.02, "d_clean": d,
                                        "c_clean": np.where(np.isfinite(d), 0.9, 0.0), "lidar": lidar,
                                        "speed": speed}))
        self.frame = pd.concat(frames, ignore_index=True)
        ids = [f"s{i}" for i in range(n_series)]
        self.split = {"train": ids[:20], "val": ids[20:24], "test": ids[24:]}
        self.seed = seed

    def clean(self, split: str) -> pd.DataFrame:
        return self.frame[self.frame["series_id"].isin(self.split[split])].reset_index(drop=True)

    def corrupted(self, preset: str, split: str) -> pd.DataFrame:
        share, bias_m = PRESETS[preset]
        parts = []
        for sid, s in self.clean(split).groupby("series_id", sort=False):
            rng = np.random.default_rng([self.seed, int(sid[1:]), list(PRESETS).index(preset)])
            d, c = s["d_clean"].to_numpy(float).copy(), s["c_clean"].to_numpy(float).copy()
            label = np.zeros(d.size, np.int8)
            while label.sum() < share * d.size:
                length = int(rng.integers(20, 61))
                start = int(rng.integers(0, d.size - length + 1))
                seg = slice(start, start + length)
                if label[max(0, start - 1):start + length + 1].any():
                    continue
                label[seg] = 1
                kind = rng.integers(3)
                if kind == 0:
                    d[seg] += rng.choice((-1.0, 1.0)) * rng.uniform(*bias_m)
                elif kind == 1:
                    d[seg], c[seg] = np.nan, 0.0
                else:
                    d[seg] += rng.normal(0.0, 0.1, length)
                    c[seg] *= 0.3
            parts.append(s.assign(d_meas=d, c_meas=c, label=label))
        return pd.concat(parts, ignore_index=True)


@pytest.mark.slow  # 3.4 s of training: the default run keeps under two minutes on 2 cores
def test_training_runs_end_to_end_and_repairs_strong_corruption():
    _, report = train_odca(SyntheticDataset(), LastValuePrior(), epochs=150, progress=False)
    assert report["head_parameters"] == 917
    assert abs(report["alignment"]["alpha"] - 0.97) < 0.02 and abs(report["alignment"]["beta"] + 0.1) < 0.02
    gate = report["gate"]
    assert 0 < gate["tau_m"] < 0.5 and report["kinematics"]["n_sigma"] in N_SIGMA_GRID
    strong = report["test"]["strong"]
    assert strong["mae"] < strong["mae_raw"]
    assert np.isfinite(list(report["final_losses"].values())).all()
