"""``racf bench service-stress``: what must hold of ``racf serve`` under hostile and heavy use.

- **Fuzz**: frame sets no protocol allows (any number of frames, random bytes, msgpack of any
  shape, the protocol's requests with their fields broken, arrays whose bytes lie), sent from a
  DEALER socket in batches; after every batch a fresh car must get its ping answered.
- **Connections**: many sockets at once, each asking once; every one must be answered.
- **Cars**: several cars at the control rate for minutes, each its own session, replaying an
  episode's real samples; every answer must come in time, and the server's memory must stay
  within a margin of where it started.
"""

from __future__ import annotations

import threading
import time
from pathlib import Path

import numpy as np

from racf.experiments.link.remote import RemoteEstimator
from racf.experiments.service.bench import percentiles
from racf.experiments.link.wire import PROTOCOL, pack

__all__ = ["fuzz_frames", "fuzz", "connections", "cars", "rss_mb", "ping"]

_OPS = ("ping", "hello", "calibrate", "reset", "estimate", "would_pass", "bye", "", None, 7, "x" * 300)


def _value(rng: np.random.Generator, depth: int = 0):
    """Any msgpack value: numbers, NaN, strings, bytes, lists, maps, fake arrays."""
    kind = rng.integers(9 if depth < 3 else 5)
    if kind == 0:
        return None
    if kind == 1:
        return float(rng.choice([np.nan, np.inf, -1e308, 0.0, rng.normal()]))
    if kind == 2:
        return int(rng.integers(-2**62, 2**62))
    if kind == 3:
        return "".join(chr(int(c)) for c in rng.integers(32, 0x2FF, rng.integers(0, 20)))
    if kind == 4:
        return rng.bytes(int(rng.integers(0, 64)))
    if kind == 5:
        return [_value(rng, depth + 1) for _ in range(rng.integers(0, 5))]
    if kind == 6:
        return {str(_value(rng, depth + 1))[:10]: _value(rng, depth + 1) for _ in range(rng.integers(0, 5))}
    if kind == 7:  # an array whose header lies about its bytes, or names a dtype it may not
        return {"__nd__": True, "dtype": str(rng.choice(["|O", "<f8", "|u1", "<U4", "|V8", "x"])),
                "shape": [int(n) for n in rng.integers(-1, 1 << 20, rng.integers(0, 6))], "data": rng.bytes(16)}
    return {"op": _OPS[rng.integers(len(_OPS))], "id": _value(rng, depth + 1), "protocol": PROTOCOL, "estimator": "raw",
            "sample": _value(rng, depth + 1), "speed": _value(rng, depth + 1), "dt": _value(rng, depth + 1),
            "yaw_rate": 0.0, "calibration": _value(rng, depth + 1), "kwargs": _value(rng, depth + 1),
            "options": _value(rng, depth + 1)}


def fuzz_frames(rng: np.random.Generator) -> list[bytes]:
    """One frame set a hostile or broken peer might send a ROUTER (after its identity)."""
    kind = rng.integers(5)
    if kind == 0:  # any number of frames of random bytes
        return [rng.bytes(int(rng.integers(0, 200))) for _ in range(rng.integers(1, 7))]
    if kind == 1:  # a REQ envelope around random bytes
        return [b"", rng.bytes(int(rng.integers(0, 2000)))]
    if kind == 2:  # a REQ envelope around msgpack of any shape
        return [b"", pack({"v": _value(rng)}) if rng.random() < 0.2 else _packed(_value(rng))]
    if kind == 3:  # a request with broken fields, without the delimiter (a DEALER's)
        return [_packed(_value(rng, 2) if rng.random() < 0.3 else _request(rng))]
    return [b"", _packed(_request(rng)), *([b"trailing"] if rng.random() < 0.5 else [])]


def _request(rng: np.random.Generator) -> dict:
    return {"op": _OPS[rng.integers(len(_OPS))], "id": int(rng.integers(0, 1 << 20)), "protocol": PROTOCOL,
            "estimator": "raw", "options": {},
            "sample": _value(rng, 1), "speed": _value(rng, 2), "dt": 0.02, "yaw_rate": 0.0}


def _packed(value) -> bytes:
    import msgpack

    return msgpack.packb(value, use_bin_type=True)


def ping(endpoint: str, timeout_s: float = 5.0, keys=None) -> bool:
    """Whether a fresh car gets an answer to a ping within ``timeout_s``."""
    import zmq

    from racf.experiments.link.wire import unpack

    sock = zmq.Context.instance().socket(zmq.REQ)
    sock.setsockopt(zmq.LINGER, 0)
    if keys is not None:
        keys.apply(sock)
    sock.connect(endpoint)
    try:
        sock.send(pack({"op": "ping", "id": 1}))
        return bool(sock.poll(timeout_s * 1000.0)) and unpack(sock.recv()).get("pong") is True
    finally:
        sock.close(0)


