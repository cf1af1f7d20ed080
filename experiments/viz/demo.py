"""``racf demo``: one clean stop-sign trial, driven by the perception pipeline and filmed.

The car follows the approach route (Stanley, curve speed limit, PI speed loop); the
detector finds the sign in the RGB image, the depth distance feeds the braking
controller, and the car stops for the line. Writes a top view with the trajectory, a
strip of chase / camera (with the detection box) / depth frames, and traces of speed,
brake command, d_true, d_meas and the LiDAR reference.
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np

from experiments.episode import TrialSpec, default_env, run_trial

__all__ = ["run_demo"]

_FRAME_EVERY = 15


def run_demo(out_dir: Path, sign: int = 2, speed: float = 1.0, seed: int = 0) -> dict:
    """Runs one clean trial and writes pictures; returns a summary dict."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from tqdm import tqdm

    from experiments.viz.figures import camera_views, top_view

    out_dir.mkdir(parents=True, exist_ok=True)
    frames: list[tuple] = []
    last: dict = {}
    bar = tqdm(desc=f"demo: stop sign {sign} at {speed} m/s", unit="step")

    def on_step(env, obs, info, row):
        last.update(obs=obs, info=info)
        if bar.n % _FRAME_EVERY == 0:
            rgb = obs["rgb"].copy()
            if row["detected"]:
                cv2.rectangle(rgb, (row["det_x0"] - 2, row["det_y0"] - 2), (row["det_x1"] + 1, row["det_y1"] + 1),
                              (0, 255, 0), 1)
            frames.append((row["t"], rgb, obs["depth"][..., 0], env.render(), row["brake"]))
        bar.update()

    spec = TrialSpec("clean", sign, speed, seed)
    result, log = run_trial(spec, make_env=lambda s: default_env(s, render_mode="rgb_array"), on_step=on_step)
    bar.close()
    log.to_parquet(out_dir / "demo_log.parquet", index=False)

    top_view(out_dir / "demo_top.png", pose=tuple(last["info"]["pose"]),
             trajectory=log[["x", "y"]].to_numpy(), title=f"Approach to stop sign {sign} at {speed} m/s")
    camera_views(out_dir, last["obs"]["rgb"], last["obs"]["depth"][..., 0], last["obs"]["lidar"], last["info"]["sign_mask"],
                 prefix="demo_final_")

    picks = np.linspace(0, len(frames) - 1, min(6, len(frames))).astype(int)
    fig, axes = plt.subplots(3, len(picks), figsize=(3.2 * len(picks), 7.2), squeeze=False)
    for col, i in enumerate(picks):
        t, rgb, depth, chase, brake = frames[i]
        axes[0, col].imshow(chase)
        axes[0, col].set_title(f"t = {t:.2f} s" + (" (braking)" if brake else ""), fontsize=9)
        axes[1, col].imshow(rgb)
        axes[2, col].imshow(np.where(depth > 0, depth, np.nan), cmap="turbo", vmin=0, vmax=3)
        for row in range(3):
            axes[row, col].axis("off")
    axes[0, 0].text(-0.05, 0.5, "chase view", transform=axes[0, 0].transAxes, rotation=90, va="center", ha="right")
    axes[1, 0].text(-0.05, 0.5, "D435 colour + detection", transform=axes[1, 0].transAxes, rotation=90,
                    va="center", ha="right")
    axes[2, 0].text(-0.05, 0.5, "depth (0-3 m)", transform=axes[2, 0].transAxes, rotation=90, va="center", ha="right")
    fig.tight_layout()
    fig.savefig(out_dir / "demo_frames.png", dpi=90)
    plt.close(fig)

    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7, 5.5), sharex=True)
    a1.plot(log["t"], log["speed"], label="speed")
    a1.fill_between(log["t"], 0, log["brake"].astype(float) * max(speed, 0.1), alpha=0.2, color="r", label="brake command")
    a1.set_ylabel("m/s")
    a1.legend()
    a2.plot(log["t"], log["dist_to_stop_line"], label="front bumper to stop line")
    a2.plot(log["t"], log["d_true"].where(log["sign_in_view"]), lw=2.5, alpha=0.6, label="d_true (camera to sign; in view)")
    a2.plot(log["t"], log["d_meas"], ".", ms=3, label="d_meas (median depth in the detection)")
    a2.plot(log["t"], log["lidar"], "x", ms=3, label="LiDAR cluster range")
    a2.axhspan(0, 0.6, color="g", alpha=0.12, label="success band 0-0.60 m")
    a2.set_ylabel("m")
    a2.set_xlabel("time (s)")
    a2.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out_dir / "demo_traces.png", dpi=100)
    plt.close(fig)

    return {"sign": sign, "speed": speed, "steps": len(log), "stopped": result.stopped,
            "stop_distance_m": result.stop_distance_m, "success": result.success,
            "trigger_delay_s": result.to_dict()["trigger_delay_s"], "dt_brake_s": result.to_dict()["dt_brake_s"],
            "failure": result.failure, "outputs": sorted(str(p) for p in out_dir.glob("*.png"))}

