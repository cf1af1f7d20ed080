"""The multi-sensor driving dataset: ``racf collect`` and its loader.

Shaped like the paper's QCar 2 benchmark: synchronized 50 Hz series of the perception
pipeline's clean depth distance and confidence, the LiDAR reference and a compact scan,
the vehicle state and pose, and the simulator's ground truth. One series is one clean
closed-loop approach (``experiments.trial``): the car cruises at 1.0, 1.5 or 2.0 m/s along
a stop-sign approach (straight ones for signs 0 and 1, curves of about +-15 deg steering
for signs 2 and 3) or towards a crate on the lane (an obstacle both sensors see), brakes on
the pipeline's own distance, stops and dwells.

Layout of a dataset folder:

- ``series/<series_id>.parquet`` + ``.json``: one finished series (the resume unit);
- ``dataset.parquet``: every series in long format (``series_id``, ``t``, ...), in order;
- ``split.json``: the fixed by-series split (70 / 10 / 20 %), seeded;
- ``dataset_card.md``: what, how made, columns and units, seed, counts;
- ``series.png``: a few series plotted.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from experiments.corruption import corrupt_series, series_seed
from experiments.trial import SCAN_FOV_HALF_BEAMS, TrialSpec
from experiments.trials import SIGNS, SPEEDS_MPS, run_batch

__all__ = ["COLUMNS", "DEFAULT_RUNS", "collection_specs", "collect", "summarize_dataset", "load_dataset",
           "QCarDataset", "SPLIT_SHARES"]

#: Runs per (target, speed): (4 signs + 2 crates) x 3 speeds x 26 = 468 series, ~74k samples
#: (the paper: 67,821 samples in 13 sequences).
DEFAULT_RUNS = 26
OBSTACLES = (0, 1)
SPLIT_SHARES = (0.7, 0.1, 0.2)

#: Dataset columns: name -> (unit, meaning).
COLUMNS: dict[str, tuple[str, str]] = {
    "series_id": ("", "one approach; the split is by series"),
    "t": ("s", "time since the start of the series (50 Hz)"),
    "target": ("", "what the car approaches: sign0-sign3 (stop signs) or obstacle0-obstacle1 (blue crates)"),
    "speed_set": ("m/s", "cruise speed of the series"),
    "d_clean": ("m", "perception output: median depth in the detector's mask (NaN: no detection)"),
    "c_clean": ("1", "its confidence: detection confidence x valid-depth share"),
    "d_true": ("m", "ground truth: depth of the target's centre (sign plate / crate's near face) along the camera axis"),
    "sign_in_view": ("bool", "ground truth: some of the target is visible"),
    "detected": ("bool", "the detector reported the target"),
    "lidar": ("m", "range of the nearest DBSCAN cluster in the camera's view near the detection (NaN: none)"),
    "scan_fov_mm": ("mm", f"LiDAR ranges (uint16), beams -{SCAN_FOV_HALF_BEAMS}..+{SCAN_FOV_HALF_BEAMS} deg "
                            "CCW from forward; 0 = no return"),
    "speed": ("m/s", "measured speed"),
    "steering": ("rad", "measured steering angle, left positive"),
    "yaw_rate": ("rad/s", "IMU yaw rate"),
    "accel": ("m/s^2", "IMU longitudinal acceleration"),
    "x": ("m", "pose in the map frame"),
    "y": ("m", "pose in the map frame"),
    "yaw": ("rad", "heading in the map frame"),
    "dist_to_stop_line": ("m", "ground truth: front bumper to the stop line along the route"),
    "brake": ("bool", "the braking controller's command"),
}

_RENAME = {"c_meas": "c_clean", "state_speed_mps": "speed", "state_steering_rad": "steering",
           "state_yaw_rate_radps": "yaw_rate", "state_accel_mps2": "accel"}


def collection_specs(runs: int = DEFAULT_RUNS, seed: int = 0, signs: tuple[int, ...] = SIGNS,
                     speeds: tuple[float, ...] = SPEEDS_MPS,
                     obstacles: tuple[int, ...] = OBSTACLES) -> list[TrialSpec]:
    """The series to record: every sign and crate at every speed, ``runs`` times, seeds from ``seed``."""
    if runs < 1:
        raise ValueError(f"runs must be >= 1, got {runs}")
    targets = [("sign", i) for i in signs] + [("obstacle", i) for i in obstacles]
    return [TrialSpec("clean", index, speed, seed * 100_000 + k, target=kind)
            for k in range(runs) for speed in speeds for kind, index in targets]


def collect(out_dir: Path, runs: int = DEFAULT_RUNS, seed: int = 0, workers: int = 2, progress: bool = True,
            signs: tuple[int, ...] = SIGNS, speeds: tuple[float, ...] = SPEEDS_MPS,
            obstacles: tuple[int, ...] = OBSTACLES) -> Path:
    """Records (or resumes) the collection and writes the dataset files; returns ``dataset.parquet``."""
    out_dir = Path(out_dir)
    specs = collection_specs(runs, seed, signs, speeds, obstacles)
    run_batch(specs, out_dir / "_runs", workers=workers, progress=progress)
    frames = []
    for spec in specs:
        log = pd.read_parquet(out_dir / "_runs" / "trials" / f"{spec.trial_id}.parquet")
        log = log.drop(columns=["speed"]).rename(columns=_RENAME)  # speed: the measured one
        log["series_id"] = spec.trial_id
        log["target"] = f"{spec.target}{spec.sign}"
        log["speed_set"] = spec.speed
        log["scan_fov_mm"] = [_scan_mm(r) for r in log["scan_fov"]]
        frames.append(log[list(COLUMNS)])
    data = pd.concat(frames, ignore_index=True)
    path = out_dir / "dataset.parquet"
    data.to_parquet(path, index=False)
    ids = [s.trial_id for s in specs]
    split = make_split(ids, seed)
    (out_dir / "split.json").write_text(json.dumps({"seed": seed, "shares": SPLIT_SHARES, **split}, indent=1))
    summary = summarize_dataset(data, split)
    _write_card(out_dir / "dataset_card.md", summary, runs, seed)
    plot_series(data, out_dir / "series.png")
    return path


def _scan_mm(ranges) -> np.ndarray:
    """Compact scan: millimetres as uint16, 0 = no return (the LiDAR reads 0.15-12 m)."""
    r = np.asarray(ranges, float)
    return np.where(np.isfinite(r) & (r > 0), np.round(r * 1000), 0).clip(0, 65535).astype(np.uint16)


def make_split(series_ids: list[str], seed: int) -> dict[str, list[str]]:
    """Fixed by-series split: a seeded permutation cut 70 / 10 / 20 %."""
    ids = sorted(series_ids)
    order = np.random.default_rng(seed).permutation(len(ids))
    n_train = int(round(SPLIT_SHARES[0] * len(ids)))
    n_val = int(round(SPLIT_SHARES[1] * len(ids)))
    picked = [ids[i] for i in order]
    return {"train": sorted(picked[:n_train]), "val": sorted(picked[n_train:n_train + n_val]),
            "test": sorted(picked[n_train + n_val:])}


def summarize_dataset(data: pd.DataFrame, split: dict[str, list[str]] | None = None) -> dict:
    """The collection's summary: counts, speeds, ranges and how well d_clean tracks d_true."""
    per_series = data.groupby("series_id", sort=False).size()
    both = data[np.isfinite(data["d_clean"]) & np.isfinite(data["d_true"]) & data["sign_in_view"]]
    err = both["d_clean"] - both["d_true"]
    finite_true = data.loc[data["sign_in_view"], "d_true"]
    summary = {
        "n_series": int(per_series.size),
        "n_samples": int(len(data)),
        "speeds": sorted(float(v) for v in data["speed_set"].unique()),
        "rmse_clean_vs_true": float(np.sqrt(np.mean(err**2))) if len(err) else None,
        "mae_clean_vs_true": float(np.mean(np.abs(err))) if len(err) else None,
        "n_clean_samples": int(len(err)),
        "samples_per_series": {"min": int(per_series.min()), "median": float(per_series.median()),
                               "max": int(per_series.max())},
        "d_true_in_view_m": [float(finite_true.min()), float(finite_true.max())] if len(finite_true) else None,
        "d_clean_m": [float(data["d_clean"].min()), float(data["d_clean"].max())],
        "measured_speed_mps": [float(data["speed"].min()), float(data["speed"].max())],
        "steering_deg": [float(np.degrees(data["steering"].min())), float(np.degrees(data["steering"].max()))],
        "targets": sorted(str(s) for s in data["target"].unique()),
    }
    if split is not None:
        summary["split"] = {k: len(v) for k, v in split.items()}
    return summary


