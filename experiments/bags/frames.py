"""A replay's rerun recording: the frames the car saw, placed by its own pose estimate (a recording
has no ground truth to place them by)."""

from __future__ import annotations

import numpy as np

from racf.experiments.episode.rerun_log import Frame

__all__ = ["ReplayFrames"]


class ReplayFrames:
    """Step hook for :func:`racf.experiments.bags.replay.replay_bag` keeping one frame every ``every``
    steps (default 5: 10 Hz), the camera placed from the car's estimated pose and its build."""

    def __init__(self, calibration, intrinsics, every: int = 5) -> None:
        self.calibration = calibration
        self.intrinsics = intrinsics
        self.every = every
        self.frames: list[Frame] = []
        self._step = 0

    def __call__(self, env, obs: dict, info: dict, row: dict) -> None:
        if self._step % self.every == 0:
            x, y, yaw = float(row["x_est"]), float(row["y_est"]), float(row["yaw_est"])
            c, s = np.cos(yaw), np.sin(yaw)
            cx, cy = self.calibration.camera_xy_m
            cam_pos = np.array([x + c * cx - s * cy, y + s * cx + c * cy, self.calibration.camera_height_m])
            # MuJoCo's camera axes in the map: x right, y up, z backward.
            cam_mat = np.column_stack([[s, -c, 0.0], [0.0, 0.0, 1.0], [-c, -s, 0.0]])
            depth = obs["depth"][..., 0]
            self.frames.append(Frame(float(row["t"]), obs["rgb"].copy(),
                                     np.clip(np.rint(depth * 1000.0), 0, 65535).astype(np.uint16),
                                     np.asarray(obs["lidar"], np.float32).copy(), cam_pos, cam_mat, None))
        self._step += 1
