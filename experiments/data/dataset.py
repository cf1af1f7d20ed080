"""The multi-sensor driving dataset: ``racf collect`` and its loader.

Shaped like the paper's QCar 2 benchmark: synchronized 50 Hz series of the perception
pipeline's clean depth distance and confidence, the LiDAR target reference and a compact
scan, the vehicle state and pose, and the simulator's ground truth. One series is one
continuous clean closed-loop drive (``racf.experiments.episode`` with ``target="drive"``): a random
road-graph route of 20-60 s that meets two or more targets; the car stops at every stop
sign, dwells and drives on, and a crate on the lane ends the drive. The seed draws the
start node, run-up, lateral offset, heading error and cruise speed
(``racf.sim.world.drives.draw_drive``); the nominal speeds 1.0 / 1.5 / 2.0 m/s take turns.

Layout of a dataset folder:

- ``_runs/trials/<series_id>.parquet`` + ``.json``: one finished drive (the resume unit);
- ``dataset.parquet``: every series in long format (``series_id``, ``t``, ...), in order;
- ``split.json``: both splits: by series (70 / 10 / 20 %, seeded) and leave-one-target-out;
- ``dataset_card.md``: what, how made, columns and units, seed, counts;
- ``series.png``: a few series plotted.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd

from racf.errors import UserError
from racf.experiments.data.card import plot_series, write_card
from racf.experiments.data.corruption import corrupt_series, draw_seed
from racf.experiments.episode import DRIVE_S, TrialSpec
from racf.experiments.episode.record import STEP_LOG
from racf.experiments.episode.runner import SCAN_FOV_HALF_BEAMS
from racf.experiments.sweeps.batches import SPEEDS_MPS, TRIALS_LOGS, run_batch
from racf.provenance import atomic_write

__all__ = ["COLUMNS", "DEFAULT_DRIVES", "SPLITS", "collection_specs", "collect", "summarize_dataset",
           "reference_quality", "load_dataset", "QCarDataset", "SPLIT_SHARES", "make_split",
           "make_target_split"]

#: Drives in the default collection: 36 x ~43 s of 50 Hz samples, > 67,821 (the paper's count).
DEFAULT_DRIVES = 36
SPLIT_SHARES = (0.7, 0.1, 0.2)
#: The two split schemes ``load_dataset`` offers.
SPLITS = ("by_series", "leave_target_out")
#: What made a dataset (drives, seed, sensor profile, sign geometry), beside it.
COLLECTION_FILE = "collection.json"
#: A sample counts as moving above this speed (the protocol's standstill bound), m/s.
MOVING_MPS = 0.05

#: The dataset's own columns: name -> (unit, meaning).
_OWN_COLUMNS: dict[str, tuple[str, str]] = {
    "series_id": ("", "one drive; the splits are by series"),
    "drive_seed": ("", "the drive's seed: what the drive is (its corruption draws derive from it)"),
    "speed_set": ("m/s", "nominal cruise speed of the series (1.0, 1.5 or 2.0; the drive's own is within +-10 %)"),
    "d_clean": ("m", "perception output: median depth in the detector's mask (NaN: no detection)"),
    "c_clean": ("1", "its confidence: detection confidence x valid-depth share"),
    "scan_fov_mm": ("mm", f"LiDAR ranges (uint16), beams -{SCAN_FOV_HALF_BEAMS}..+{SCAN_FOV_HALF_BEAMS} deg "
                            "CCW from forward; 0 = no return"),
}
#: Dataset columns copied from the step log (racf.experiments.episode.record): name -> its log column.
_FROM_LOG = {"t": "t", "slot": "slot", "target": "target", "d_true": "d_true", "sign_in_view": "sign_in_view",
             "detected": "detected", "bearing": "bearing", "lidar": "lidar", "d_size": "d_size", "size_std": "size_std",
             "scan_new": "scan_new",
             "speed": "state_speed_mps", "steering": "state_steering_rad", "yaw_rate": "state_yaw_rate_radps",
             "accel": "state_accel_mps2", "x": "x", "y": "y", "yaw": "yaw", "x_est": "x_est", "y_est": "y_est",
             "yaw_est": "yaw_est", "fix_x": "fix_x", "fix_y": "fix_y", "fix_yaw": "fix_yaw",
             "dist_to_stop_line": "dist_to_stop_line", "brake": "brake"}
_ORDER = ("series_id", "drive_seed", "t", "slot", "target", "speed_set", "d_clean", "c_clean", "d_true", "sign_in_view",
          "detected", "bearing", "lidar", "d_size", "size_std", "scan_new", "scan_fov_mm", "speed", "steering", "yaw_rate", "accel", "x", "y",
          "yaw", "x_est", "y_est", "yaw_est", "fix_x", "fix_y", "fix_yaw", "dist_to_stop_line", "brake")
#: Dataset columns: name -> (unit, meaning); those from the step log take the log's declaration.
COLUMNS: dict[str, tuple[str, str]] = {
    name: _OWN_COLUMNS[name] if name in _OWN_COLUMNS else (STEP_LOG[_FROM_LOG[name]].unit,
                                                           STEP_LOG[_FROM_LOG[name]].meaning)
    for name in _ORDER}

_RENAME = {"c_meas": "c_clean", **{log: name for name, log in _FROM_LOG.items() if log != name}}


def collection_specs(drives: int = DEFAULT_DRIVES, seed: int = 0, speeds: tuple[float, ...] = SPEEDS_MPS,
                     duration_s: tuple[float, float] = DRIVE_S, sensor_profile: str = "qcar2",
                     sign_geometry: str = "plate") -> list[TrialSpec]:
    """The drives to record: ``drives`` of them, nominal speeds in turn, seeds ``seed * 100000 + k``,
    on ``sensor_profile``'s sensors with ``sign_geometry``'s stop signs."""
    if drives < 1:
        raise ValueError(f"drives must be >= 1, got {drives}")
    return [TrialSpec("clean", 0, speeds[k % len(speeds)], seed * 100_000 + k, target="drive", drive_s=duration_s,
                      sensor_profile=sensor_profile, sign_geometry=sign_geometry)
            for k in range(drives)]


def collect(out_dir: Path, drives: int = DEFAULT_DRIVES, seed: int = 0, workers: int = 2, progress: bool = True,
            speeds: tuple[float, ...] = SPEEDS_MPS, duration_s: tuple[float, float] = DRIVE_S, backend: str = "local",
            address: str | None = None, sensor_profile: str = "qcar2", sign_geometry: str = "plate") -> Path:
    """Records (or resumes) the collection on ``backend`` and writes the dataset files; returns ``dataset.parquet``.

    The drives run on the one batch path (``racf.experiments.sweeps``); their per-step logs stay in
    ``<out_dir>/_runs/trials/``, so an interrupted collection resumes where it stopped.
    """
    out_dir = Path(out_dir)
    specs = collection_specs(drives, seed, speeds, duration_s, sensor_profile, sign_geometry)
    runs = out_dir / "_runs"
    run_batch(specs, runs, workers=workers, progress=progress, backend=backend, address=address, desc="drives")
    frames = []
    for spec in specs:
        log = pd.read_parquet(runs / TRIALS_LOGS / f"{spec.trial_id}.parquet")
        log = log.drop(columns=["speed"]).rename(columns=_RENAME)  # speed: the measured one
        log["series_id"] = spec.trial_id
        log["drive_seed"] = spec.seed
        log["speed_set"] = spec.speed
        log["scan_fov_mm"] = [_scan_mm(r) for r in log["scan_fov"]]
        frames.append(log[list(COLUMNS)])
    data = pd.concat(frames, ignore_index=True)
    path = atomic_write(out_dir / "dataset.parquet", data)
    splits = make_splits(data, seed)
    atomic_write(out_dir / "split.json", json.dumps({"seed": seed, "shares": SPLIT_SHARES, **splits}, indent=1))
    made = {"drives": drives, "seed": seed, "sensor_profile": sensor_profile, "sign_geometry": sign_geometry,
            "detector": specs[0].detector}
    atomic_write(out_dir / COLLECTION_FILE, json.dumps(made, indent=1))
    summary = summarize_dataset(data, splits)
    write_card(out_dir / "dataset_card.md", summary, COLUMNS, **made)
    plot_series(data, out_dir / "series.png")
    return path


def _scan_mm(ranges) -> np.ndarray:
    """Compact scan: millimetres as uint16, 0 = no return (the LiDAR reads 0.15-12 m)."""
    r = np.asarray(ranges, float)
    return np.where(np.isfinite(r) & (r > 0), np.round(r * 1000), 0).clip(0, 65535).astype(np.uint16)


def make_split(series_ids: list[str], seed: int, shares: tuple[float, float, float] = SPLIT_SHARES
               ) -> dict[str, list[str]]:
    """Fixed by-series split: a seeded permutation cut 70 / 10 / 20 %."""
    ids = sorted(series_ids)
    order = np.random.default_rng(seed).permutation(len(ids))
    n_train = int(round(shares[0] * len(ids)))
    n_val = int(round(shares[1] * len(ids)))
    picked = [ids[i] for i in order]
    return {"train": sorted(picked[:n_train]), "val": sorted(picked[n_train:n_train + n_val]),
            "test": sorted(picked[n_train + n_val:])}


def make_target_split(data: pd.DataFrame, held_out: str, seed: int) -> dict:
    """Leave-one-target-out: every series that meets ``held_out`` is test; the rest is cut 7:1 into train and val."""
    met = data.groupby("series_id", sort=False)["target"].agg(lambda t: held_out in set(t))
    if held_out not in set(data["target"]):
        raise ValueError(f"held_out must be a target of the dataset, one of {sorted(set(data['target']))}; "
                         f"got {held_out!r}")
    rest = make_split([str(i) for i in met.index[~met]], seed, (0.875, 0.125, 0.0))
    return {"held_out": held_out, "train": rest["train"], "val": rest["val"],
            "test": sorted(str(i) for i in met.index[met])}


def default_held_out(data: pd.DataFrame) -> str:
    """The stop sign met by the share of series nearest 25 % (a test split near the by-series one's size)."""
    share = {t: data.loc[data["target"] == t, "series_id"].nunique() / data["series_id"].nunique()
             for t in sorted(set(data["target"])) if t.startswith("sign")}
    return min(share, key=lambda t: (abs(share[t] - 0.25), t))


def make_splits(data: pd.DataFrame, seed: int, held_out: str | None = None) -> dict[str, dict]:
    """Both split schemes (``SPLITS``) of a collected frame."""
    ids = list(dict.fromkeys(data["series_id"]))
    return {"by_series": make_split(ids, seed),
            "leave_target_out": make_target_split(data, held_out or default_held_out(data), seed)}


def reference_quality(frame: pd.DataFrame, outlier_m: float = 0.15, within_m: float = 3.0) -> dict:
    """How well the LiDAR reference tracks the target (the issue's three checks), on the given series.

    ``rmse_vs_true``: |l - d_true| over the steps where the tracker reports a range;
    ``coverage``: share of the steps with the target in view within ``within_m`` that have
    one; ``outlier_share``: share of reported values more than ``outlier_m`` off (another
    object). Also the same RMSE over moving steps only.
    """
    reported = frame[np.isfinite(frame["lidar"]) & np.isfinite(frame["d_true"])]
    err = (reported["lidar"] - reported["d_true"]).to_numpy()
    moving = (reported["speed"] > MOVING_MPS).to_numpy()
    near = frame[frame["sign_in_view"] & (frame["d_true"] <= within_m)]
    return {
        "n_reported": int(len(err)),
        "rmse_vs_true": _rmse(err),
        "rmse_vs_true_moving": _rmse(err[moving]),
        "coverage": float(np.isfinite(near["lidar"]).mean()) if len(near) else None,
        "n_in_view_within_3m": int(len(near)),
        "outlier_share": float(np.mean(np.abs(err) > outlier_m)) if len(err) else None,
    }


def localisation_error(frame: pd.DataFrame) -> dict:
    """The car's pose estimate against the truth over every step, and the raw fix's on the steps a
    new fix arrived (the drift bounds what the filter can do): position error (m) and heading
    error (deg) as RMSE, p95 and max."""
    fix_cols = ["fix_x", "fix_y", "fix_yaw"]
    changed = frame.groupby("series_id", sort=False)[fix_cols].diff().fillna(1.0).ne(0.0).any(axis=1)
    out: dict = {"n": int(len(frame)), "n_fixes": int(changed.sum())}
    for name, (x, y, yaw), rows in (("filter", ("x_est", "y_est", "yaw_est"), frame),
                                    ("fix", tuple(fix_cols), frame[changed])):
        pos = np.hypot(rows[x] - rows["x"], rows[y] - rows["y"]).to_numpy()
        head = np.degrees(np.abs(np.angle(np.exp(1j * (rows[yaw] - rows["yaw"]).to_numpy()))))
        out[name] = {f"{what}_{stat}": value for what, err in (("position_m", pos), ("heading_deg", head))
                     for stat, value in (("rmse", _rmse(err)), ("p95", float(np.percentile(err, 95))),
                                         ("max", float(err.max())))}
    return out


def _rmse(err: np.ndarray) -> float | None:
    return float(np.sqrt(np.mean(err**2))) if len(err) else None


def summarize_dataset(data: pd.DataFrame, splits: dict[str, dict] | None = None) -> dict:
    """The collection's summary: counts, drives, speeds, ranges, d_clean and LiDAR quality (strict JSON)."""
    per_series = data.groupby("series_id", sort=False)
    sizes = per_series.size()
    both = data[np.isfinite(data["d_clean"]) & np.isfinite(data["d_true"]) & data["sign_in_view"]]
    err = (both["d_clean"] - both["d_true"]).to_numpy()
    finite_true = data.loc[data["sign_in_view"], "d_true"]
    targets = per_series["slot"].max() + 1
    starts = per_series[["x", "y", "yaw"]].first().round(3)
    summary = {
        "n_series": int(sizes.size),
        "n_samples": int(len(data)),
        "n_moving_samples": int((data["speed"] > MOVING_MPS).sum()),
        "standstill_share": float((data["speed"] <= MOVING_MPS).mean()),
        "speeds": sorted(float(v) for v in data["speed_set"].unique()),
        "series_duration_s": {"min": float(sizes.min() / 50), "median": float(sizes.median() / 50),
                              "max": float(sizes.max() / 50)},
        "samples_per_series": {"min": int(sizes.min()), "median": float(sizes.median()), "max": int(sizes.max())},
        "targets_per_series": {"min": int(targets.min()), "median": float(targets.median()),
                               "max": int(targets.max())},
        "series_per_target": {t: int(n) for t, n in data.groupby("target")["series_id"].nunique().items()},
        "distinct_start_poses": int(len(starts.drop_duplicates())),
        "rmse_clean_vs_true": _rmse(err),
        "mae_clean_vs_true": float(np.mean(np.abs(err))) if len(err) else None,
        "n_clean_samples": int(len(err)),
        "d_true_in_view_m": [float(finite_true.min()), float(finite_true.max())] if len(finite_true) else None,
        "measured_speed_mps": [float(data["speed"].min()), float(data["speed"].max())],
        "steering_deg": [float(np.degrees(data["steering"].min())), float(np.degrees(data["steering"].max()))],
        "targets": sorted(str(s) for s in data["target"].unique()),
        "lidar_reference": reference_quality(data),
        "lidar_reference_per_target": {str(t): reference_quality(f) for t, f in data.groupby("target", sort=True)},
        "localisation": localisation_error(data),
    }
    if splits is not None:
        summary["split"] = {scheme: {k: (len(v) if isinstance(v, list) else v) for k, v in split.items()}
                            for scheme, split in splits.items()}
        test = data[data["series_id"].isin(splits["by_series"]["test"])]
        summary["lidar_reference_test"] = reference_quality(test)
    return summary


@dataclass
class QCarDataset:
    """A collected dataset: the clean frame, one split scheme and corrupted views.

    Attributes:
        frame: every series, long format.
        split: the active scheme's ``train`` / ``val`` / ``test`` series ids.
        path: the dataset folder.
        scheme: ``by_series`` or ``leave_target_out``.
        splits: both schemes, as in ``split.json``.
    """

    frame: pd.DataFrame
    split: dict[str, list[str]]
    path: Path
    scheme: str = "by_series"
    splits: dict[str, dict] | None = None

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

    def series(self, column: str = "d_clean", split: str | None = None) -> list[np.ndarray]:
        """One float32 array of ``column`` per series (all, or one split's), in order."""
        if column not in self.frame.columns:
            raise ValueError(f"column must be one of {list(self.frame.columns)}, got {column!r}")
        return [g[column].to_numpy(np.float32) for _, g in self.clean(split).groupby("series_id", sort=False)]

    def corrupted(self, preset: str, split: str | None = None, draw: int = 0) -> pd.DataFrame:
        """Clean series plus the preset's ``draw``-th corruption: ``d_meas``, ``c_meas``, ``label`` (0/1), ``kind``.

        A series' draw is seeded by what the series is (``draw_seed(drive_seed, preset, draw)``),
        so every method sees identical corrupted input, on every machine and whatever the code
        version in the series id.
        """
        frame = self.clean(split).copy()
        parts = []
        for sid, s in frame.groupby("series_id", sort=False):
            c = corrupt_series(s["d_clean"].to_numpy(), s["c_clean"].to_numpy(), preset,
                               seed=draw_seed(int(s["drive_seed"].iloc[0]), preset, draw))
            parts.append(pd.DataFrame({"d_meas": c.depth, "c_meas": c.confidence, "label": c.label,
                                       "kind": c.kind}, index=s.index))
        return frame.join(pd.concat(parts)) if parts else frame


def load_dataset(path: Path, split: str = "by_series", held_out: str | None = None) -> QCarDataset:
    """Loads a dataset folder written by ``racf collect``; a clear error if it is not one.

    Args:
        path: the dataset folder.
        split: ``by_series`` (70 / 10 / 20 %) or ``leave_target_out``.
        held_out: with ``leave_target_out``, the target to hold out (default: the one in
            ``split.json``), e.g. ``sign2`` or ``obstacle0``.
    """
    path = Path(path)
    if split not in SPLITS:
        raise ValueError(f"split must be one of {SPLITS}, got {split!r}")
    if held_out is not None and split != "leave_target_out":
        raise ValueError("held_out applies to split='leave_target_out' only")
    data_file, split_file = path / "dataset.parquet", path / "split.json"
    if not data_file.exists() or not split_file.exists():
        raise UserError(f"{path} is not a racf dataset folder (need dataset.parquet and split.json; "
                        f"make one with `racf collect --out {path}`)")
    try:
        frame = pd.read_parquet(data_file)
        raw = json.loads(split_file.read_text())
    except (OSError, ValueError) as err:  # pyarrow's and json's errors for a file that is not theirs
        raise UserError(f"{path} holds a corrupt dataset ({type(err).__name__}: {err}); recollect it with "
                        f"`racf collect --out {path}`") from None
    missing = sorted(set(COLUMNS) - set(frame.columns))
    if missing or not isinstance(raw, dict) or "by_series" not in raw:
        raise UserError(f"{path} is a dataset of an older racf (lacks columns {missing} or both splits); "
                         f"recollect it with `racf collect --out {path}`")
    splits = {k: raw[k] for k in SPLITS}
    if held_out is not None and held_out != splits["leave_target_out"]["held_out"]:
        splits["leave_target_out"] = make_target_split(frame, held_out, int(raw["seed"]))
    chosen = {k: splits[split][k] for k in ("train", "val", "test")}
    return QCarDataset(frame, chosen, path, split, splits)
