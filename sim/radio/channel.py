"""The simulated radio between vehicles: a broadcast rate, latency, loss and range.

Each vehicle that broadcasts (a world manager's :class:`~.message.Broadcast`) sends at ``hz`` (10 Hz,
the rate of ETSI's cooperative awareness messages), each message numbered, stamped with the fleet's
clock and signed with its key: the episode's fleet (:class:`~.keys.FleetKeys`), drawn at reset from
the radio's own random stream (a child of it: the channel's other draws are those it always made). Its state carries the sender's own localisation error
(``position_std_m``, ``speed_std_mps``). A message is lost with probability ``loss``, or when the
receiver is beyond ``range_m``, and otherwise arrives ``latency_s`` plus up to ``jitter_s`` later.
The car reads what arrived during a control step as the ``radio`` observation: up to
:data:`RADIO_SLOTS` messages of :data:`~.message.SIGNED_BYTES` one after the other, flat (an empty
slot is zeros; flat, as learning libraries expect a vector), and ``radio_times``, when each arrived
(s, the car's clock).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from racf.sim.radio.keys import FleetKeys
from racf.sim.radio.message import SIGNED_BYTES, Broadcast, V2VMessage, sign

__all__ = ["Radio", "RadioConfig", "RADIO_SLOTS", "empty_rows", "slots_holding"]

#: Messages the car can take in one control step (a 10 Hz sender's come one or none a 20 ms step).
RADIO_SLOTS = 8


@dataclass(frozen=True)
class RadioConfig:
    """The radio's settings (a DSRC/C-V2X link at a few metres; every value checked in ``__post_init__``)."""

    hz: float = 10.0
    latency_s: float = 0.02
    jitter_s: float = 0.01
    loss: float = 0.02
    range_m: float = 30.0
    position_std_m: float = 0.02
    speed_std_mps: float = 0.02

    def __post_init__(self) -> None:
        for name, lo, hi in (("hz", 0.5, 50.0), ("latency_s", 0.0, 1.0), ("jitter_s", 0.0, 1.0), ("loss", 0.0, 1.0),
                             ("range_m", 0.0, 1000.0), ("position_std_m", 0.0, 1.0), ("speed_std_mps", 0.0, 1.0)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not lo <= value <= hi:
                raise ValueError(f"radio {name} must be a number in [{lo}, {hi}], got {value!r}")


def empty_rows() -> tuple[np.ndarray, np.ndarray]:
    """The ``radio`` and ``radio_times`` observations of a step with nothing received."""
    return np.zeros(RADIO_SLOTS * SIGNED_BYTES, np.uint8), np.zeros(RADIO_SLOTS, np.float64)


def slots_holding(rows: np.ndarray, messages) -> int:
    """Which of a step's ``radio`` slots hold one of ``messages`` (bytes), as a bit mask (slot i: bit i)."""
    rows = np.asarray(rows, np.uint8).reshape(-1, SIGNED_BYTES)
    return sum(1 << i for i, row in enumerate(rows) if row.any() and row.tobytes() in messages)


class Radio:
    """The channel: what each sender sent, in flight until it arrives (or is lost)."""

    def __init__(self, config: RadioConfig | None = None) -> None:
        self.config = config if config is not None else RadioConfig()
        self.reset(np.random.default_rng(0))

    def reset(self, rng: np.random.Generator) -> None:
        self.fleet = FleetKeys.draw(rng.spawn(1)[0])
        self.rng = rng
        self._seq: dict[int, int] = {}
        self._in_flight: list[tuple[float, bytes]] = []
        self._next_send_s = 0.0
        self.sent = self.delivered = 0  # this step's, for the referee
        self.delivered_now: frozenset[bytes] = frozenset()  # this step's genuine messages, for the referee

    def tick(self, now_s: float, broadcasts: tuple[Broadcast, ...], receiver_xy: tuple[float, float]
             ) -> tuple[np.ndarray, np.ndarray]:
        """One control step at ``now_s``: the senders send if their time has come; what arrived by now
        is returned as the step's ``radio`` rows and their arrival times."""
        c = self.config
        self.sent = 0
        if broadcasts and now_s + 1e-9 >= self._next_send_s:
            self._next_send_s = math.floor(now_s * c.hz + 1e-6) / c.hz + 1.0 / c.hz
            for state in broadcasts:
                self._send(now_s, state, receiver_xy)
        arrived = sorted(m for m in self._in_flight if m[0] <= now_s + 1e-9)
        self._in_flight = [m for m in self._in_flight if m[0] > now_s + 1e-9]
        rows, times = empty_rows()
        for i, (t, raw) in enumerate(arrived[:RADIO_SLOTS]):
            rows[i * SIGNED_BYTES:(i + 1) * SIGNED_BYTES] = np.frombuffer(raw, np.uint8)
            times[i] = t
        self.delivered = min(len(arrived), RADIO_SLOTS)
        self.delivered_now = frozenset(raw for _, raw in arrived[:RADIO_SLOTS])
        return rows, times

    def _send(self, now_s: float, state: Broadcast, receiver_xy: tuple[float, float]) -> None:
        c, rng = self.config, self.rng
        seq = self._seq.get(state.sender, 0) + 1
        self._seq[state.sender] = seq
        # The sender's own localiser and encoder: what it knows of itself, not the world's truth.
        dx, dy, dv = rng.normal(0.0, 1.0, 3) * (c.position_std_m, c.position_std_m, c.speed_std_mps)
        said = replace(state, x_m=state.x_m + float(dx), y_m=state.y_m + float(dy),
                       speed_mps=max(state.speed_mps + float(dv), 0.0))
        raw = sign(V2VMessage(seq, now_s, said), self.fleet.signing_key(state.sender))
        self.sent += 1
        lost = rng.random() < c.loss
        delay = c.latency_s + c.jitter_s * float(rng.random())
        if lost or math.dist((state.x_m, state.y_m), receiver_xy) > c.range_m:
            return
        self._in_flight.append((now_s + delay, raw))
