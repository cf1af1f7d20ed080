"""``DepthBlackout``: no depth over the sign (or the whole frame) during an attack window."""

from __future__ import annotations

from typing import Any

import gymnasium as gym

from racf.sim.attacks._common import check_region
from racf.sim.attacks.base import AttackWrapper
from racf.sim.attacks.schedule import AttackSchedule

__all__ = ["DepthBlackout"]


class DepthBlackout(AttackWrapper):
    """Invalidates depth (0 = no return) inside the sign's region grown by ``margin_px``, or everywhere.

    Args:
        env: the racf env.
        region: ``"sign"`` or ``"frame"``.
        margin_px: growth of the sign's region, pixels.
        **schedule: ``AttackSchedule`` fields (duration_s, cooldown_s, window_s, stable_steps,
            trigger, ...); its defaults are the protocol's.
    """

    name = "depth_blackout"

    def __init__(self, env: gym.Env, region: str = "sign", margin_px: int = 2, **schedule: Any) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, region=region, margin_px=margin_px, **schedule)
        self.region = check_region(region)
        if not (isinstance(margin_px, int) and 0 <= margin_px <= 50):
            raise ValueError(f"margin_px must be an int in [0, 50], got {margin_px!r}")
        self.margin_px = margin_px
        super().__init__(env, AttackSchedule(**schedule))

    def _attack(self, obs: dict, info: dict) -> dict:
        depth = obs["depth"].copy()
        if self.region == "frame":
            depth[:] = 0.0
        else:
            depth[self.sign_region(info, self.margin_px)] = 0.0
        obs["depth"] = depth
        return obs
