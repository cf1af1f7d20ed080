"""``racf bench service-probes``: an attacker's probes of ``racf serve``, each with its number.

- **Half-sent frames**: connections that finish ZeroMQ's handshake and send a frame's header and all
  of its bytes but one; the server's memory before, with them open, and some seconds later.
- **Checkpoint spellings**: one car served at the control rate while another says hello with the
  shipped head's path spelt many ways; the served car's round trips.
- **One host's many addresses**: sessions opened from 64 loopback addresses; whether a car from
  another range is still served.
- **Keep-alives that do no work**: sessions that only send ``reset`` (or only ``ping``) past the
  service's idle time; how many are still open.

The raw peer (:func:`zmtp_peer`) speaks ZMTP 3.0's NULL handshake by hand, as an attacker would:
a ZeroMQ socket never leaves a frame half-sent.
"""

from __future__ import annotations

import socket
import struct
import threading
import time
from pathlib import Path


from racf.experiments.link.wire import PROTOCOL, pack, unpack
from racf.experiments.service.stress import cars, rss_mb

__all__ = ["zmtp_peer", "half_sent", "closed_within", "half_sent_memory", "spellings", "range_fill", "keep_alive"]

#: ZMTP 3.0's greeting for the NULL mechanism, as a client (signature, version 3.0, mechanism, as-server 0).
_GREETING = b"\xff" + b"\x00" * 8 + b"\x7f" + b"\x03\x00" + b"NULL".ljust(20, b"\x00") + b"\x00" + b"\x00" * 31


def _ready_command(socket_type: bytes = b"DEALER") -> bytes:
    name = b"Socket-Type"
    body = b"\x05READY" + bytes([len(name)]) + name + struct.pack(">I", len(socket_type)) + socket_type
    return b"\x04" + bytes([len(body)]) + body


def _host_port(endpoint: str) -> tuple[str, int]:
    host, _, port = endpoint.removeprefix("tcp://").rpartition(":")
    return host, int(port)


def zmtp_peer(endpoint: str, timeout_s: float = 5.0) -> socket.socket:
    """A TCP connection to ``endpoint`` that has finished the NULL handshake as a DEALER."""
    peer = socket.create_connection(_host_port(endpoint), timeout=timeout_s)
    peer.sendall(_GREETING)
    got = b""
    while len(got) < len(_GREETING):
        chunk = peer.recv(len(_GREETING) - len(got))
        if not chunk:
            raise ConnectionError(f"{endpoint} closed the connection during the greeting")
        got += chunk
    peer.sendall(_ready_command())
    return peer


def half_sent(endpoint: str, size: int) -> socket.socket:
    """A handshaken connection that declared a frame of ``size`` bytes and sent all but its last."""
    peer = zmtp_peer(endpoint)
    peer.sendall(b"\x02" + struct.pack(">Q", size) + b"\x00" * (size - 1))
    return peer


def closed_within(peer: socket.socket, seconds: float) -> float | None:
    """How long until the far end closed ``peer``, s (None: still open after ``seconds``). Reads and
    drops whatever the far end sends meanwhile (its handshake, its pings)."""
    start = time.monotonic()
    peer.settimeout(0.1)
    while time.monotonic() - start < seconds:
        try:
            if peer.recv(4096) == b"":
                return time.monotonic() - start
        except socket.timeout:
            continue
        except OSError:
            return time.monotonic() - start
    return None


def half_sent_memory(endpoint: str, pid: int, n: int = 300, size: int = (1 << 20), wait_s: float = 10.0) -> dict:
    """``n`` connections each half-sending a frame of ``size`` bytes: the server's memory before, with
    them open (1 s later), and ``wait_s`` later; how many the server closed by then."""
    before = rss_mb(pid)
    peers = []
    try:
        for _ in range(n):
            try:
                peers.append(half_sent(endpoint, size))
            except OSError:
                break  # the server refused more connections: what it held is measured
        time.sleep(1.0)
        held = rss_mb(pid)
        time.sleep(wait_s)
        after = rss_mb(pid)
        closed = sum(closed_within(peer, 0.01) is not None for peer in peers)
    finally:
        for peer in peers:
            peer.close()
    return {"connections": len(peers), "frame_bytes": size, "server_mb_before": before, "server_mb_open": held,
            "server_mb_after": after, "after_s": wait_s + 1.0, "closed_by_server": closed}


def _ask(sock, message: dict, wait_ms: float = 10_000.0) -> dict | None:
    sock.send(pack(message))
    return unpack(sock.recv()) if sock.poll(wait_ms) else None


_CONTEXT = None


