"""Training end to end on synthetic approach series (no simulator): alignment, head, gate, scores."""

import numpy as np
import pandas as pd

from experiments.data.dataset import QCarDataset
from odca import LastValuePrior
from odca.synthetic import approach_curve
from odca.train import train_odca


def _fake_dataset(n_series=30, seed=0) -> QCarDataset:
    rng = np.random.default_rng(seed)
    frames = []
    for i in range(n_series):
        d = approach_curve(rng, 150)
        d = np.where(np.isfinite(d), d, np.nan)
        lidar = (d + 0.1) / 0.97 + rng.normal(0, 0.01, d.size)  # the depth camera sits ahead of the LiDAR
        speed = np.clip(-np.gradient(pd.Series(d).ffill().bfill().to_numpy(), 0.02), 0, 3)
        frames.append(pd.DataFrame({"series_id": f"s{i}", "t": np.arange(d.size) * 0.02, "d_clean": d,
                                    "c_clean": np.where(np.isfinite(d), 0.9, 0.0), "lidar": lidar, "speed": speed}))
    frame = pd.concat(frames, ignore_index=True)
    ids = [f"s{i}" for i in range(n_series)]
    return QCarDataset(frame, {"train": ids[:20], "val": ids[20:24], "test": ids[24:]}, path=None)


def test_training_runs_end_to_end_and_repairs_strong_corruption():
    model, report = train_odca(_fake_dataset(), LastValuePrior(), epochs=150, progress=False)
    assert report["head_parameters"] == 917
    assert abs(report["alignment"]["alpha"] - 0.97) < 0.02 and abs(report["alignment"]["beta"] + 0.1) < 0.02
    gate = report["gate"]
    assert 0 <= gate["tau_low"] < gate["tau_high"]
    strong = report["test"]["strong"]
    assert strong["mae"] < strong["mae_raw"]
    assert np.isfinite(list(report["final_losses"].values())).all()
