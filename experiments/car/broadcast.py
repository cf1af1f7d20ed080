"""The car's radio receiver: the fleet's signed broadcasts checked, and the car ahead as they tell it.

A broadcast is a witness the sensor attacker does not reach: what the car ahead says of itself
(:mod:`racf.sim.radio`), signed with its fleet key. The car trusts nothing it is sent
(DeBruhl et al., WiSec 2015; IEEE 1609.2's checks), so a message counts only when:

1. it parses and names a vehicle in the car's trust store, whose key verifies its signature
   (else ``forged``: an attacker outside the fleet, or a message changed on the air);
2. its sequence number is past the sender's last accepted one (else ``replayed``);
3. it was sent no more than ``max_age_s`` before it is read, and not in the future (else ``stale``:
   a message held back, or a clock that lies).

The last accepted message, moved on to now by its own speed and acceleration, gives the lead's
distance from the camera to its rear (from the car's own pose estimate; on a straight lane what the
depth and the LiDAR measure, in a bend the chord, which they no longer see) and its speed, where the
map puts it on the car's own lane ahead: :class:`BroadcastWitness`. An insider (a fleet vehicle that lies with its own key)
passes every check; the stages that use the witness take the more cautious of it and their sensors,
so a lie alone cannot make the car bolder than its sensors allow.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from racf.sim.radio import SIGNED_BYTES, V2VMessage, open_signed, trust_store
from racf.sim.world.manager import QCAR2_BOX_M

__all__ = ["BroadcastReceiver", "BroadcastWitness", "REFUSALS", "MAX_AGE_S"]

#: Why a message is refused, in the order the checks run.
REFUSALS = ("forged", "replayed", "stale")
#: A message older than this when read is stale, s (three of a 10 Hz sender's periods).
MAX_AGE_S = 0.3
#: A message stamped later than now by more than this is refused too, s (clocks differ a little).
FUTURE_S = 0.05
#: The lead must stand this close to the car's lane to be the car ahead, m (half a lane).
LANE_HALF_M = 0.3
#: And no farther ahead along it than this, m.
AHEAD_MAX_M = 6.0
#: The broadcast's error the car allows for when it compares it with its sensors, m (the lead's and the
#: car's own localisation, a few centimetres each, and the latency's prediction).
AGREE_M = 0.2
#: The same for the lead's speed, m/s.
SPEED_AGREE_MPS = 0.2


@dataclass(frozen=True)
class BroadcastWitness:
    """The car ahead as its broadcast tells it, now.

    Attributes:
        distance_m: from the camera to its rear, along the camera's axis, m.
        speed_mps: its speed, m/s.
        age_s: how old the message it comes from is, s.
    """

    distance_m: float
    speed_mps: float
    age_s: float


class BroadcastReceiver:
    """Checks each step's ``radio`` rows and keeps the last message each trusted sender sent.

    Args:
        trusted: sender -> public key (default: the fleet's, ``racf.sim.radio.trust_store``).
        max_age_s: the oldest a message may be when read.
    """

    def __init__(self, trusted: dict | None = None, max_age_s: float = MAX_AGE_S) -> None:
        self.trusted = trusted if trusted is not None else trust_store()
        self.max_age_s = float(max_age_s)
        self.reset()

    def reset(self) -> None:
        self.last: dict[int, V2VMessage] = {}
        self.accepted = 0
        self.refused = dict.fromkeys(REFUSALS, 0)

    def hear(self, obs: dict, now_s: float) -> list[V2VMessage]:
        """The messages of this step's observation that pass every check (each refusal counted)."""
        rows, times = obs.get("radio"), obs.get("radio_times")
        if rows is None or times is None:
            return []
        out = []
        for row in np.asarray(rows, np.uint8).reshape(-1, SIGNED_BYTES):
            if not row.any():
                continue  # an empty slot
            opened = open_signed(row.tobytes(), self.trusted)
            message = opened.message
            if message is None:
                self.refused["forged"] += 1
                continue
            sender = message.state.sender
            if sender in self.last and message.seq <= self.last[sender].seq:
                self.refused["replayed"] += 1
                continue
            if not -FUTURE_S <= now_s - message.t_s <= self.max_age_s:
                self.refused["stale"] += 1
                continue
            self.last[sender] = message
            self.accepted += 1
            out.append(message)
        return out

    def witness(self, now_s: float, pose: np.ndarray, camera_xy_m: tuple[float, float], path, progress_m: float
                ) -> BroadcastWitness | None:
        """The nearest car ahead on the lane (``path``, the car at ``progress_m`` along it) as the trusted
        messages tell it (None: none fresh, or none ahead on the lane)."""
        best = None
        for message in self.last.values():
            age = now_s - message.t_s
            if not 0.0 <= age <= self.max_age_s:
                continue
            said = _ahead(message, age, pose, camera_xy_m, path, progress_m)
            if said is not None and (best is None or said.distance_m < best.distance_m):
                best = said
        return best


def _ahead(message: V2VMessage, age_s: float, pose: np.ndarray, camera_xy_m: tuple[float, float], path,
           progress_m: float) -> BroadcastWitness | None:
    """Where the sender's rear is now (moved on ``age_s`` by its own speed and acceleration), from the camera."""
    s = message.state
    v, a = max(s.speed_mps, 0.0), s.accel_mps2
    speed = max(v + a * age_s, 0.0)
    # Braking to a stop within the age, it goes v^2 / 2|a| and stays; else v t + a t^2 / 2.
    travel = v * v / (-2.0 * a) if speed == 0.0 and a < 0.0 else v * age_s + 0.5 * a * age_s ** 2
    rear = QCAR2_BOX_M[0] / 2.0
    x = s.x_m + (travel - rear) * math.cos(s.yaw_rad)
    y = s.y_m + (travel - rear) * math.sin(s.yaw_rad)
    px, py, yaw = (float(p) for p in pose[:3])
    c, n = math.cos(yaw), math.sin(yaw)
    cx, cy = px + c * camera_xy_m[0] - n * camera_xy_m[1], py + n * camera_xy_m[0] + c * camera_xy_m[1]
    along, aside = path.project(np.array([x, y]), s_hint=progress_m + AHEAD_MAX_M / 2, window_m=AHEAD_MAX_M / 2)
    ahead = (x - cx) * c + (y - cy) * n
    # (the search ends AHEAD_MAX_M on: a sender beyond it projects onto the window's end, and is none)
    if not progress_m < along < progress_m + AHEAD_MAX_M or ahead <= 0.0 or abs(aside) > LANE_HALF_M:
        return None
    return BroadcastWitness(math.hypot(x - cx, y - cy), speed, age_s)
