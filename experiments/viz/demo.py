"""``racf demo``: the whole story at one stop sign, in three closed-loop runs.

1. **Clean**: the car sees the sign, measures its distance with the depth camera and stops
   in the band before the line.
2. **Attack**: after the detection is stable, an adversarial patch covers the sign
   (strong regime); the detector loses it and the car, with no defence, runs the line.
3. **Attack + ODCA**: the same attack (same seed), with ODCA repairing the distance from
   the LiDAR reference and the temporal prior; the car stops.

Each run is recorded to rerun (``<setting>.rrd``: camera, depth, LiDAR, map, distances,
gate and brake); one PNG puts the three distance traces side by side with the attack
window shaded, and a small table gives stopped?, stop distance, trigger delay and dt_brake.
Every number comes from the runs.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

__all__ = ["DEMO_SETTINGS", "run_demo", "demo_table"]

#: The three runs, in the order the story tells them.
DEMO_SETTINGS = ("clean", "attack", "attack+odca")


def run_demo(out_dir: Path, sign: int = 1, speed: float = 1.5, seed: int = 0,
             settings: tuple[str, ...] = DEMO_SETTINGS, progress: bool = True, sensor_profile: str = "qcar2",
             sign_geometry: str = "plate") -> dict:
    """Runs the settings at one sign and writes ``<setting>.rrd``, ``<setting>.parquet``, ``demo_traces.png``
    and ``moment.png`` (the defended run at the moment the attack acts: ``racf.experiments.viz.moment``)."""
    from tqdm import tqdm

    from racf.experiments.episode import TrialSpec
    from racf.experiments.episode.rerun_log import recorded_trial

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    rows, logs = [], {}
    for setting in tqdm(settings, desc=f"demo: stop sign {sign} at {speed} m/s", unit="run", disable=not progress):
        spec = TrialSpec(setting, sign, speed, seed, sensor_profile=sensor_profile, sign_geometry=sign_geometry)
        name = setting.replace("+", "_")
        rrd = out_dir / f"{name}.rrd"
        result, log = recorded_trial(spec, rrd, f"racf demo: {setting}")
        log.to_parquet(out_dir / f"{name}.parquet", index=False)
        logs[setting] = log
        r = result.to_dict()
        rows.append({"setting": setting, "stopped": r["stopped"], "success": r["success"],
                     "stop_distance_m": r["stop_distance_m"], "trigger_delay_s": r["trigger_delay_s"],
                     "dt_brake_s": r["dt_brake_s"], "failure": r["failure"], "rrd": str(rrd)})
    png = traces_figure(logs, out_dir / "demo_traces.png", sign, speed)
    summary = {"sign": sign, "speed": speed, "seed": seed, "sensor_profile": sensor_profile,
               "sign_geometry": sign_geometry, "runs": rows, "png": str(png)}
    defended = next((s for s in settings if s.startswith("attack+")), None)
    if defended is not None:  # the moment the attack acts and the defence answers (the README's figure)
        from racf.experiments.viz.moment import moment_figure

        spec = TrialSpec(defended, sign, speed, seed, sensor_profile=sensor_profile, sign_geometry=sign_geometry)
        summary["moment_png"] = str(moment_figure(spec, out_dir / "moment.png", logs[defended]))
    return summary


def demo_table(summary: dict) -> str:
    """The demo's result table (plain text)."""
    def f(x, unit=""):
        return "—" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{x:.2f}{unit}"

    lines = [f"stop sign {summary['sign']} at {summary['speed']} m/s, seed {summary['seed']}",
             f"{'setting':<14}{'stopped?':>9}{'stop dist':>11}{'trigger delay':>15}{'dt_brake':>10}  outcome"]
    for r in summary["runs"]:
        outcome = "stopped in the band" if r["success"] else f"failed: {r['failure']}"
        lines.append(f"{r['setting']:<14}{'yes' if r['stopped'] else 'no':>9}{f(r['stop_distance_m'], ' m'):>11}"
                     f"{f(r['trigger_delay_s'], ' s'):>15}{f(r['dt_brake_s'], ' s'):>10}  {outcome}")
    lines.append("stop dist: front bumper to the line at rest (success band 0-0.60 m); trigger delay: brake "
                 "command - t*; dt_brake: t* to braking within 0.60 m of the line")
    return "\n".join(lines)


def traces_figure(logs: dict, path: Path, sign: int, speed: float) -> Path:
    """One panel per run: d_true, the distance the controller used, the brake, the attack window shaded."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(logs), figsize=(4.6 * len(logs), 3.6), sharey=True, squeeze=False)
    for ax, (setting, log) in zip(axes[0], logs.items()):
        t = log["t"].to_numpy()
        active = log["attack_active"].to_numpy(bool)
        edges = np.flatnonzero(np.diff(np.r_[0, active.astype(int), 0]))
        for k, (a, b) in enumerate(zip(edges[::2], edges[1::2])):
            ax.axvspan(t[a], t[min(b, len(t) - 1)], color="red", alpha=0.12, label="attack active" if k == 0 else None)
        ax.plot(t, log["d_true"].where(log["sign_in_view"]), color="black", lw=1.8, label="d_true (sign in view)")
        ax.plot(t, log["d_meas"], ".", color="gray", ms=3, label="d~ (depth in the detection)")
        if np.isfinite(log["lidar"].to_numpy(float)).any():  # no entry for a series with no point to show
            ax.plot(t, log["lidar"], "x", color="#17becf", ms=3, label="LiDAR reference")
        if "odca" in setting:  # from the first measurement on (before it ODCA reports its 0 m fallback)
            started = np.cumsum(np.isfinite(log["d_meas"].to_numpy())) > 0
            ax.plot(t, log["d_fused"].where(started), color="#1f77b4", lw=1.6, label="ODCA d_fused")
        ax.plot(t, log["dist_to_stop_line"], color="#2ca02c", lw=1.0, ls="--", label="bumper to stop line")
        brake = log["brake"].to_numpy(bool)
        if brake.any():
            ax.axvline(t[np.argmax(brake)], color="#d62728", lw=1.2, label="brake command")
        ax.axhspan(0, 0.6, color="g", alpha=0.08)
        ax.set_title(setting, fontsize=10)
        ax.set_xlabel("t (s)")
        ax.grid(alpha=0.3)
    axes[0, 0].set_ylabel("distance (m)")
    # One legend for every panel, below them: inside a panel it covered that panel's traces.
    entries: dict = {}
    for ax in axes[0]:
        for handle, label in zip(*ax.get_legend_handles_labels()):
            entries.setdefault(label, handle)
    fig.legend(entries.values(), entries.keys(), loc="lower center", ncol=min(4, len(entries)), fontsize=8,
               frameon=False)
    fig.suptitle(f"Stop sign {sign} at {speed} m/s: clean, patch attack, patch attack + ODCA", fontsize=11)
    fig.tight_layout(rect=(0, 0.05 + 0.045 * ((len(entries) - 1) // 4), 1, 1))
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return Path(path)
