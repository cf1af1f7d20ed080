"""The service's sessions: one defence per car, bounded per client, per network range and in all,
ended with their connection or when idle (only a defence's work keeps one alive: a car that sends
``reset`` or ``ping`` and nothing else is idle), each logged in one line when it ends (at most one a
second for a kind of ending: a flood of short sessions is not a flood of lines)."""

from __future__ import annotations

import ipaddress
import logging
import time
from collections import deque
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Session", "Sessions", "LOG", "warn", "Throttle", "client_range", "TIMES_KEPT"]

LOG = logging.getLogger("racf.serve")
#: A flood of bad requests must not become a flood of log lines: one line per kind per second,
#: with the count of those it stood for.
_WARN_EVERY_S = 1.0
#: A session keeps the service times of its last this many estimates (its line's percentiles are of
#: those): a session's memory does not grow with its length.
TIMES_KEPT = 4096
#: A network range: the addresses one host or one site can take (an IPv4 /24, an IPv6 /64).
_RANGE_BITS = {4: 24, 6: 64}


class Throttle:
    """Logs at most one line of a kind per ``every_s``, saying how many like it it stands for."""

    def __init__(self, every_s: float = _WARN_EVERY_S) -> None:
        self.every_s = every_s
        self._last: dict[str, list] = {}

    def log(self, level: int, kind: str, message: str, *args) -> None:
        now = time.monotonic()
        last = self._last.setdefault(kind, [-float("inf"), 0])
        if now - last[0] < self.every_s:
            last[1] += 1
            return
        more = f" (and {last[1]} more like it since the last line)" if last[1] else ""
        self._last[kind] = [now, 0]
        LOG.log(level, message + more, *args)


_THROTTLE = Throttle()


def warn(kind: str, message: str, *args) -> None:
    """Logs a warning of ``kind`` at most once per second, saying how many like it it stands for."""
    _THROTTLE.log(logging.WARNING, kind, message, *args)


@dataclass
class Session:
    """A car's defence and what the service saw of it.

    Attributes:
        client: who opened it: the car's CURVE key, else its network address.
        name, options: the defence and its options (to rebuild it after it raises).
        calibration: the car's build as the car sent it (raw), for a rebuilt defence.
    """

    estimator: object
    client: str
    name: str
    options: dict
    calibration: dict | None = None
    connection: int | None = None  # the connection's file descriptor at the server: its end ends the session
    steps: int = 0
    restarts: int = 0
    service_ms: deque = field(default_factory=lambda: deque(maxlen=TIMES_KEPT))
    opened: float = field(default_factory=time.monotonic)
    seen: float = field(default_factory=time.monotonic)

    def line(self, why: str, car: dict | None = None) -> str:
        """The session in one line: defence, steps, the service's own time, the car's round trips."""
        ms = np.asarray(self.service_ms, float)
        own = f"service {np.percentile(ms, 50):.2f}/{np.percentile(ms, 99):.2f} ms p50/p99" if ms.size else "no estimates"
        car = car or {}
        rtt = (f", round trip {car['rtt_p50_ms']:.2f}/{car['rtt_p99_ms']:.2f} ms p50/p99 (car)"
               if isinstance(car.get("rtt_p50_ms"), float) and isinstance(car.get("rtt_p99_ms"), float) else "")
        return (f"session of {self.client} ended ({why}): {self.name}, {self.steps} steps, {own}{rtt}, "
                f"{self.restarts} defence restarts, {time.monotonic() - self.opened:.0f} s")


def client_range(client: str) -> str:
    """The network range of a client that is an address (its /24, or /64 for IPv6); a car key is its own."""
    try:
        address = ipaddress.ip_address(client)
    except ValueError:
        return client
    return str(ipaddress.ip_network(f"{address}/{_RANGE_BITS[address.version]}", strict=False))


class Sessions:
    """The open sessions by the socket identity of the car that opened each.

    Args:
        idle_s: a session that did no work this long is dropped (work: a defence's estimate,
            calibration or answer; a ``reset`` or a ``ping`` is none).
        per_client: at most this many sessions per client (a car key, else an address); a hello
            beyond is refused. Never does a new hello end another car's session: a session ends
            with its connection, so a car that reconnects has freed its old one.
        per_range: at most this many per network range (:func:`client_range`): one host holds many
            addresses (64 loopback addresses once opened all 1,024 sessions in 1.5 s).
        total: at most this many in all; a hello beyond is refused.
    """

    def __init__(self, idle_s: float = 600.0, per_client: int = 16, total: int = 1024, per_range: int = 64) -> None:
        self.idle_s, self.per_client, self.total, self.per_range = idle_s, per_client, total, per_range
        self._open: dict[bytes, Session] = {}
        self._swept = time.monotonic()
        self._lines = Throttle()

    def __len__(self) -> int:
        return len(self._open)

    def get(self, identity: bytes) -> Session | None:
        return self._open.get(identity)

    @staticmethod
    def worked(session: Session) -> None:
        """``session``'s defence did work: it is not idle."""
        session.seen = time.monotonic()

    def open(self, identity: bytes, session: Session) -> str | None:
        """Adds ``session``; returns why it cannot be (None: opened)."""
        self.close(identity, "the car said hello again")
        if sum(s.client == session.client for s in self._open.values()) >= self.per_client:
            return (f"{session.client} holds this service's most sessions per client ({self.per_client}); "
                    f"end one, or try again later")
        where = client_range(session.client)
        if where != session.client and sum(client_range(s.client) == where for s in self._open.values()) >= self.per_range:
            return (f"the addresses of {where} hold this service's most sessions per network range "
                    f"({self.per_range}); try again later")
        if len(self._open) >= self.total:
            return f"this service holds its most sessions ({self.total}); try again later"
        self._open[identity] = session
        return None

    def close(self, identity: bytes, why: str, car: dict | None = None) -> None:
        session = self._open.pop(identity, None)
        if session is not None:
            self._lines.log(logging.INFO, why, "%s", session.line(why, car))

    def end_connection(self, connection: int) -> None:
        """Ends the sessions opened on ``connection`` (its file descriptor), which has closed."""
        for identity in [i for i, s in self._open.items() if s.connection == connection]:
            self.close(identity, "its connection closed")

    def expire(self, every_s: float = 1.0) -> None:
        """Drops the sessions that did no work for ``idle_s`` (looked at once per ``every_s``)."""
        now = time.monotonic()
        if now - self._swept < every_s:
            return
        self._swept = now
        for identity in [i for i, s in self._open.items() if now - s.seen > self.idle_s]:
            self.close(identity, f"idle {self.idle_s:.0f} s")

    def close_all(self, why: str) -> None:
        for identity in list(self._open):
            self.close(identity, why)
