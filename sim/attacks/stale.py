"""``StaleData``: the stale-data attacks. LiDAR scans replayed late, or the depth frozen at a past frame."""

from __future__ import annotations

from collections import deque
from typing import Any

import gymnasium as gym
import numpy as np

from racf.sim.attacks._common import check_region
from racf.sim.attacks.base import AttackWrapper
from racf.sim.attacks.schedule import AttackSchedule
from racf.sim.sensors import TIMESTAMP_FIELDS

__all__ = ["StaleData", "STALE_SENSORS"]

#: What the attack can make stale.
STALE_SENSORS = ("lidar", "depth")
_SCAN_TIME = TIMESTAMP_FIELDS.index("lidar")
_FRAME_TIME = TIMESTAMP_FIELDS.index("depth")


class StaleData(AttackWrapper):
    """Replays stale sensor data as fresh while the car moves on: LiDAR scans `frames` late (`sensor="lidar"`) or depth frozen at the attack's start (`sensor="depth"`).

    Black box: it reads only the sensor stream it tampers with (and, for the depth region,
    where the sign is, as every attack here may).

    - ``sensor="lidar"``: each scan the car receives is the one delivered ``frames`` scans
      earlier (the scan's timestamp and beam times stay the current ones: the car takes the
      old ranges for a fresh scan). Before ``frames`` scans are buffered, the oldest one is
      replayed.
    - ``sensor="depth"``: the depth image is frozen at the frame delivered when the attack
      began, over the whole frame or in the sign's region (``region``), and stays frozen while
      the window lasts (``frames`` is unused).

    Args:
        env: the racf env.
        sensor: ``"lidar"`` or ``"depth"``.
        frames: the LiDAR's delay, in scans (1 to 50; the A2M12 scans at 10 Hz).
        region: for depth, ``"frame"`` (the default) or ``"sign"``.
        **schedule: ``AttackSchedule`` fields; its defaults are the protocol's.
    """

    name = "delay"

    def __init__(self, env: gym.Env, sensor: str = "lidar", frames: int = 5, region: str = "frame",
                 **schedule: Any) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, sensor=sensor, frames=frames, region=region, **schedule)
        if sensor not in STALE_SENSORS:
            raise ValueError(f"sensor must be one of {STALE_SENSORS}, got {sensor!r}")
        if not (isinstance(frames, (int, np.integer)) and not isinstance(frames, bool) and 1 <= frames <= 50):
            raise ValueError(f"frames must be an integer number of scans in [1, 50], got {frames!r}")
        self.sensor, self.frames, self.region = sensor, int(frames), check_region(region)
        super().__init__(env, AttackSchedule(**schedule))
        self._scans: deque = deque(maxlen=self.frames + 1)
        self._frozen: np.ndarray | None = None
        self._last_depth: np.ndarray | None = None
        self._scan_time = -np.inf
        self._frame_time = -np.inf

    def _on_reset(self) -> None:
        self._scans.clear()
        self._frozen = self._last_depth = None
        self._scan_time = self._frame_time = -np.inf

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None):
        obs, info = super().reset(seed=seed, options=options)
        self._remember(obs)
        return obs, info

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        self._remember(obs)
        self.active = self.schedule.update(info)
        if self.active:
            obs = self._attack(dict(obs), info)
        else:
            self._frozen = None
        return obs, reward, terminated, truncated, self._mark(info)

    def _remember(self, obs: dict) -> None:
        """Buffers each new scan and the latest depth frame, as delivered (before the attack)."""
        stamps = np.asarray(obs["timestamps"], np.float64)
        if stamps[_SCAN_TIME] != self._scan_time:
            self._scan_time = float(stamps[_SCAN_TIME])
            self._scans.append(np.array(obs["lidar"], copy=True))
        if stamps[_FRAME_TIME] != self._frame_time or self._last_depth is None:
            self._frame_time = float(stamps[_FRAME_TIME])
            if self._frozen is None:  # once frozen, the frame before the attack is kept
                self._last_depth = np.array(obs["depth"], copy=True)

    def _attack(self, obs: dict, info: dict) -> dict:
        if self.sensor == "lidar":
            obs["lidar"] = self._scans[0].copy()  # ``frames`` scans before the newest one
            return obs
        if self._frozen is None:
            self._frozen = self._last_depth.copy()
        depth = obs["depth"].copy()
        where = self.sign_region(info, 1) if self.region == "sign" else np.ones(depth.shape[:2], bool)
        depth[where] = self._frozen[where]
        obs["depth"] = depth
        return obs
