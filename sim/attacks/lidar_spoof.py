"""``LidarSpoof``: a fake LiDAR return at an attacker-chosen range in the sign's direction."""

from __future__ import annotations

from typing import Any

import gymnasium as gym

from racf.sim.attacks.base import AttackWrapper
from racf.sim.attacks.schedule import AttackSchedule, as_range

__all__ = ["LidarSpoof", "SPOOF_RANGE_M"]

#: The fake range drawn per episode, m: far enough that a repair trusting it would not brake in time.
SPOOF_RANGE_M = (2.5, 3.5)


class LidarSpoof(AttackWrapper):
    """Replaces the beams that hit the sign's plate with returns at ``range_m``.

    Beyond the paper: a spoofed LiDAR agrees with a spoofed depth and defeats a gate
    that trusts the LiDAR.

    Args:
        env: the racf env.
        range_m: the fake range, metres: a value or a (low, high) range drawn per episode
            (default ``SPOOF_RANGE_M``).
        **schedule: ``AttackSchedule`` fields (duration_s, cooldown_s, window_s, stable_steps,
            trigger, ...); its defaults are the protocol's.
    """

    name = "lidar_spoof"
    needs_simulator = "it aims at the sign's beams from the simulator's geometry"

    def __init__(self, env: gym.Env, range_m: Any = SPOOF_RANGE_M, **schedule: Any) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, range_m=range_m, **schedule)
        self.range_bounds = as_range("range_m", range_m, 0.15, 12.0)
        super().__init__(env, AttackSchedule(**schedule))
        self.range_m = self.range_bounds[0]

    def _on_reset(self) -> None:
        self.range_m = float(self.rng.uniform(*self.range_bounds))

    def _attack(self, obs: dict, info: dict) -> dict:
        ranges = obs["lidar"].copy()
        ranges[self.sign_beams(ranges.size)] = self.range_m
        obs["lidar"] = ranges
        return obs
