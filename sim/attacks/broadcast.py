"""Attacks on the car ahead's broadcast (``racf.sim.radio``), as the V2X security literature poses them:

- ``radio_jam``: every message lost while the attack is on (a jammer on the channel);
- ``radio_delay``: every message held ``delay_s`` before it is let through (a relay that holds them; what
  it still holds when the attack ends is lost);
- ``radio_replay``: the attacker records the lead's messages and sends each again ``age_s`` later, beside
  the lead's own (valid signatures, old sequence numbers and timestamps);
- ``radio_forge``: messages in the lead's name saying it is ``ahead_m`` farther and ``faster_mps`` faster,
  at the lead's rate and numbered past its own, signed with a key outside the fleet (the attacker
  has none in it);
- ``radio_lie``: an insider: the lead itself, with its own valid key, says it is ``faster_mps`` faster and,
  with ``rate_mps``, farther by a move grown at that rate up to ``bias_m`` (``lead_frustum``'s adaptive
  spoof's story, told over the radio too when the two attacks run together);
- ``radio_stolen_key``: an attacker with one fleet vehicle's stolen key (``vehicle``) says that vehicle
  stands ``ahead_m`` ahead of the car on its lane, at the radio's rate. Its messages pass every check
  the car can make: what it can do is what a broadcast alone can do, which the car's stages bound by
  taking the more cautious of it and their sensors (a phantom ahead slows or stops the car: needless
  stops, never a bolder car).

An attack that needs a fleet key is an insider and is handed one vehicle's key by the world, by name
(``FleetKeys.hand_over``); no key can be made from anything public.

They act from ``start_s`` for the episode's ``t_atk`` (``trigger="at_time"``, as the lead attacks do) and
count what they put on the air that is not the lead's own (``info["radio_injected"]``: forged and replayed
messages; an insider's lie is the lead's own message, signed by it).
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import gymnasium as gym
import numpy as np
from nacl.signing import SigningKey

from racf.sim.attacks.lead import _LeadAttack
from racf.sim.radio import FLEET, RADIO_SLOTS, SIGNED_BYTES, Broadcast, V2VMessage, sign
from racf.sim.radio.message import parse
from racf.vehicle import QCAR2_BOX_M

__all__ = ["RadioJam", "RadioDelay", "RadioReplay", "RadioForge", "RadioLie", "RadioStolenKey"]


def _check(name: str, value: Any, lo: float, hi: float, low_open: bool = False) -> None:
    """ValueError naming ``name`` unless ``value`` is a number in [lo, hi] (``low_open``: (lo, hi])."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not (
            (lo < value if low_open else lo <= value) and value <= hi):
        raise ValueError(f"{name} must be in {'(' if low_open else '['}{lo:g}, {hi:g}], got {value!r}")


def _rows(obs: dict) -> list[tuple[float, bytes]]:
    """The step's received messages: (arrival time, bytes), empty slots left out."""
    rows = np.asarray(obs["radio"], np.uint8).reshape(-1, SIGNED_BYTES)
    times = np.asarray(obs["radio_times"], float)
    return [(float(t), row.tobytes()) for row, t in zip(rows, times) if row.any()]


def _put(obs: dict, messages: list[tuple[float, bytes]]) -> dict:
    """``obs`` with its radio rows replaced by ``messages`` (the first ``RADIO_SLOTS``)."""
    rows = np.zeros((RADIO_SLOTS, SIGNED_BYTES), np.uint8)
    times = np.zeros(RADIO_SLOTS, np.float64)
    for i, (t, raw) in enumerate(messages[:RADIO_SLOTS]):
        rows[i] = np.frombuffer(raw.ljust(SIGNED_BYTES, b"\0")[:SIGNED_BYTES], np.uint8)
        times[i] = t
    return {**obs, "radio": rows.reshape(-1), "radio_times": times}