def fuzz(endpoint: str, n: int, seed: int = 0, batch: int = 500, progress=None) -> dict:
    """Sends ``n`` fuzzed frame sets in batches of ``batch``; after each batch a ping must be answered."""
    import zmq

    rng = np.random.default_rng(seed)
    sock = zmq.Context.instance().socket(zmq.DEALER)
    sock.setsockopt(zmq.LINGER, 0)
    sock.connect(endpoint)
    sent = replies = pings = batches = 0
    try:
        while sent < n:
            for _ in range(min(batch, n - sent)):
                sock.send_multipart(fuzz_frames(rng))
                sent += 1
                while sock.poll(0):
                    sock.recv_multipart()
                    replies += 1
            batches += 1
            pings += ping(endpoint)
            if progress is not None:
                progress(sent)
        deadline = time.monotonic() + 1.0
        while time.monotonic() < deadline and sock.poll(50):
            sock.recv_multipart()
            replies += 1
    finally:
        sock.close(0)
    return {"requests": sent, "batches": batches, "pings_answered": pings, "replies": replies}


def connections(endpoint: str, k: int, timeout_s: float = 10.0) -> dict:
    """``k`` sockets connected at once, each asking once; how many were answered."""
    import zmq

    ctx = zmq.Context.instance()
    socks = []
    for _ in range(k):
        s = ctx.socket(zmq.REQ)
        s.setsockopt(zmq.LINGER, 0)
        s.connect(endpoint)
        socks.append(s)
    for s in socks:
        s.send(pack({"op": "ping"}))
    answered, deadline = 0, time.monotonic() + timeout_s
    poller = zmq.Poller()
    for s in socks:
        poller.register(s, zmq.POLLIN)
    waiting = set(socks)
    while waiting and time.monotonic() < deadline:
        for s, _ in poller.poll(100):
            s.recv()
            answered += 1
            poller.unregister(s)
            waiting.discard(s)
    for s in socks:
        s.close(0)
    return {"connections": k, "answered": answered}


def rss_mb(pid: int) -> float:
    """A process's resident memory, MB (Linux)."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024.0
    raise OSError(f"no VmRSS for process {pid}")


def cars(endpoint: str, defence: str, calls: list, calibration, k: int, hz: float, seconds: float,
         timeout_ms: float, server_pid: int | None = None, keys=None, progress=None) -> dict:
    """``k`` cars at ``hz`` for ``seconds``, each replaying ``calls`` (an episode's samples) through
    its own session; lost answers, round trips and the server's memory at start and end."""
    estimates = [c for c in calls if c is not None]
    results: list[dict] = [None] * k
    start_mb = rss_mb(server_pid) if server_pid else None

    def drive(i: int) -> None:
        car = RemoteEstimator(endpoint, defence, timeout_ms=timeout_ms, keys=keys)
        car.use_calibration(calibration)
        car.reset()
        rtt, lost, period = [], 0, 1.0 / hz
        t0 = time.perf_counter()
        step = 0
        while time.perf_counter() - t0 < seconds:
            sample, speed, dt, yaw = estimates[step % len(estimates)]
            car.estimate(sample, speed, dt, yaw)
            d = car.diagnostics()
            if d["service_fallback"] == 1.0:
                lost += 1
            else:
                rtt.append(d["service_rtt_ms"])
            step += 1
            time.sleep(max(0.0, t0 + step * period - time.perf_counter()))
            if step % len(estimates) == 0:
                car.reset()
        car.close()
        results[i] = {"steps": step, "lost": lost, "rtt": rtt}

    threads = [threading.Thread(target=drive, args=(i,), daemon=True) for i in range(k)]
    for t in threads:
        t.start()
    t0 = time.monotonic()
    while any(t.is_alive() for t in threads):
        time.sleep(1.0)
        if progress is not None:
            progress(min(time.monotonic() - t0, seconds))
    rtt = np.concatenate([np.asarray(r["rtt"], float) for r in results])
    end_mb = rss_mb(server_pid) if server_pid else None
    spread = {f"rtt_{k}": v for k, v in percentiles(rtt).items() if k != "n"} if rtt.size else {}
    return {"cars": k, "hz": hz, "seconds": seconds, "steps": sum(r["steps"] for r in results),
            "lost": sum(r["lost"] for r in results), **spread, "server_mb_start": start_mb, "server_mb_end": end_mb}
