"""``StealthRamp``: a depth bias that grows as fast as the defence lets it, and no faster."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from sim.attacks._common import check_region
from sim.attacks.base import AttackWrapper
from sim.attacks.schedule import AttackSchedule

__all__ = ["StealthRamp", "per_step_tolerance"]


def per_step_tolerance(defence: Any) -> float:
    """How far the depth may move in one step, beyond the car's motion, without the defence
    flagging it, m; inf for a defence with no such test (raw depth, the EKF, Chronos-only).

    ODCA re-anchors its kinematic branch on every depth that passes, so a depth passes while
    each step's change stays within the tolerance of a freshly anchored branch.
    """
    config = getattr(getattr(defence, "model", None), "config", None)
    if config is None or not hasattr(config, "step_bound_m"):
        return float("inf")
    return float(config.step_bound_m)


class StealthRamp(AttackWrapper):
    """Adds a bias to the sign's depth that grows at ``rate_mps``, capped per step below the
    defence's own tolerance, so the gate never opens.

    White box: it reads the defence's thresholds (``attach_defence``; the runner hands it the
    car's estimator). Against a defence with no per-step test the ramp is uncapped. Each
    step's increment is at most ``margin`` x the tolerance (``per_step_tolerance``), and
    ``max_step_m`` holds the cap in force.

    Args:
        env: the racf env.
        rate_mps: how fast the bias grows, m/s (0 to 20).
        direction: ``+1`` (farther: the dangerous case) or ``-1``.
        margin: the share of the tolerance it uses per step (0 to 1).
        region: ``"sign"`` or ``"frame"``.
        **schedule: ``AttackSchedule`` fields; its defaults are the protocol's.
    """

    name = "stealth_ramp"
    threat_model = "white box"

    def __init__(self, env: gym.Env, rate_mps: float = 1.0, direction: int = 1, margin: float = 0.9,
                 region: str = "sign", **schedule: Any) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, rate_mps=rate_mps, direction=direction, margin=margin,
                                                 region=region, **schedule)
        if not (isinstance(rate_mps, (int, float)) and 0.0 <= rate_mps <= 20.0):
            raise ValueError(f"rate_mps must be a number of m/s in [0, 20], got {rate_mps!r}")
        if direction not in (-1, 1):
            raise ValueError(f"direction must be -1 or 1, got {direction!r}")
        if not (isinstance(margin, (int, float)) and 0.0 < margin <= 1.0):
            raise ValueError(f"margin must be in (0, 1], got {margin!r}")
        self.rate_mps, self.direction, self.margin = float(rate_mps), int(direction), float(margin)
        self.region = check_region(region)
        super().__init__(env, AttackSchedule(**schedule))
        self.bias = 0.0
        self._last_time: float | None = None

    @property
    def max_step_m(self) -> float:
        """The largest increment of the bias in one step against the attached defence, m."""
        return self.margin * per_step_tolerance(self.defence)

    def _on_reset(self) -> None:
        self.bias = 0.0
        self._last_time = None

    def _attack(self, obs: dict, info: dict) -> dict:
        t = float(info["time"])
        dt = t - self._last_time if self._last_time is not None else 0.0
        self._last_time = t
        self.bias += self.direction * min(self.rate_mps * dt, self.max_step_m)
        depth = obs["depth"].copy()
        plane = depth[..., 0]
        where = (plane > 0) & (self.sign_region(info, 1) if self.region == "sign" else True)
        shifted = plane[where] + self.bias
        plane[where] = np.where(shifted > 0, shifted, 0.0).astype(depth.dtype)
        obs["depth"] = depth
        return obs
