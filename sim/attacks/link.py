"""Attacks on the link between the car and its defence service (``racf serve``), not on its sensors.

The paper's car sent its perception offboard and braked on the answer: whoever sits on that
network can slow, lose or replace the answers. Each attack here is a man in the middle on the
service's TCP connection (``racf.experiments.link.relay`` puts it there when a spec names
one) that sees ZeroMQ's frames as they pass:

- ``link_delay``: holds each answer ``delay_ms`` (± ``jitter_ms``, drawn per answer);
- ``link_drop``: loses each answer with probability ``rate``;
- ``link_spoof``: answers the attacker's distance ``distance_m`` instead of the service's.

On a plain link the frames are readable and a spoofed distance reaches the car. On a CurveZMQ
link (``racf serve keys``) every answer is encrypted and authenticated: the attacker can still
hold or lose them (it sees their boundaries), but a forged one fails the car's check, the car
drops the connection and falls back to its own depth distance, and it logs the refusal.
They act on the protocol's schedule (the window after a stable detection), like the others; the
sensors they leave untouched.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import gymnasium as gym

from racf.sim.attacks.base import AttackWrapper, attack_wrappers
from racf.sim.attacks.schedule import AttackSchedule

__all__ = ["LinkAttack", "LinkDelay", "LinkDrop", "LinkSpoof", "LinkVerdict", "link_attacks"]


@dataclass(frozen=True)
class LinkVerdict:
    """What the man in the middle does to one answer: hold it ``delay_s``, lose it, or send ``body``
    (the answer's last frame, replaced) instead."""

    delay_s: float = 0.0
    drop: bool = False
    body: bytes | None = None


class LinkAttack(AttackWrapper):
    """The base of the link's attacks: the observation passes as it is; :meth:`on_answer` decides
    each answer of the service while the schedule has the attack on."""

    needs_simulator = "it acts on the link to a defence service, which a recording does not have"
    #: Marks an attack that needs the car's defence served over a link (``--estimator-endpoint``).
    on_link = True

    def _attack(self, obs: dict, info: dict) -> dict:
        return obs

    def bind_link(self, link) -> None:
        """The relay that carries this attack (closed with the env)."""
        self._link = link

    def close(self) -> None:
        link = getattr(self, "_link", None)
        if link is not None:
            link.close()
            self._link = None
        super().close()

    def on_answer(self, body: bytes, encrypted: bool) -> LinkVerdict:
        """The verdict on one answer whose last frame is ``body`` (ciphertext where ``encrypted``)."""
        raise NotImplementedError


def _number(name: str, value: Any, lo: float, hi: float) -> float:
    if not (isinstance(value, (int, float)) and not isinstance(value, bool) and lo <= value <= hi):
        raise ValueError(f"{name} must be a number in [{lo}, {hi}], got {value!r}")
    return float(value)


class LinkDelay(LinkAttack):
    """Holds each answer ``delay_ms`` plus a uniform jitter of ± ``jitter_ms`` (at least 0).

    Args:
        env: the racf env.
        delay_ms: the added latency, ms (0 to 5000).
        jitter_ms: its spread, ms (0 to 5000).
        **schedule: ``AttackSchedule`` fields.
    """

    name = "link_delay"

    def __init__(self, env: gym.Env, delay_ms: float = 60.0, jitter_ms: float = 20.0, **schedule: Any) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, delay_ms=delay_ms, jitter_ms=jitter_ms, **schedule)
        self.delay_ms = _number("delay_ms", delay_ms, 0.0, 5000.0)
        self.jitter_ms = _number("jitter_ms", jitter_ms, 0.0, 5000.0)
        super().__init__(env, AttackSchedule(**schedule))

    def on_answer(self, body: bytes, encrypted: bool) -> LinkVerdict:
        ms = self.delay_ms + self.rng.uniform(-self.jitter_ms, self.jitter_ms)
        return LinkVerdict(delay_s=max(ms, 0.0) / 1000.0)


class LinkDrop(LinkAttack):
    """Loses each answer with probability ``rate`` (1: every answer in the attack's window).

    Args:
        env: the racf env.
        rate: the share of answers lost, in (0, 1].
        **schedule: ``AttackSchedule`` fields.
    """

    name = "link_drop"

    def __init__(self, env: gym.Env, rate: float = 1.0, **schedule: Any) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, rate=rate, **schedule)
        self.rate = _number("rate", rate, 0.0, 1.0)
        if self.rate == 0.0:
            raise ValueError("rate must be in (0, 1]: a drop rate of 0 is no attack")
        super().__init__(env, AttackSchedule(**schedule))

    def on_answer(self, body: bytes, encrypted: bool) -> LinkVerdict:
        return LinkVerdict(drop=bool(self.rng.random() < self.rate))


class LinkSpoof(LinkAttack):
    """Answers ``distance_m`` for the service: the car reads the sign (or obstacle) that far away.

    On a plain link it rewrites each distance answer; on an encrypted one it cannot read which
    answer holds the distance, and any it replaces fails the car's authentication.

    Args:
        env: the racf env.
        distance_m: the attacker's distance, m (0 to 50; far: the car does not brake).
        **schedule: ``AttackSchedule`` fields.
    """

    name = "link_spoof"

    def __init__(self, env: gym.Env, distance_m: float = 5.0, **schedule: Any) -> None:
        gym.utils.RecordConstructorArgs.__init__(self, distance_m=distance_m, **schedule)
        self.distance_m = _number("distance_m", distance_m, 0.0, 50.0)
        super().__init__(env, AttackSchedule(**schedule))

    def on_answer(self, body: bytes, encrypted: bool) -> LinkVerdict:
        if encrypted:  # a forgery without the keys: the box's last byte changed, its tag no longer matches
            return LinkVerdict(body=body[:-1] + bytes([body[-1] ^ 0xFF])) if body else LinkVerdict()
        import msgpack

        try:
            answer = msgpack.unpackb(body, raw=False, strict_map_key=False)
        except Exception:  # not an answer the attacker can read: it passes
            return LinkVerdict()
        if not (isinstance(answer, dict) and "distance" in answer):
            return LinkVerdict()
        answer["distance"] = self.distance_m
        return LinkVerdict(body=msgpack.packb(answer, use_bin_type=True))


def link_attacks(env: gym.Env) -> list[LinkAttack]:
    """The link attacks among ``env``'s wrappers, outermost first."""
    return [w for w in attack_wrappers(env) if isinstance(w, LinkAttack)]
