"""``ConfidenceDegradation``: depth dropout and heavy noise on the sign, lowering c~."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from racf.sim.attacks.base import AttackWrapper
from racf.sim.attacks.schedule import AttackSchedule

__all__ = ["ConfidenceDegradation"]


class ConfidenceDegradation(AttackWrapper):
    """Removes a share ``1 - confidence_multiplier`` of the sign's valid depth pixels and adds
    Gaussian noise of ``noise_std_m`` to the rest.

    The pipeline's confidence is detection confidence x valid-pixel share, so it falls by
    about ``confidence_multiplier``; the noise perturbs the median (the protocol's
    "confidence degradation with heavy noise").

    Args:
        env: the racf env.
        confidence_multiplier: in [0, 1].
        noise_std_m: >= 0, metres.
        **schedule: ``AttackSchedule`` fields (duration_s, cooldown_s, window_s, stable_steps,
            trigger, ...); its defaults are the protocol's.
    """

    name = "confidence_degradation"

    def __init__(self, env: gym.Env, confidence_multiplier: float = 0.3, noise_std_m: float = 0.10,
                 **schedule: Any) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, confidence_multiplier=confidence_multiplier,
                                                 noise_std_m=noise_std_m, **schedule)
        if not 0.0 <= confidence_multiplier <= 1.0:
            raise ValueError(f"confidence_multiplier must be in [0, 1], got {confidence_multiplier!r}")
        if not 0.0 <= noise_std_m <= 10.0:
            raise ValueError(f"noise_std_m must be in [0, 10] m, got {noise_std_m!r}")
        self.confidence_multiplier, self.noise_std_m = float(confidence_multiplier), float(noise_std_m)
        super().__init__(env, AttackSchedule(**schedule))

    def _attack(self, obs: dict, info: dict) -> dict:
        depth = obs["depth"].copy()
        plane = depth[..., 0]  # (H, W) view of the (H, W, 1) image, like the sign's region
        rows, cols = np.nonzero(self.sign_region(info, 1) & (plane > 0))
        if rows.size:
            drop = self.rng.random(rows.size) >= self.confidence_multiplier
            noisy = plane[rows, cols] + self.rng.normal(0.0, self.noise_std_m, rows.size)
            plane[rows, cols] = np.where(drop | (noisy <= 0), 0.0, noisy).astype(depth.dtype)
        obs["depth"] = depth
        return obs
