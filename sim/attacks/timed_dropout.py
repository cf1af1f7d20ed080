"""``TimedDropout``: a depth attack timed to the LiDAR's silence on the target."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from racf.sim.attacks.base import AttackWrapper
from racf.sim.attacks.schedule import AttackSchedule
from racf.sim.sensors import TIMESTAMP_FIELDS

__all__ = ["TimedDropout", "TIMED_EFFECTS"]

#: What the attack does to the depth while it is on.
TIMED_EFFECTS = ("blackout", "bias")
_SCAN_TIME = TIMESTAMP_FIELDS.index("lidar")
#: A return within this of the LiDAR's distance to the sign counts as the sign's, m.
RETURN_TOLERANCE_M = 0.15


class TimedDropout(AttackWrapper):
    """Attacks the sign's depth only while the LiDAR has nothing on the target.

    Black box with the attacker's usual knowledge: it watches the scans the car receives
    and knows where the sign is. It counts the scans in a row with no return from the sign
    (no beam towards the plate reading within 0.15 m of its distance). Once ``scans`` such
    scans have come in a row, with the sign in the camera's view, it attacks the depth in the
    sign's region: ``blackout`` (no return) or ``bias`` (``bias_m`` farther). It stops on the
    first scan with a return from the sign, when a defence could compare the two sensors.
    ``info["attack_active"]`` marks the steps it is on.

    Args:
        env: the racf env.
        scans: empty scans in a row before it starts (1 to 50; the A2M12 scans at 10 Hz).
        effect: ``"blackout"`` or ``"bias"``.
        bias_m: the bias for ``effect="bias"``, m (0 to 5).
        **schedule: ``AttackSchedule`` fields, accepted (and checked) so that it composes with
            the others in a trial; its timing is the LiDAR's silence, not the schedule's.
    """

    name = "dropout_timed"
    needs_simulator = "it aims at the sign's beams from the simulator's geometry"

    def __init__(self, env: gym.Env, scans: int = 3, effect: str = "blackout", bias_m: float = 0.8,
                 **schedule: Any) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, scans=scans, effect=effect, bias_m=bias_m, **schedule)
        if not (isinstance(scans, (int, np.integer)) and not isinstance(scans, bool) and 1 <= scans <= 50):
            raise ValueError(f"scans must be an integer number of LiDAR scans in [1, 50], got {scans!r}")
        if effect not in TIMED_EFFECTS:
            raise ValueError(f"effect must be one of {TIMED_EFFECTS}, got {effect!r}")
        if not (isinstance(bias_m, (int, float)) and 0.0 <= bias_m <= 5.0):
            raise ValueError(f"bias_m must be a number of metres in [0, 5], got {bias_m!r}")
        self.scans, self.effect, self.bias_m = int(scans), effect, float(bias_m)
        super().__init__(env, AttackSchedule(**schedule))
        self.empty_scans = 0
        self._scan_time = -np.inf

    def _on_reset(self) -> None:
        self.empty_scans = 0
        self._scan_time = -np.inf

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        scan_time = float(np.asarray(obs["timestamps"])[_SCAN_TIME])
        if scan_time != self._scan_time:
            self._scan_time = scan_time
            self.empty_scans = 0 if self._sign_returns(obs["lidar"]) else self.empty_scans + 1
        was_active = self.active
        self.active = self.empty_scans >= self.scans and bool(info.get("sign_in_view", False))
        if self.active:
            # Its windows, as a schedule keeps them (the runner reports the first).
            t = float(info["time"])
            windows = self.schedule.windows
            if was_active and windows:
                windows[-1] = (windows[-1][0], t)
            else:
                windows.append((t, t))
            obs = self._attack(dict(obs), info)
        return obs, reward, terminated, truncated, self._mark(info)

    def _sign_returns(self, ranges: np.ndarray) -> bool:
        """Whether a beam towards the plate reads about the LiDAR's distance to the sign."""
        ranges = np.asarray(ranges, float)
        beams = self.sign_beams(ranges.size)
        return bool((np.abs(ranges[beams] - self.sign_range_m()) <= RETURN_TOLERANCE_M).any())

    def _attack(self, obs: dict, info: dict) -> dict:
        depth = obs["depth"].copy()
        plane = depth[..., 0]
        where = self.sign_region(info, 1) & (plane > 0)
        plane[where] = 0.0 if self.effect == "blackout" else plane[where] + self.bias_m
        obs["depth"] = depth
        return obs
