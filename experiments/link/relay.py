"""The man in the middle of the link attacks (``racf.sim.attacks.link``): a TCP relay between the car
and ``racf serve`` that reads ZeroMQ's framing (ZMTP 3) in the service's answers.

The car connects to the relay, the relay to the service; what the car sends passes untouched.
The service's bytes are cut into ZMTP frames after the 64-byte greeting. A message on a plain
link is its frames up to one without the MORE flag; on a CurveZMQ link every frame is an
encrypted ``MESSAGE`` command (libzmq sends it as a data frame) whose flags sit inside the box, so the relay counts frames as the
attacker would: racf's answers are two (the REQ envelope's empty delimiter, then the map).
While an attack's schedule has it on, each answer gets its verdict (held, lost, or its last frame
replaced); handshake commands always pass. A lost answer on a plain link or an encrypted one
leaves the stream valid (CURVE rejects only replayed nonces, not skipped ones).
"""

from __future__ import annotations

import selectors
import socket
import struct
import threading
import time
from collections import deque

from racf.sim.attacks.link import LinkAttack, LinkVerdict

__all__ = ["LinkRelay", "ZmtpFrames", "frame_bytes"]

_GREETING = 64
_MORE, _LONG, _COMMAND = 0x01, 0x02, 0x04
#: Frames in one of racf's answers on an encrypted link (delimiter + map).
_ANSWER_FRAMES = 2


def frame_bytes(body: bytes, flags: int) -> bytes:
    """One ZMTP frame: flags (the LONG bit set from the size), size, body."""
    if len(body) > 255:
        return bytes([(flags | _LONG) & 0xFF]) + struct.pack(">Q", len(body)) + body
    return bytes([flags & ~_LONG & 0xFF, len(body)]) + body


class ZmtpFrames:
    """Cuts one direction's byte stream into the greeting and whole frames, as they complete."""

    def __init__(self) -> None:
        self._buf = bytearray()
        self._greeting_left = _GREETING

    def feed(self, data: bytes) -> list[tuple[bytes, int, bytes]]:
        """The pieces ``data`` completes: (raw bytes, flags, body). The greeting's bytes pass as they
        come, with flags -1 (ZMTP sends it in stages and waits on the other end's)."""
        out = []
        if self._greeting_left:
            head, data = data[:self._greeting_left], data[self._greeting_left:]
            self._greeting_left -= len(head)
            if head:
                out.append((bytes(head), -1, b""))
        self._buf += data
        while len(self._buf) >= 2:
            flags = self._buf[0]
            head = 9 if flags & _LONG else 2
            if len(self._buf) < head:
                break
            size = struct.unpack(">Q", self._buf[1:9])[0] if flags & _LONG else self._buf[1]
            if len(self._buf) < head + size:
                break
            out.append((bytes(self._buf[:head + size]), flags, bytes(self._buf[head:head + size])))
            del self._buf[:head + size]
        return out




class _Pair:
    """One car connection and its connection to the service."""

    def __init__(self, car: socket.socket, service: socket.socket) -> None:
        self.car, self.service = car, service
        self.frames = ZmtpFrames()
        self.message: list[tuple[bytes, int, bytes]] = []  # the answer being gathered
        self.curve = False  # the service answered a CurveZMQ handshake (WELCOME): its frames are boxes
        self.curve_frames = 0
        self.out: deque = deque()  # (release time, bytes) towards the car, in order
        self.last_release = 0.0


