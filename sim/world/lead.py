"""The car ahead: a second QCar 2 driving the ego car's own lane with a speed profile.

Like cross-traffic (``racf.sim.world.traffic``) the lead car is kinematic: a pure function of
time, tabulated once per episode, the same to the millisecond on every machine, and it reads
nothing of the ego car. Its profile is one of:

- ``cruise``: it holds ``speed_mps``;
- ``slow_down``: at ``brake_t_s`` it slows to half its speed at ``decel_mps2`` and holds that;
- ``hard_brake``: at ``brake_t_s`` it brakes at ``decel_mps2`` to a stop and stays there;
- ``stop_and_go``: at ``brake_t_s`` it brakes at ``decel_mps2`` to a stop, waits ``STOP_AND_GO_WAIT_S``
  and pulls away again at ``LAUNCH_MPS2``.

Whatever the profile, it obeys the road: it comes to rest at ``stop_s`` (the stop line of the
ego car's sign, which faces it too) braking at ``TRAFFIC_BRAKE_MPS2``, and stays there.
Pure numpy: nothing here knows MuJoCo.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np

from racf.sim.world.traffic import TRAFFIC_BRAKE_MPS2, TRAFFIC_COLOURS, _route_path, _unwrapped_headings

__all__ = ["LeadCar", "LEAD_PROFILES", "STOP_AND_GO_WAIT_S", "LAUNCH_MPS2"]

#: The lead's speed profiles.
LEAD_PROFILES = ("cruise", "slow_down", "hard_brake", "stop_and_go")
#: How long a stop-and-go lead stands before it pulls away, s.
STOP_AND_GO_WAIT_S = 1.5
#: How hard it pulls away, m/s^2 (a gentle launch of the 1/10 car).
LAUNCH_MPS2 = 1.0
#: The grid the profile is integrated on, s (the physics step's order: 2 ms).
_DT_S = 0.002


@dataclass(frozen=True)
class LeadCar:
    """The car ahead.

    Attributes:
        route: its road-graph nodes (the ego car's).
        start_s: where its body origin is at t = 0 along the route's path, m.
        speed_mps: its cruise speed.
        stop_s: where it comes to rest for good (the stop line ahead of it), m.
        profile: one of ``LEAD_PROFILES``.
        decel_mps2: how hard it brakes at ``brake_t_s``.
        brake_t_s: when it brakes, s after the start.
        colour: a ``TRAFFIC_COLOURS`` name.
    """

    route: tuple[int, ...]
    start_s: float
    speed_mps: float
    stop_s: float
    profile: str = "hard_brake"
    decel_mps2: float = 3.0
    brake_t_s: float = 3.0
    colour: str = "white"

    def __post_init__(self) -> None:
        if self.profile not in LEAD_PROFILES:
            raise ValueError(f"profile must be one of {LEAD_PROFILES}, got {self.profile!r}")
        if self.colour not in TRAFFIC_COLOURS:
            raise ValueError(f"colour must be one of {tuple(TRAFFIC_COLOURS)}, got {self.colour!r}")
        for name, lo, hi in (("speed_mps", 0.0, 3.0), ("decel_mps2", 0.1, 8.0), ("brake_t_s", 0.0, 60.0)):
            value = getattr(self, name)
            if not (isinstance(value, numbers.Real) and lo <= value <= hi):
                raise ValueError(f"{name} must be in [{lo}, {hi}], got {value!r}")
        length = _route_path(self.route).length
        if not (0.0 <= self.start_s <= self.stop_s <= length + 1e-9):
            raise ValueError(f"need 0 <= start_s <= stop_s <= {length:.2f} m (the route's length), "
                             f"got start_s={self.start_s!r}, stop_s={self.stop_s!r}")

    def wanted_mps(self, t: np.ndarray) -> np.ndarray:
        """The speed its profile asks for at each of ``t`` (s), before the road's stop line."""
        v, a, tb = self.speed_mps, self.decel_mps2, self.brake_t_s
        after = np.clip(t - tb, 0.0, None)
        if self.profile == "cruise":
            return np.full_like(t, v)
        if self.profile == "slow_down":
            return np.maximum(v - a * after, 0.5 * v)
        braking = np.maximum(v - a * after, 0.0)
        if self.profile == "hard_brake":
            return braking
        t_go = tb + v / a + STOP_AND_GO_WAIT_S  # stop_and_go
        return np.where(t < t_go, braking, np.minimum(LAUNCH_MPS2 * (t - t_go), v))

    def profile_at(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(arclength m, speed m/s) at each of ``times`` (s): the profile's speed, capped by what still
        stops it at ``stop_s`` at ``TRAFFIC_BRAKE_MPS2``, integrated on a 2 ms grid."""
        times = np.asarray(times, float)
        horizon = float(np.max(times, initial=0.0))
        grid = np.arange(0.0, horizon + 2 * _DT_S, _DT_S)
        wanted = self.wanted_mps(grid)
        s = np.empty_like(grid)
        v = np.empty_like(grid)
        pos = self.start_s
        for i, w in enumerate(wanted):  # the stop line's cap depends on where it is: a forward pass
            room = max(self.stop_s - pos, 0.0)
            v[i] = min(w, math.sqrt(2 * TRAFFIC_BRAKE_MPS2 * room))
            s[i] = pos
            pos = min(pos + v[i] * _DT_S, self.stop_s)
        return np.interp(times, grid, s), np.interp(times, grid, v)

    def states(self, times: np.ndarray) -> np.ndarray:
        """(n, 4) x, y, yaw, speed at each of ``times`` (s)."""
        s, v = self.profile_at(times)
        path = _route_path(self.route)
        yaw = np.interp(s, path.arclength, _unwrapped_headings(self.route))
        return np.column_stack([np.interp(s, path.arclength, path.points[:, 0]),
                                np.interp(s, path.arclength, path.points[:, 1]),
                                (yaw + np.pi) % (2 * np.pi) - np.pi, v])

    def to_options(self) -> dict:
        """The env's reset option ``lead``."""
        return {"route": list(self.route), "start_s_m": self.start_s, "speed_mps": self.speed_mps,
                "stop_s_m": self.stop_s, "profile": self.profile, "decel_mps2": self.decel_mps2,
                "brake_t_s": self.brake_t_s, "colour": self.colour}

    @classmethod
    def from_options(cls, raw: object) -> "LeadCar":
        """A lead car from its reset option; ValueError names what is wrong."""
        keys = {"route", "start_s_m", "speed_mps", "stop_s_m", "profile", "decel_mps2", "brake_t_s", "colour"}
        if not isinstance(raw, dict) or set(raw) != keys:
            raise ValueError(f"options['lead'] must be a dict with exactly {sorted(keys)}, got {raw!r}")
        route = raw["route"]
        if isinstance(route, (str, bytes)) or not all(isinstance(n, numbers.Integral) for n in route):
            raise ValueError(f"the lead's route must be road-graph node ids, got {route!r}")
        return cls(tuple(int(n) for n in route), float(raw["start_s_m"]), float(raw["speed_mps"]),
                   float(raw["stop_s_m"]), str(raw["profile"]), float(raw["decel_mps2"]),
                   float(raw["brake_t_s"]), str(raw["colour"]))