class _RadioAttack(_LeadAttack):
    """An attack on the radio: it listens on every step and acts on the ``radio`` rows while active."""

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        now = float(info["time"])
        self.info = info  # what an attacker by the road sees of the car (its pose), for the attacks that need it
        self._overhear(obs, now)
        self.active = self.schedule.update(info)
        obs, injected = self._radio(dict(obs), now, self.active)
        info = self._mark(info)
        info["radio_injected"] = int(info.get("radio_injected", 0)) + injected
        return obs, reward, terminated, truncated, info

    def _overhear(self, obs: dict, now: float) -> None:
        """What the attacker records of the genuine traffic (on every step, active or not)."""

    def _radio(self, obs: dict, now: float, active: bool) -> tuple[dict, int]:
        """The rows the car gets and how many messages the attacker put on the air this step."""
        raise NotImplementedError

    def _attack(self, obs: dict, info: dict) -> dict:  # the radio attacks act in step()
        return obs


class RadioJam(_RadioAttack):
    """Every message lost while the attack is on."""

    name = "radio_jam"

    def __init__(self, env: gym.Env, **schedule: Any) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, **schedule)
        super().__init__(env, **schedule)

    def _radio(self, obs, now, active):
        return (_put(obs, []) if active else obs), 0


class RadioDelay(_RadioAttack):
    """Every message held ``delay_s`` while the attack is on and let through when due (lost if the attack
    ends first)."""

    name = "radio_delay"

    def __init__(self, env: gym.Env, delay_s: float = 0.5, **schedule: Any) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, delay_s=delay_s, **schedule)
        _check("delay_s", delay_s, 0.0, 10.0, low_open=True)
        self.delay_s = float(delay_s)
        self._held: list[tuple[float, bytes]] = []
        super().__init__(env, **schedule)

    def _on_reset(self) -> None:
        self._held = []

    def _radio(self, obs, now, active):
        if not active:
            self._held = []
            return obs, 0
        self._held += [(t + self.delay_s, raw) for t, raw in _rows(obs)]
        due = [(now, raw) for t, raw in self._held if t <= now + 1e-9]
        self._held = [(t, raw) for t, raw in self._held if t > now + 1e-9]
        return _put(obs, due), 0


class RadioReplay(_RadioAttack):
    """The lead's messages recorded and each sent again ``age_s`` after it first arrived, beside the lead's own."""

    name = "radio_replay"

    def __init__(self, env: gym.Env, age_s: float = 1.0, **schedule: Any) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, age_s=age_s, **schedule)
        _check("age_s", age_s, 0.0, 30.0, low_open=True)
        self.age_s = float(age_s)
        self._tape: list[tuple[float, bytes]] = []
        super().__init__(env, **schedule)

    def _on_reset(self) -> None:
        self._tape = []

    def _overhear(self, obs, now):
        self._tape += _rows(obs)

    def _radio(self, obs, now, active):
        due = [(now, raw) for t, raw in self._tape if t + self.age_s <= now + 1e-9]
        self._tape = [(t, raw) for t, raw in self._tape if t + self.age_s > now + 1e-9]
        if not active:
            return obs, 0
        return _put(obs, _rows(obs) + due), len(due[:max(RADIO_SLOTS - len(_rows(obs)), 0)])


class RadioForge(_RadioAttack):
    """Messages in the lead's name, ``ahead_m`` farther and ``faster_mps`` faster than its last, signed
    with a key outside the fleet, at the lead's rate and numbered past its own."""

    name = "radio_forge"

    def __init__(self, env: gym.Env, ahead_m: float = 2.0, faster_mps: float = 1.0, **schedule: Any) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, ahead_m=ahead_m, faster_mps=faster_mps, **schedule)
        _check("ahead_m", ahead_m, -10.0, 10.0)
        _check("faster_mps", faster_mps, -10.0, 10.0)
        self.ahead_m, self.faster_mps = float(ahead_m), float(faster_mps)
        self._last: V2VMessage | None = None
        self._key = SigningKey(bytes(32))
        super().__init__(env, **schedule)

    def _on_reset(self) -> None:
        self._last = None
        self._key = SigningKey(self.rng.bytes(32))  # the attacker's own: in no car's trust store

    def _overhear(self, obs, now):
        for _, raw in _rows(obs):
            message = parse(raw)
            if message is not None:
                self._last = message

    def _radio(self, obs, now, active):
        last = self._last
        if not active or last is None or not _rows(obs):  # it speaks when the lead does, to be taken for it
            return obs, 0
        s = last.state
        said = replace(s, x_m=s.x_m + self.ahead_m * math.cos(s.yaw_rad), y_m=s.y_m + self.ahead_m * math.sin(s.yaw_rad),
                       speed_mps=s.speed_mps + self.faster_mps, braking=False)
        forged = sign(V2VMessage(last.seq + 1, now, said), self._key)
        return _put(obs, [(now, forged)] + _rows(obs)), 1


