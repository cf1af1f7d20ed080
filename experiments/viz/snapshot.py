"""``racf snapshot``: the map from above and the car's camera, depth and LiDAR at a pose."""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym

from racf import sim  # noqa: F401  (registers the env)
from racf.experiments.viz.figures import camera_views, top_view

__all__ = ["snapshot"]


def snapshot(out_dir: Path, sign: int = 2, run_up_m: float = 1.2, width: int = 320, height: int = 240,
             seed: int = 0) -> list[Path]:
    """Places the car ``run_up_m`` before stop sign ``sign``'s stop line and writes PNGs."""
    out_dir.mkdir(parents=True, exist_ok=True)
    env = gym.make(sim.ENV_ID, camera_width=width, camera_height=height)
    try:
        obs, info = env.reset(seed=seed, options={"sign": sign, "cruise_speed": 0.0, "run_up_m": run_up_m})
        paths = [top_view(out_dir / "map_top.png", pose=tuple(info["pose"]),
                          title=f"QCar 2 indoor map: car {run_up_m} m before stop sign {sign}")]
        paths += camera_views(out_dir, obs["rgb"], obs["depth"][..., 0], obs["lidar"], info["sign_mask"])
        return paths
    finally:
        env.close()
