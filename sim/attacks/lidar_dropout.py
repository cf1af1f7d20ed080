"""``LidarDropout``: LiDAR returns removed around the sign (or everywhere) during a window."""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np

from racf.sim.attacks.base import AttackWrapper
from racf.sim.attacks.schedule import AttackSchedule

__all__ = ["LidarDropout"]


class LidarDropout(AttackWrapper):
    """Sets a share ``share`` of the beams in a sector to no return (inf).

    Beyond the paper: its gate trusts the LiDAR, so losing it is worth testing.

    Args:
        env: the racf env.
        share: share of the sector's beams removed, in [0, 1].
        sector: ``"sign"`` (beams on the sign's plate plus ``margin_deg``) or ``"all"``.
        margin_deg: widening of the sign sector, degrees.
        **schedule: ``AttackSchedule`` fields (duration_s, cooldown_s, window_s, stable_steps,
            trigger, ...); its defaults are the protocol's.
    """

    name = "lidar_dropout"
    needs_simulator = "it aims at the sign's beams from the simulator's geometry"

    def __init__(self, env: gym.Env, share: float = 1.0, sector: str = "sign", margin_deg: float = 3.0,
                 **schedule: Any) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, share=share, sector=sector, margin_deg=margin_deg, **schedule)
        if not 0.0 <= share <= 1.0:
            raise ValueError(f"share must be in [0, 1], got {share!r}")
        if sector not in ("sign", "all"):
            raise ValueError(f"sector must be 'sign' or 'all', got {sector!r}")
        if not 0.0 <= margin_deg <= 180.0:
            raise ValueError(f"margin_deg must be in [0, 180], got {margin_deg!r}")
        self.share, self.sector, self.margin_rad = float(share), sector, math.radians(margin_deg)
        super().__init__(env, AttackSchedule(**schedule))

    def _attack(self, obs: dict, info: dict) -> dict:
        ranges = obs["lidar"].copy()
        beams = self.sign_beams(ranges.size, self.margin_rad) if self.sector == "sign" else np.ones(ranges.size, bool)
        beams &= self.rng.random(ranges.size) < self.share
        ranges[beams] = np.inf
        obs["lidar"] = ranges
        return obs
