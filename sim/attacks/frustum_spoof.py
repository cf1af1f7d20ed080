"""``FrustumSpoof``: depth and LiDAR moved together, so they agree with each other and not with the world."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from racf.sim.attacks.image_scale import scale_region
from racf.sim.attacks.stealth_ramp import StealthRamp

__all__ = ["FrustumSpoof"]

#: A beam's return counts as the sign's within this of the LiDAR's distance to it, m.
SIGN_RETURN_M = 0.15


class FrustumSpoof(StealthRamp):
    """Shifts the sign's depth and the LiDAR's returns from the sign by the same bias b(t).

    After Hallyburton et al. (USENIX Security 2022): points moved inside the camera's
    frustum so that camera and LiDAR stay consistent. b ramps as in ``StealthRamp`` (white
    box: as far as the defence's detector lets it, asked with the LiDAR moved too), so no
    cross-check of depth against LiDAR can see it; only the car's own odometry can. The LiDAR's returns from the sign
    (beams towards the plate reading within 0.15 m of its distance) move by b along their
    beams; on a beam at bearing a the return's depth along the optical axis moves by
    b cos(a), within 1 cm of b inside the +-8 deg the sign spans at the ranges the braking
    window covers.

    With ``scale_box`` it also injects the camera's colour stream: the sign is drawn smaller
    (or larger), as it would look at the spoofed distance, so a size witness (its box against
    the sign's known size) moves with depth and LiDAR. The defence is then asked with the
    size moved too (``would_pass(size_shift=...)``): the attacker that knows every witness.

    Args: those of ``StealthRamp``; ``scale_box``: also scale the sign in the colour image.
    """

    name = "frustum_spoof"
    needs_simulator = "it moves the sign's returns in the scene (the simulator's geometry)"
    moves_lidar = True

    def __init__(self, env: gym.Env, rate_mps: float = 1.0, direction: int = 1, margin: float = 0.9,
                 region: str = "sign", scale_box: bool = False, **schedule: Any) -> None:
        if not isinstance(scale_box, bool):
            raise ValueError(f"scale_box must be true or false, got {scale_box!r}")
        self.scale_box = self.moves_size = scale_box
        super().__init__(env, rate_mps=rate_mps, direction=direction, margin=margin, region=region, **schedule)
        gym.utils.RecordConstructorArgs.__init__(self, rate_mps=rate_mps, direction=direction, margin=margin,
                                                 region=region, scale_box=scale_box, **schedule)

    def _attack(self, obs: dict, info: dict) -> dict:
        obs = super()._attack(obs, info)  # advances the bias and moves the depth
        ranges = np.array(obs["lidar"], copy=True)
        beams = self.sign_beams(ranges.size)
        on_sign = beams & np.isfinite(ranges) & (np.abs(ranges - self.sign_range_m()) <= SIGN_RETURN_M)
        ranges[on_sign] = np.maximum(ranges[on_sign] + self.bias, 0.0)
        obs["lidar"] = ranges.astype(obs["lidar"].dtype)
        d_true = float(info.get("d_true", np.nan))
        if self.scale_box and np.isfinite(d_true) and d_true + self.bias > 0.05:
            obs["rgb"] = scale_region(obs["rgb"], self.sign_region(info), d_true / (d_true + self.bias))
        return obs
