"""``DepthBias``: a constant offset on the sign's depth during an attack window."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from racf.sim.attacks._common import check_region
from racf.sim.attacks.base import AttackWrapper
from racf.sim.attacks.schedule import AttackSchedule, as_range

__all__ = ["DepthBias"]


class DepthBias(AttackWrapper):
    """Adds ``bias_m`` to the valid depth pixels of the sign's region (or the frame).

    Args:
        env: the racf env.
        bias_m: magnitude, metres: a value or a (low, high) range drawn once per episode.
        direction: ``+1`` (farther: the dangerous case), ``-1`` (nearer) or ``0`` (random per episode).
        region: ``"sign"`` or ``"frame"``.
        **schedule: ``AttackSchedule`` fields (duration_s, cooldown_s, window_s, stable_steps,
            trigger, ...); its defaults are the protocol's.

    Pixels pushed to or below zero read as no return.
    """

    name = "depth_bias"

    def __init__(self, env: gym.Env, bias_m: Any = (0.5, 1.0), direction: int = 1, region: str = "sign",
                 **schedule: Any) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, bias_m=bias_m, direction=direction, region=region, **schedule)
        self.bias_range = as_range("bias_m", bias_m, 0.0, 20.0)
        if direction not in (-1, 0, 1):
            raise ValueError(f"direction must be -1, 0 (random) or 1, got {direction!r}")
        self.direction = direction
        self.region = check_region(region)
        super().__init__(env, AttackSchedule(**schedule))
        self.bias = 0.0

    def _on_reset(self) -> None:
        sign = self.direction or (1 if self.rng.random() < 0.5 else -1)
        self.bias = sign * float(self.rng.uniform(*self.bias_range))

    def _attack(self, obs: dict, info: dict) -> dict:
        depth = obs["depth"].copy()
        plane = depth[..., 0]  # (H, W) view of the (H, W, 1) image, like the sign's region
        where = (plane > 0) & (self.sign_region(info, 1) if self.region == "sign" else True)
        shifted = plane[where] + self.bias
        plane[where] = np.where(shifted > 0, shifted, 0.0).astype(depth.dtype)
        obs["depth"] = depth
        return obs