def _write_card(path: Path, summary: dict, runs: int, seed: int) -> None:
    rows = "\n".join(f"| `{name}` | {unit} | {meaning} |" for name, (unit, meaning) in COLUMNS.items())
    path.write_text(f"""# RACF QCar 2 simulated approach dataset

**What.** Synchronized 50 Hz series from the racf MuJoCo simulation of the Quanser QCar 2 on
its indoor map: the perception pipeline's clean depth distance to a stop sign and its
confidence, the LiDAR reference and a compact scan, the vehicle state and pose, and the
simulator's ground truth. Shaped like the RACF paper's QCar 2 benchmark (67,821 samples,
13 sequences, speeds 1.0 / 1.5 / 2.0 m/s, steering about 0 and +-15 deg). Simulated data,
not recordings of a real car.

**How it was made.** `racf collect --runs {runs} --seed {seed}`: for every target and
cruise speed (1.0, 1.5, 2.0 m/s), {runs} clean closed-loop approaches (seeds
`{seed} * 100000 + run`). The targets are the four stop signs and two blue crates
(0.12 x 0.16 x 0.22 m) standing on lanes, with a virtual stop line 0.25 m before them; the
camera and the LiDAR both see them. The car follows the approach route with Stanley lane
following, a curve speed limit and a PI speed loop. The detector (stop sign, or crate by
colour), the depth distance and the braking controller run as in
`racf trial --setting clean`; each series ends after the car has stopped and dwelt 1 s.
Signs 0 and 1 and the crates have straight final approaches; signs 2 and 3 approach
through curves (steering up to about 16-22 deg). Sensor noise is the simulator's (depth
0.0037 z^2 m, LiDAR 1 %).

**Counts.** {summary['n_series']} series, {summary['n_samples']} samples; samples per series
{summary['samples_per_series']['min']}-{summary['samples_per_series']['max']} (median
{summary['samples_per_series']['median']:.0f}); split {summary.get('split')} (by series, seed {seed}).

**Quality of the pseudo ground truth.** d_clean vs d_true over {summary['n_clean_samples']}
samples with the sign in view and detected: RMSE {summary['rmse_clean_vs_true']:.4f} m,
MAE {summary['mae_clean_vs_true']:.4f} m.

**Columns** (long format, one row per 50 Hz step):

| column | unit | meaning |
|---|---|---|
{rows}

**Corruption.** `experiments.dataset.load_dataset(path).corrupted("weak" | "mid" | "strong")`
adds the protocol's offline corruption (`d_meas`, `c_meas`, `label`, `kind`) with a fixed
seed per series.
""")


