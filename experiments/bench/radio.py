"""What checking the car ahead's broadcast costs the car: ``racf bench radio``.

Each message the car reads is parsed, its Ed25519 signature verified against the fleet's key
(libsodium, through PyNaCl) and its number and age checked (:class:`~racf.experiments.car.broadcast.
BroadcastReceiver`). This times that whole check, one message at a time on one core, over signed
messages of a lead driving at 10 Hz, and sets its percentiles against the car's 20 ms control period.
"""

from __future__ import annotations

import time

import numpy as np

from racf.experiments.car.broadcast import BroadcastReceiver
from racf.sim.radio import RADIO_SLOTS, SIGNED_BYTES, Broadcast, FleetKeys, V2VMessage, sign

__all__ = ["time_verification", "CONTROL_PERIOD_MS"]

#: The car's control period, ms (50 Hz).
CONTROL_PERIOD_MS = 20.0


def time_verification(messages: int = 5000) -> dict:
    """The receiver's check of ``messages`` signed messages, each timed alone: p50, p99 and max in
    microseconds, and p99 as a share of the control period."""
    if messages < 100:
        raise ValueError(f"messages must be at least 100 (a p99 needs them), got {messages}")
    fleet = FleetKeys.draw(np.random.default_rng(0))
    key, car = fleet.signing_key(1), BroadcastReceiver(fleet.trust_store())
    costs = np.empty(messages)
    for k in range(messages):
        t = 0.1 * (k + 1)
        raw = sign(V2VMessage(k + 1, t, Broadcast(1, 0.6 * t, 0.0, 0.0, 0.6, 0.0, False)), key)
        rows = np.zeros(RADIO_SLOTS * SIGNED_BYTES, np.uint8)
        rows[:SIGNED_BYTES] = np.frombuffer(raw, np.uint8)
        obs = {"radio": rows, "radio_times": np.full(RADIO_SLOTS, t)}
        start = time.perf_counter()
        heard = car.hear(obs, t)
        costs[k] = time.perf_counter() - start
        assert len(heard) == 1  # every message genuine: the time is an accepted message's whole check
    us = costs * 1e6
    p99 = float(np.percentile(us, 99))
    return {"messages": messages, "p50_us": float(np.percentile(us, 50)), "p99_us": p99, "max_us": float(us.max()),
            "control_period_ms": CONTROL_PERIOD_MS, "p99_share_of_period": p99 / (CONTROL_PERIOD_MS * 1000.0)}