class RadioLie(_RadioAttack):
    """The lead, with its own key, says it is ``faster_mps`` faster and farther by ``min(rate_mps t, bias_m)``
    (t from the attack's start; ``rate_mps`` 0: the whole ``bias_m`` at once)."""

    name = "radio_lie"

    def __init__(self, env: gym.Env, faster_mps: float = 0.5, bias_m: float = 0.0, rate_mps: float = 0.0,
                 **schedule: Any) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, faster_mps=faster_mps, bias_m=bias_m, rate_mps=rate_mps,
                                                 **schedule)
        _check("faster_mps", faster_mps, -5.0, 5.0)
        _check("bias_m", bias_m, -10.0, 10.0)
        _check("rate_mps", rate_mps, 0.0, 10.0)
        self.faster_mps, self.bias_m, self.rate_mps = float(faster_mps), float(bias_m), float(rate_mps)
        self._keys: dict = {}
        super().__init__(env, **schedule)

    def _on_reset(self) -> None:
        self._keys = {}  # the lead's own key, handed over by the world when it first speaks

    def moved_m(self, now: float) -> float:
        """How much farther the lead says it is now, m."""
        if self.rate_mps == 0.0:
            return self.bias_m
        return min(self.rate_mps * (now - self.schedule.windows[-1][0]), self.bias_m)

    def _radio(self, obs, now, active):
        if not active:
            return obs, 0
        out = []
        for t, raw in _rows(obs):
            message = parse(raw)
            if message is None:
                out.append((t, raw))
                continue
            s, ahead = message.state, self.moved_m(now)
            said = replace(s, x_m=s.x_m + ahead * math.cos(s.yaw_rad), y_m=s.y_m + ahead * math.sin(s.yaw_rad),
                           speed_mps=max(s.speed_mps + self.faster_mps, 0.0))
            if s.sender not in self._keys:
                self._keys[s.sender] = self.unwrapped.radio.fleet.hand_over(s.sender)
            out.append((t, sign(replace(message, state=said), self._keys[s.sender])))
        return _put(obs, out), 0


class RadioStolenKey(_RadioAttack):
    """With vehicle ``vehicle``'s stolen key, that vehicle said to stand ``ahead_m`` ahead of the car on its
    lane, at the radio's rate (see the module: what a key alone can do)."""

    name = "radio_stolen_key"

    def __init__(self, env: gym.Env, vehicle: int = 5, ahead_m: float = 0.6, **schedule: Any) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, vehicle=vehicle, ahead_m=ahead_m, **schedule)
        if isinstance(vehicle, bool) or not isinstance(vehicle, int) or vehicle not in FLEET:
            raise ValueError(f"vehicle must be one of the fleet's {FLEET}, got {vehicle!r}")
        _check("ahead_m", ahead_m, 0.0, 10.0)
        self.vehicle, self.ahead_m = vehicle, float(ahead_m)
        self._key = None
        self._seq = 0
        self._next_s = 0.0
        super().__init__(env, **schedule)

    def _on_reset(self) -> None:
        self._key = self.unwrapped.radio.fleet.hand_over(self.vehicle)
        self._seq, self._next_s = 0, 0.0

    def _radio(self, obs, now, active):
        if not active or now + 1e-9 < self._next_s:
            return obs, 0
        self._next_s = now + 1.0 / self.unwrapped.radio.config.hz
        x, y, yaw = (float(v) for v in self.info["pose"])
        # The car's front is half a car ahead of its origin; the phantom's origin half a car past its rear.
        ahead = QCAR2_BOX_M[0] + self.ahead_m
        said = Broadcast(self.vehicle, x + ahead * math.cos(yaw), y + ahead * math.sin(yaw), yaw, 0.0, 0.0, True)
        self._seq += 1
        forged = sign(V2VMessage(self._seq, now, said), self._key)
        return _put(obs, [(now, forged)] + _rows(obs)), 1