def plot_series(data: pd.DataFrame, path: Path, per_sign: int = 1) -> None:
    """Plots one series per target: distances and speed over time."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    picks = [sid for target in sorted(data["target"].unique())
             for sid in data.loc[data["target"] == target, "series_id"].unique()[:per_sign]]
    fig, axes = plt.subplots(len(picks), 1, figsize=(8, 2.2 * len(picks)), squeeze=False, sharex=False)
    for ax, sid in zip(axes[:, 0], picks):
        s = data[data["series_id"] == sid]
        ax.plot(s["t"], s["d_true"].where(s["sign_in_view"]), lw=2.5, alpha=0.5, label="d_true (in view)")
        ax.plot(s["t"], s["d_clean"], ".", ms=3, label="d_clean")
        ax.plot(s["t"], s["lidar"], "x", ms=3, label="LiDAR cluster")
        ax.plot(s["t"], s["speed"], "k-", lw=1, label="speed (m/s)")
        ax.set_title(sid, fontsize=9)
        ax.set_ylabel("m, m/s")
        ax.set_ylim(0, 3.5)
    axes[0, 0].legend(fontsize=7, ncol=4)
    axes[-1, 0].set_xlabel("t (s)")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


@dataclass
class QCarDataset:
    """A collected dataset: the clean frame, the split and corrupted views."""

    frame: pd.DataFrame
    split: dict[str, list[str]]
    path: Path

    def series_ids(self, split: str | None = None) -> list[str]:
        if split is None:
            return list(self.frame["series_id"].unique())
        if split not in self.split:
            raise ValueError(f"split must be one of {sorted(self.split)}, got {split!r}")
        return list(self.split[split])

    def clean(self, split: str | None = None) -> pd.DataFrame:
        """Clean series in long format (all, or one split's)."""
        if split is None:
            return self.frame
        return self.frame[self.frame["series_id"].isin(self.series_ids(split))].reset_index(drop=True)

    def corrupted(self, preset: str, split: str | None = None, base_seed: int = 0) -> pd.DataFrame:
        """Clean series plus the preset's corruption: ``d_meas``, ``c_meas``, ``label`` (0/1), ``kind``.

        Every series has a fixed seed (``series_seed(series_id, preset, base_seed)``), so every
        method sees identical corrupted input.
        """
        frame = self.clean(split).copy()
        parts = []
        for sid, s in frame.groupby("series_id", sort=False):
            c = corrupt_series(s["d_clean"].to_numpy(), s["c_clean"].to_numpy(), preset,
                               seed=series_seed(str(sid), preset, base_seed))
            parts.append(pd.DataFrame({"d_meas": c.depth, "c_meas": c.confidence, "label": c.label,
                                       "kind": c.kind}, index=s.index))
        return frame.join(pd.concat(parts)) if parts else frame


def load_dataset(path: Path) -> QCarDataset:
    """Loads a dataset folder written by ``racf collect``; a clear error if it is not one."""
    path = Path(path)
    data_file, split_file = path / "dataset.parquet", path / "split.json"
    if not data_file.exists() or not split_file.exists():
        raise FileNotFoundError(f"{path} is not a racf dataset folder (need dataset.parquet and split.json; "
                                f"make one with `racf collect --out {path}`)")
    frame = pd.read_parquet(data_file)
    missing = sorted(set(COLUMNS) - set(frame.columns))
    if missing:
        raise ValueError(f"{data_file} lacks columns {missing}; recollect it with this version of racf")
    split = json.loads(split_file.read_text())
    return QCarDataset(frame, {k: split[k] for k in ("train", "val", "test")}, path)

