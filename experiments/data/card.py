"""The dataset's card (``dataset_card.md``: what it holds, how it was made, its columns and its
measured quality) and its picture of the first drives (``series.png``)."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

__all__ = ["write_card", "plot_series"]


_PROFILE_TEXT = {
    "qcar2": "the `qcar2` sensor profile: the RPLIDAR A2M12 swept over its 0.1 s revolution (1600 samples, "
             "1 % range noise, 1 mm steps, 0.2 m minimum, dropout by material and incidence, mixed returns "
             "at edges) and delivered through Quanser's 384-sample read and 1-degree filter; the camera at "
             "30 Hz (depth 0.0037 z^2 m); the encoder's counts, the gyro's noise and bias; the car's own "
             "localisation on the localiser's drifting fixes",
    "ideal": "the `ideal` sensor profile (an ablation): a one-instant 360-beam LiDAR with 1 % noise, every "
             "sensor at 50 Hz (depth 0.0037 z^2 m), the true pose as the fix",
}


def write_card(path: Path, summary: dict, columns: dict[str, tuple[str, str]], drives: int, seed: int,
               sensor_profile: str, sign_geometry: str, detector: str) -> None:
    """Writes the card of a dataset from its summary (``summarize_dataset``) and its columns."""
    rows = "\n".join(f"| `{name}` | {unit} | {meaning} |" for name, (unit, meaning) in columns.items())
    ref, loc = summary["lidar_reference"], summary["localisation"]
    path.write_text(f"""# RACF QCar 2 simulated driving dataset

**What.** Synchronized 50 Hz series from the racf MuJoCo simulation of the Quanser QCar 2 on
its indoor map: the perception pipeline's clean depth distance to the current target and
its confidence, the LiDAR target reference and a compact scan, the vehicle state and pose,
and the simulator's ground truth. Shaped like the RACF paper's QCar 2 benchmark (67,821
samples, 13 sequences of ~100 s, speeds 1.0 / 1.5 / 2.0 m/s). Simulated data, not
recordings of a real car.

**Sensors.** {_PROFILE_TEXT[sensor_profile]}. Stop signs: `{sign_geometry}` geometry. The car's
stop-sign detector: `{detector}`.

**How it was made.** `racf collect --drives {drives} --seed {seed} --sensor-profile {sensor_profile}
--sign-geometry {sign_geometry}`: {drives} continuous clean
closed-loop drives (seeds `{seed} * 100000 + k`). Each drive is a random road-graph route
of 20-60 s that meets at least two targets; its seed draws the start node, the run-up
along the first edge, a lateral offset (+-3 cm), a heading error (+-5 deg) and the cruise
speed (nominal 1.0 / 1.5 / 2.0 m/s in turn, x U(0.9, 1.1)). The car follows the route
(Stanley, a curve speed limit, a PI speed loop), stops at every stop sign, dwells 1 s and
drives on; a blue crate (0.12 x 0.16 x 0.22 m) on the lane, with a virtual stop line
0.25 m before it, ends the drive. The detector (stop sign, or crate by colour), the depth
distance, the LiDAR target tracker and the braking controller run as in
`racf trial --setting clean`, on the sensors above.

**Counts.** {summary['n_series']} series, {summary['n_samples']} samples
({summary['n_moving_samples']} moving, standstill share {summary['standstill_share']:.2f});
{summary['series_duration_s']['min']:.0f}-{summary['series_duration_s']['max']:.0f} s per series
(median {summary['series_duration_s']['median']:.0f} s); targets per series
{summary['targets_per_series']['min']}-{summary['targets_per_series']['max']}; series per target
{summary['series_per_target']}; {summary['distinct_start_poses']} distinct start poses.

**Splits** (`split.json`; `load_dataset(path, split=...)`): `by_series` (seeded 70 / 10 / 20 %)
and `leave_target_out` (every series that meets the held-out target is test):
{summary.get('split')}.

**Quality.** d_clean vs d_true over {summary['n_clean_samples']} samples with the target in view
and detected: RMSE {summary['rmse_clean_vs_true']:.4f} m, MAE {summary['mae_clean_vs_true']:.4f} m.
LiDAR reference vs d_true over {ref['n_reported']} reported steps: RMSE {ref['rmse_vs_true']:.4f} m;
it reports on {ref['coverage']:.1%} of the steps with the target in view within 3 m; {ref['outlier_share']:.2%}
of the reported values are more than 0.15 m off.
The car's own pose (its filter on odometry, the gyro and the localiser's fixes) against the truth
over all {loc['n']} steps: position RMSE {loc['filter']['position_m_rmse']:.4f} m (p95
{loc['filter']['position_m_p95']:.4f}, max {loc['filter']['position_m_max']:.4f}), heading RMSE
{loc['filter']['heading_deg_rmse']:.2f} deg (p95 {loc['filter']['heading_deg_p95']:.2f}, max
{loc['filter']['heading_deg_max']:.2f}); the raw fixes, over the {loc['n_fixes']} steps a new one arrived:
{loc['fix']['position_m_rmse']:.4f} m and {loc['fix']['heading_deg_rmse']:.2f} deg RMSE.

**Columns** (long format, one row per 50 Hz step):

| column | unit | meaning |
|---|---|---|
{rows}

**Corruption.** `racf.experiments.data.dataset.load_dataset(path).corrupted("weak" | "mid" | "strong", draw=k)`
adds the protocol's offline corruption (`d_meas`, `c_meas`, `label`, `kind`); draw k of a series
is seeded by (its `drive_seed`, the preset, k), so it does not change with the code.
""")


def plot_series(data: pd.DataFrame, path: Path) -> None:
    """Plots the first three drives: distances and speed over time."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    picks = list(dict.fromkeys(data["series_id"]))[:3]
    fig, axes = plt.subplots(len(picks), 1, figsize=(11, 2.6 * len(picks)), squeeze=False, sharex=False)
    for ax, sid in zip(axes[:, 0], picks):
        s = data[data["series_id"] == sid]
        ax.plot(s["t"], s["d_true"].where(s["sign_in_view"]), lw=2.5, alpha=0.5, label="d_true (in view)")
        ax.plot(s["t"], s["d_clean"], ".", ms=3, label="d_clean")
        ax.plot(s["t"], s["lidar"], "x", ms=3, label="LiDAR reference")
        ax.plot(s["t"], s["speed"], "k-", lw=1, label="speed (m/s)")
        ax.set_title(f"{sid}: " + " -> ".join(s.groupby("slot")["target"].first()), fontsize=9)
        ax.set_ylabel("m, m/s")
        ax.set_ylim(0, 3.5)
    axes[0, 0].legend(fontsize=7, ncol=4)
    axes[-1, 0].set_xlabel("t (s)")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
