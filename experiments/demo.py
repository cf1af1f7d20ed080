"""``racf demo``: one stop-sign approach, driven and filmed.

The car follows the approach route with Stanley lane following at a cruise speed and
brakes for the stop line using the simulator's ground-truth distance (the perception
pipeline and ODCA replace that in later experiments). Writes a top view with the
trajectory, a strip of camera and depth frames, and speed / distance traces.
"""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np

import sim
from controllers import StanleyController

__all__ = ["run_demo"]

_BRAKE_DECEL_MPS2 = 3.0  # planning deceleration: well inside the tyres' friction limit


def run_demo(out_dir: Path, sign: int = 2, speed: float = 1.0, seed: int = 0, max_steps: int = 600) -> dict:
    """Drives one approach and writes pictures; returns a summary dict."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from tqdm import tqdm

    from experiments.figures import camera_views, top_view

    out_dir.mkdir(parents=True, exist_ok=True)
    env = gym.make(sim.ENV_ID, render_mode="rgb_array")
    obs, info = env.reset(seed=seed, options={"sign": sign, "cruise_speed": speed})
    route = env.unwrapped.target_sign.path
    follower = StanleyController(route.points, route.headings)
    log = {k: [] for k in ("t", "speed", "d_true", "dist_to_stop_line", "brake", "x", "y")}
    # d_true is plotted only while the sign is in the camera's view.
    frames, braking = [], False
    for step in tqdm(range(max_steps), desc=f"demo: stop sign {sign} at {speed} m/s", unit="step"):
        x, y, yaw = info["pose"]
        v = info["speed"]
        # Brake once the stopping distance at the planning deceleration reaches the line (+5 cm margin).
        braking = braking or info["dist_to_stop_line"] <= v * v / (2 * _BRAKE_DECEL_MPS2) + 0.05 + v * 0.02
        command = 0.0 if braking else speed
        obs, reward, terminated, truncated, info = env.step(
            np.array([command, follower.steer(x, y, yaw, v)], np.float32))
        for key, value in (("t", info["time"]), ("speed", info["speed"]),
                           ("d_true", info["d_true"] if info["sign_in_view"] else np.nan),
                           ("dist_to_stop_line", info["dist_to_stop_line"]), ("brake", float(braking)),
                           ("x", info["pose"][0]), ("y", info["pose"][1])):
            log[key].append(value)
        if step % 15 == 0:
            frames.append((info["time"], obs["rgb"], obs["depth"], env.render()))
        if terminated or truncated or (braking and abs(info["speed"]) < 0.02):
            break
    final_obs, final_info = obs, info
    env.close()

    log_np = {k: np.asarray(v) for k, v in log.items()}
    top_view(out_dir / "demo_top.png", pose=tuple(final_info["pose"]),
             trajectory=np.column_stack([log_np["x"], log_np["y"]]),
             title=f"Approach to stop sign {sign} at {speed} m/s")
    camera_views(out_dir, final_obs["rgb"], final_obs["depth"], final_obs["lidar"], final_info["sign_mask"],
                 prefix="demo_final_")

    picks = np.linspace(0, len(frames) - 1, min(6, len(frames))).astype(int)
    fig, axes = plt.subplots(3, len(picks), figsize=(3.2 * len(picks), 7.2), squeeze=False)
    for col, i in enumerate(picks):
        t, rgb, depth, chase = frames[i]
        axes[0, col].imshow(chase)
        axes[0, col].set_title(f"t = {t:.2f} s", fontsize=9)
        axes[1, col].imshow(rgb)
        axes[2, col].imshow(np.where(depth > 0, depth, np.nan), cmap="turbo", vmin=0, vmax=3)
        for row in range(3):
            axes[row, col].axis("off")
    axes[0, 0].text(-0.05, 0.5, "chase view", transform=axes[0, 0].transAxes, rotation=90, va="center", ha="right")
    axes[1, 0].text(-0.05, 0.5, "D435 colour", transform=axes[1, 0].transAxes, rotation=90, va="center", ha="right")
    axes[2, 0].text(-0.05, 0.5, "depth (0-3 m)", transform=axes[2, 0].transAxes, rotation=90, va="center", ha="right")
    fig.tight_layout()
    fig.savefig(out_dir / "demo_frames.png", dpi=90)
    plt.close(fig)

    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7, 5.5), sharex=True)
    a1.plot(log_np["t"], log_np["speed"], label="speed")
    a1.fill_between(log_np["t"], 0, log_np["brake"] * max(speed, 0.1), alpha=0.2, color="r", label="brake command")
    a1.set_ylabel("m/s")
    a1.legend()
    a2.plot(log_np["t"], log_np["dist_to_stop_line"], label="front bumper to stop line")
    a2.plot(log_np["t"], log_np["d_true"], label="d_true (camera to sign, depth; while in view)")
    a2.axhspan(0, 0.6, color="g", alpha=0.12, label="success band 0-0.60 m")
    a2.set_ylabel("m")
    a2.set_xlabel("time (s)")
    a2.legend()
    fig.tight_layout()
    fig.savefig(out_dir / "demo_traces.png", dpi=100)
    plt.close(fig)

    stop = float(final_info["dist_to_stop_line"])
    return {"sign": sign, "speed": speed, "steps": len(log_np["t"]), "stopped": bool(abs(final_info["speed"]) < 0.05),
            "stop_distance_m": stop, "success": bool(abs(final_info["speed"]) < 0.05 and 0.0 <= stop <= 0.60),
            "outputs": sorted(str(p) for p in out_dir.glob("*.png"))}
