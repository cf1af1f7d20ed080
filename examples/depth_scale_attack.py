"""A one-file racf attack, used through ``--plugin``: the depth of the sign scaled by a factor.

    racf trials --plugin examples/depth_scale_attack.py --attack depth_scale --estimator odca -n 12

A miscalibration-style attack: every valid depth pixel of the sign's region is multiplied by
``scale`` while the attack is on (the protocol's schedule decides when), so the sign reads
farther (scale > 1) or nearer (scale < 1) than it is, by an amount that grows with distance.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym

from racf.sim.attacks import AttackSchedule, AttackWrapper


class DepthScale(AttackWrapper):
    """Multiplies the sign's valid depth pixels by ``scale`` (a miscalibrated or spoofed depth)."""

    name = "depth_scale"

    def __init__(self, env: gym.Env, scale: float = 1.6, **schedule: Any) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, scale=scale, **schedule)
        if not (isinstance(scale, (int, float)) and 0.1 <= scale <= 10.0):
            raise ValueError(f"scale must be a number in [0.1, 10], got {scale!r}")
        super().__init__(env, AttackSchedule(**schedule))
        self.scale = float(scale)

    def _attack(self, obs: dict, info: dict) -> dict:
        depth = obs["depth"].copy()
        plane = depth[..., 0]  # a view of the (H, W, 1) image
        where = (plane > 0) & self.sign_region(info, 1)
        plane[where] *= self.scale
        obs["depth"] = depth
        return obs