def _context():
    """A ZeroMQ context for the probes, with room for the 1,024 sockets a host can open (ZeroMQ's
    default holds 1,023, the process's file limit often 1,024)."""
    import resource

    import zmq

    global _CONTEXT
    if _CONTEXT is None:
        soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
        want = 8192 if hard == resource.RLIM_INFINITY else min(hard, 8192)
        if soft < want:
            resource.setrlimit(resource.RLIMIT_NOFILE, (want, hard))
        _CONTEXT = zmq.Context()
        _CONTEXT.set(zmq.MAX_SOCKETS, 4096)
    return _CONTEXT


def _req(endpoint: str, source: str | None = None):
    import zmq

    sock = _context().socket(zmq.REQ)
    sock.setsockopt(zmq.LINGER, 0)
    sock.connect(f"tcp://{source}:0;{endpoint.split('://', 1)[1]}" if source else endpoint)
    return sock


def spellings(endpoint: str, defence: str, calls: list, calibration, n: int = 20, hz: float = 50.0,
              timeout_ms: float = 150.0) -> dict:
    """One car served at ``hz`` while another says hello ``n`` times with the shipped checkpoint's path
    spelt ``n`` ways: the served car's round trips, and what the hellos were answered."""
    from racf.odca.online import SHIPPED_HEAD

    folder = Path(SHIPPED_HEAD)
    ways = [str(folder)] + [f"{folder.parent}/{'./' * k}{folder.name}" for k in range(1, n)]
    answers: list[str] = []
    served: dict = {}
    car = threading.Thread(target=lambda: served.update(cars(endpoint, defence, calls, calibration, 1, hz, 8.0,
                                                             timeout_ms)), daemon=True)
    car.start()
    time.sleep(1.0)
    start = time.monotonic()
    for way in ways[:n]:  # each hello on a socket of its own: a service that loads a file may answer late
        sock = _req(endpoint)
        try:
            answer = _ask(sock, {"op": "hello", "id": 1, "protocol": PROTOCOL, "estimator": defence,
                                 "options": {"checkpoint": way}}, wait_ms=60_000.0)
        finally:
            sock.close(0)
        answers.append("no answer" if answer is None else "refused" if "refused" in answer else "opened")
    hellos_s = time.monotonic() - start
    car.join()
    return {"spellings": n, "hellos_s": hellos_s, "answers": {a: answers.count(a) for a in set(answers)},
            "served_car": {k: v for k, v in served.items() if k in ("steps", "lost", "rtt_p50_ms", "rtt_p99_ms",
                                                                     "rtt_max_ms")}}


def range_fill(endpoint: str, defence: str = "raw", addresses: int = 64, per_address: int = 16) -> dict:
    """Sessions opened from ``addresses`` loopback addresses (127.0.0.2 on), ``per_address`` each;
    then whether a car from another range (127.0.1.2) is served."""
    socks, opened = [], 0
    hello = {"op": "hello", "id": 1, "protocol": PROTOCOL, "estimator": defence, "options": {}}
    start = time.monotonic()
    try:
        for a in range(addresses):
            for _ in range(per_address):
                sock = _req(endpoint, f"127.0.0.{a + 2}")
                answer = _ask(sock, hello)
                if answer is not None and "refused" not in answer:
                    opened += 1
                    socks.append(sock)  # it holds its session while its connection lives
                else:
                    sock.close(0)
        took = time.monotonic() - start
        other = _req(endpoint, "127.0.1.2")
        socks.append(other)
        answer = _ask(other, hello)
    finally:
        for sock in socks:
            sock.close(0)
    return {"addresses": addresses, "asked": addresses * per_address, "opened": opened, "seconds": took,
            "other_range_served": answer is not None and "refused" not in answer}


def keep_alive(endpoint: str, idle_s: float, n: int = 100, defence: str = "raw") -> dict:
    """``n`` sessions that only send ``reset`` and ``n`` that only ``ping``, every ``idle_s / 4`` for
    three idle times: how many of each still hold a session."""
    hello = {"op": "hello", "id": 1, "protocol": PROTOCOL, "estimator": defence, "options": {}}
    groups = {"reset": [], "ping": []}
    try:
        for op, socks in groups.items():
            for _ in range(n):
                sock = _req(endpoint)
                _ask(sock, hello)
                socks.append(sock)
        deadline = time.monotonic() + 3.0 * idle_s
        while time.monotonic() < deadline:
            for op, socks in groups.items():
                for k, sock in enumerate(socks):
                    _ask(sock, {"op": op, "id": k + 2})
            time.sleep(idle_s / 4.0)
        alive = {op: sum("no_session" not in (_ask(sock, {"op": "reset", "id": 9}) or {"no_session": True})
                         for sock in socks) for op, socks in groups.items()}
    finally:
        for socks in groups.values():
            for sock in socks:
                sock.close(0)
    return {"sessions": n, "idle_s": idle_s, "after_s": 3.0 * idle_s,
            "alive_resetting": alive["reset"], "alive_pinging": alive["ping"]}
