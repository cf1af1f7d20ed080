"""The car's radio receiver: the fleet's signed broadcasts checked, and the car ahead as they tell it.

A broadcast is a witness the sensor attacker does not reach: what the car ahead says of itself
(:mod:`racf.sim.radio`), signed with its fleet key. The car trusts nothing it is sent
(DeBruhl et al., WiSec 2015; IEEE 1609.2's checks), so a message counts only when (each refusal
named by :data:`racf.sim.radio.message.REFUSALS`):

1. it parses and names a vehicle whose public key the car was provisioned with, and that key
   verifies its signature (else ``malformed``, ``unknown sender``, ``bad signature``);
2. it is numbered past the sender's last accepted message and stamped later (else ``replayed``), by
   no more numbers than the sender can have sent since (:data:`MAX_HZ` a second, and
   :data:`SEQ_SLACK`; else ``out of window``): one message numbered 2^32 - 1 once locked the genuine
   sender out for the rest of the episode (IPsec's and DTLS's anti-replay windows bound it so);
3. it is fresh: sent no more than ``max_age_s`` before it is read, nor more than :data:`FUTURE_S`
   after (else ``stale``): one check, one bound, here and where a message is used.

A sender whose last accepted message is no longer fresh starts again with its next one (a sender
that restarted, or one a forged number once put ahead: it is shut out for ``max_age_s`` at most).

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

from racf.sim.radio import SIGNED_BYTES, V2VMessage, open_signed
from racf.sim.radio.message import REFUSALS
from racf.sim.world.manager import QCAR2_BOX_M

__all__ = ["BroadcastReceiver", "BroadcastWitness", "REFUSALS", "MAX_AGE_S", "MAX_HZ", "SEQ_SLACK", "fresh"]

#: A message older than this when read is stale, s (three of a 10 Hz sender's periods).
MAX_AGE_S = 0.3
#: A message stamped later than now by more than this is refused too, s (clocks differ a little).
FUTURE_S = 0.05
#: The most messages a second a sender numbers (ETSI's highest rate for awareness messages is 10 Hz).
MAX_HZ = 50.0
#: And how many more a message may be numbered past the last than that rate allows (lost ones, jitter).
SEQ_SLACK = 8


def fresh(age_s: float, max_age_s: float = MAX_AGE_S) -> bool:
    """Whether a message ``age_s`` old (negative: stamped in the future) may be used: the one age check."""
    return -FUTURE_S <= age_s <= max_age_s
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
        trusted: sender -> public key: the fleet's public keys the car was provisioned with (none: it
            trusts no broadcast).
        max_age_s: the oldest a message may be when read.
    """

    def __init__(self, trusted: dict | None = None, max_age_s: float = MAX_AGE_S) -> None:
        self.trusted = dict(trusted or {})
        self.max_age_s = float(max_age_s)
        self.reset()

    def reset(self) -> None:
        self.last: dict[int, V2VMessage] = {}
        self.accepted = 0
        self.refused = dict.fromkeys(REFUSALS, 0)
        self.slots = 0  # which of the last step's radio slots it accepted (a bit mask)

    def hear(self, obs: dict, now_s: float) -> list[V2VMessage]:
        """The messages of this step's observation that pass every check (each refusal counted)."""
        rows, times = obs.get("radio"), obs.get("radio_times")
        if rows is None or times is None:
            return []
        out = []
        self.slots = 0
        for slot, row in enumerate(np.asarray(rows, np.uint8).reshape(-1, SIGNED_BYTES)):
            if not row.any():
                continue  # an empty slot
            opened = open_signed(row.tobytes(), self.trusted)
            message = opened.message
            why = opened.refused if message is None else self._order(message, now_s)
            if why:
                self.refused[why] += 1
                continue
            self.last[message.state.sender] = message
            self.accepted += 1
            self.slots |= 1 << slot
            out.append(message)
        return out

    def _order(self, message: V2VMessage, now_s: float) -> str:
        """Why a verified message is refused by its number and time, or its age ("": it is not)."""
        last = self.last.get(message.state.sender)
        if last is not None and fresh(now_s - last.t_s, self.max_age_s):  # else it starts the sender again
            if message.seq <= last.seq or message.t_s <= last.t_s:
                return "replayed"
            if message.seq - last.seq > math.ceil((message.t_s - last.t_s) * MAX_HZ) + SEQ_SLACK:
                return "out of window"
        return "" if fresh(now_s - message.t_s, self.max_age_s) else "stale"

    def witness(self, now_s: float, pose: np.ndarray, camera_xy_m: tuple[float, float], path, progress_m: float
                ) -> BroadcastWitness | None:
        """The nearest car ahead on the lane (``path``, the car at ``progress_m`` along it) as the trusted
        messages tell it (None: none fresh, or none ahead on the lane)."""
        best = None
        for message in self.last.values():
            age = now_s - message.t_s
            if not fresh(age, self.max_age_s):
                continue
            said = _ahead(message, max(age, 0.0), pose, camera_xy_m, path, progress_m)
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
