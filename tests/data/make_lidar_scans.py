"""Records the LiDAR scans (and the ground truth around them) in ``lidar_scans.npz``.

Run from the repository root: ``python tests/data/make_lidar_scans.py``. Each approach (the
four stop signs and the two crates) starts at 1 m/s a short run-up before the target,
drives straight (speed 1 m/s, no steering) and keeps the scan of every step on which a new
one arrives (the LiDAR scans at 10 Hz, control runs at 50 Hz). Per control step it also
keeps what a tracker is fed and what it is scored against, so tests can replay the
approaches without the simulator.

Arrays (S scans, T control steps, all float32 unless said):
    ranges (S, 360): the scans, metres, inf = no return.
    scan_step (S,) int32: the control step (index into the per-step arrays) of each scan.
    episode (T,) int32: approach index; step (T,) int32: control step within it.
    target_is_sign (T,) bool: stop sign (True) or crate (False).
    speed, yaw_rate (T,): odometry, m/s and rad/s.
    d_true (T,): depth of the target's centre along the optical axis, metres.
    bearing (T,): the target centre's bearing from the optical axis, rad, left positive.
    span_left, span_right (T,): bearings of the left and right edges of the target's
        visible pixels, rad; NaN when it is not in view.
"""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np

from racf import sim

OUT = Path(__file__).with_name("lidar_scans.npz")
#: Reset options per approach; the run-ups put the car on the straight before the target.
APPROACHES = [{"sign": 0, "run_up_m": 1.6}, {"sign": 1, "run_up_m": 1.2}, {"sign": 2, "run_up_m": 0.8},
              {"sign": 3, "run_up_m": 0.8}, {"obstacle": 0, "run_up_m": 1.2}, {"obstacle": 1, "run_up_m": 1.2}]
STEPS = 21  # 5 scans per approach (a new scan on steps 0, 5, ..., 20)
SEED = 7


def main() -> None:
    env = gym.make(sim.ENV_ID)
    k = env.unwrapped.rig.intrinsics
    rows: dict[str, list] = {name: [] for name in
                             ("episode", "step", "target_is_sign", "speed", "yaw_rate", "d_true", "bearing",
                              "span_left", "span_right")}
    ranges, scan_step = [], []
    for episode, option in enumerate(APPROACHES):
        obs, info = env.reset(seed=SEED + episode, options={**option, "cruise_speed": 1.0})
        for step in range(STEPS):
            if step > 0:
                obs, _, terminated, truncated, info = env.step(np.array([1.0, 0.0], np.float32))
                if terminated or truncated:
                    raise RuntimeError(f"approach {option} ended early at step {step}")
            if step % 5 == 0:
                ranges.append(obs["lidar"].astype(np.float32))
                scan_step.append(len(rows["step"]))
            cols = np.nonzero(info["sign_mask"].any(axis=0))[0]
            left = right = np.nan
            if cols.size:
                left = np.arctan2(k.cx - (cols.min() - 0.5), k.fx)
                right = np.arctan2(k.cx - (cols.max() + 0.5), k.fx)
            values = (episode, step, info["target_kind"] == "stop_sign", obs["state"][0], obs["state"][2],
                      info["d_true"], info["sign_bearing"], left, right)
            for name, value in zip(rows, values):
                rows[name].append(value)
    env.close()
    arrays = {"ranges": np.stack(ranges), "scan_step": np.asarray(scan_step, np.int32)}
    for name, values in rows.items():
        dtype = {"episode": np.int32, "step": np.int32, "target_is_sign": bool}.get(name, np.float32)
        arrays[name] = np.asarray(values, dtype)
    np.savez_compressed(OUT, **arrays)
    print(f"wrote {OUT} ({OUT.stat().st_size / 1024:.0f} KiB): {len(ranges)} scans, {len(rows['step'])} steps")


if __name__ == "__main__":
    main()