class LinkRelay:
    """Relays ``tcp://HOST:PORT`` (the service) at a loopback port of its own (``endpoint``), with
    ``attacks`` deciding the answers while they are active. Runs in a daemon thread until :meth:`close`."""

    def __init__(self, service: str, attacks: list[LinkAttack]) -> None:
        host, port = service.split("://", 1)[1].rsplit(":", 1)
        self._service = (host.strip("[]"), int(port))
        self.attacks = attacks
        self._listener = socket.create_server(("127.0.0.1", 0))
        self.endpoint = f"tcp://127.0.0.1:{self._listener.getsockname()[1]}"
        self._sel = selectors.DefaultSelector()
        self._sel.register(self._listener, selectors.EVENT_READ, None)
        self._pairs: list[_Pair] = []
        self._stop = threading.Event()
        self.tampered = 0
        self._thread = threading.Thread(target=self._run, name="racf-link-relay", daemon=True)
        self._thread.start()

    def close(self) -> None:
        self._stop.set()
        self._thread.join(2.0)

    # -- the loop -----------------------------------------------------------------------
    def _run(self) -> None:
        try:
            while not self._stop.is_set():
                for key, _ in self._sel.select(self._wait()):
                    if key.data is None:
                        self._accept()
                    else:
                        pair, side = key.data
                        self._read(pair, side)
                self._release()
        finally:
            for pair in list(self._pairs):
                self._drop(pair)
            self._sel.close()
            self._listener.close()

    def _wait(self) -> float:
        pending = [p.out[0][0] for p in self._pairs if p.out]
        return max(0.0, min(pending) - time.monotonic()) if pending else 0.05

    def _accept(self) -> None:
        car, _ = self._listener.accept()
        try:
            service = socket.create_connection(self._service, timeout=2.0)
        except OSError:
            car.close()
            return
        for s in (car, service):
            s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            s.setblocking(True)
        pair = _Pair(car, service)
        self._pairs.append(pair)
        self._sel.register(car, selectors.EVENT_READ, (pair, "car"))
        self._sel.register(service, selectors.EVENT_READ, (pair, "service"))

    def _read(self, pair: _Pair, side: str) -> None:
        src = pair.car if side == "car" else pair.service
        try:
            data = src.recv(65536)
        except OSError:
            data = b""
        if not data:
            self._drop(pair)
            return
        if side == "car":
            self._send(pair, pair.service, data)
            return
        for raw, flags, body in pair.frames.feed(data):
            self._answer_piece(pair, raw, flags, body)

    def _answer_piece(self, pair: _Pair, raw: bytes, flags: int, body: bytes) -> None:
        """Gathers an answer's frames; a handshake's pieces pass at once."""
        if flags < 0 or flags & _COMMAND:
            pair.curve |= body.startswith(b"\x07WELCOME")
            self._queue(pair, raw, 0.0)
            return
        pair.message.append((raw, flags, body))
        if pair.curve:  # libzmq frames each box as a data frame holding a MESSAGE command
            pair.curve_frames += 1
            complete, encrypted = pair.curve_frames % _ANSWER_FRAMES == 0, True
        else:
            complete, encrypted = not flags & _MORE, False
        if complete:
            frames, pair.message = pair.message, []
            self._decide(pair, frames, encrypted)

    def _decide(self, pair: _Pair, frames: list, encrypted: bool) -> None:
        verdict = LinkVerdict()
        for attack in self.attacks:
            if attack.active:
                verdict = attack.on_answer(frames[-1][2], encrypted)
                break
        if verdict.drop:
            return
        if verdict.body is not None:
            self.tampered += 1
            raw, flags, _ = frames[-1]
            frames[-1] = (frame_bytes(verdict.body, flags), flags, verdict.body)
        self._queue(pair, b"".join(raw for raw, _, _ in frames), verdict.delay_s)

    def _queue(self, pair: _Pair, data: bytes, delay_s: float) -> None:
        release = max(time.monotonic() + delay_s, pair.last_release)  # order kept: no answer overtakes another
        pair.last_release = release
        pair.out.append((release, data))
        self._release()

    def _release(self) -> None:
        now = time.monotonic()
        for pair in list(self._pairs):
            while pair.out and pair.out[0][0] <= now:
                self._send(pair, pair.car, pair.out.popleft()[1])

    def _send(self, pair: _Pair, dst: socket.socket, data: bytes) -> None:
        try:
            dst.sendall(data)
        except OSError:
            self._drop(pair)

    def _drop(self, pair: _Pair) -> None:
        if pair not in self._pairs:
            return
        self._pairs.remove(pair)
        for s in (pair.car, pair.service):
            try:
                self._sel.unregister(s)
            except (KeyError, ValueError):
                pass
            s.close()
