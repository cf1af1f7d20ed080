"""The defence as a service: the car's side of ``racf serve``.

The paper ran ODCA "on an offboard server over a local network", about 49 ms a cycle. Here a
defence can run in its own process (``racf serve``) and the car reaches it over ZeroMQ, each
request a msgpack map with numpy arrays as raw buffers. ZeroMQ, not gRPC: one request a control
step of a few kilobytes needs no schema compiler or HTTP/2 stack, a REQ/ROUTER pair gives each
car its own session on one server, and a loopback round trip is tens of microseconds
(``racf bench service`` measures it).

:class:`RemoteEstimator` is a ``DistanceEstimator`` like any other: the car calls it each
step and the service's defence (one instance per car) answers. What the car must survive:

- **A slow answer.** The measured round trip is the estimate's ``latency_s``; the runner
  delays the action by each whole control period it overran (an answer within the period is
  in time for that step's action, as on the paper's 20 Hz loop).
- **No answer.** After ``timeout_ms`` the car falls back to its own perception's depth
  distance (``d_meas``, no repair) for that step, logs it (``service_fallback``), and asks the
  service again after ``retry_s`` of its own time; a service that comes back starts its defence
  afresh (``reset``), and that is logged too (``service_restarts`` in the result row). An answer
  that is not a message (:mod:`~racf.experiments.episode.wire`), or a defence the service had to
  rebuild, is no answer either.
- **A peer that is not the service.** On a CurveZMQ link (``keys``) the car talks only to the
  service whose key it pins; a man in the middle fails the handshake or the box, the car falls
  back and counts it (``service_refusals``), and logs the first in one line.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time

import numpy as np

from racf.controllers import PerceptionSample
from racf.errors import UserError
from racf.experiments.episode.curve import CarKeys, handshake_failure
from racf.experiments.episode.wire import (DEFAULT_RETRY_S, DEFAULT_TIMEOUT_MS, MAX_MESSAGE_BYTES, PROTOCOL, WireError,
                                           decode_sample, encode_sample, pack, unpack)

__all__ = ["RemoteEstimator", "ServiceError", "encode_sample", "decode_sample", "pack", "unpack", "PROTOCOL",
           "DEFAULT_TIMEOUT_MS", "DEFAULT_RETRY_S"]

LOG = logging.getLogger("racf.link")
#: How long a car waits for a service to answer at all before it says none is there.
PING_TIMEOUT_S = 2.0
#: How long the first request's failure waits for the handshake's events to say why, ms: only when
#: the session opens (a step's timeout never waits for them: the car falls back at once).
HANDSHAKE_WAIT_MS = 1000.0
#: How long closing a session waits for the service to take the car's goodbye.
BYE_TIMEOUT_MS = 200.0


class ServiceError(RuntimeError):
    """The service refused a request (its message says why)."""


class RemoteEstimator:
    """A defence served by ``racf serve`` at ``endpoint`` (``tcp://HOST:PORT``).

    Args:
        endpoint: where the service listens.
        name: the defence the episode asks for; the service must serve it (else UserError).
        options: the defence's options, as the service must have been started with.
        timeout_ms: how long the car waits for an answer before it falls back.
        retry_s: after a failure, how much of the car's own time passes before it asks again.
        connect_s: how long the car waits for the service to open its session (before it drives:
            the service may build and warm the defence first).
        keys: the car's CURVE keys and the service key it pins (``racf.experiments.episode.curve``);
            None: a plain link.
    """

    def __init__(self, endpoint: str, name: str, options: dict | None = None, timeout_ms: float = DEFAULT_TIMEOUT_MS,
                 retry_s: float = DEFAULT_RETRY_S, connect_s: float = 60.0, keys: CarKeys | None = None) -> None:
        self.endpoint, self.name, self.options = endpoint, name, dict(options or {})
        self.timeout_ms, self.retry_s, self.keys = float(timeout_ms), float(retry_s), keys
        self._socket = self._monitor = self._ctx = None
        self._clock = 0.0
        self._down_until = -math.inf
        self._needs_reset = False
        self._last: dict = {}
        self._stands: bool | None = None
        self._calibration = None
        self._rtts: list[float] = []
        self.latency_s = 0.0
        self.restarts = 0
        self.refusals = 0  # answers lost to a failed handshake (a peer that is not the pinned service)
        self.connect_s = float(connect_s)
        try:  # a live service answers a ping at once; the hello may wait while it builds the defence
            self._request({"op": "ping"}, PING_TIMEOUT_S * 1000.0, handshake_wait_ms=HANDSHAKE_WAIT_MS)
            hello = self._hello()
        except TimeoutError as err:
            self._close()
            why = (f"{err}; give the car the key folder the service was started with (--service-keys DIR, "
                   f"made by `racf serve keys DIR`)" if str(err) else
                   f"no defence service answers at {endpoint}; start one there with "
                   f"`racf serve --bind {endpoint} --defence {name}`")
            raise UserError(why) from None
        except (ServiceError, WireError) as err:
            self._close()
            raise UserError(f"the service at {endpoint}: {err}") from None
        if "refused" in hello:
            self._close()
            raise UserError(f"the service at {endpoint}: {hello['refused']}")
        self.service = hello
        self.existence = bool(hello.get("existence", False))
        self.second_detector = hello.get("second_detector")
        self.n_parameters = hello.get("n_parameters", 0)
        if hello.get("n_frozen_parameters") is not None:
            self.n_frozen_parameters = hello["n_frozen_parameters"]

    # -- the DistanceEstimator protocol --------------------------------------------------
    def use_calibration(self, calibration) -> None:
        self._calibration = dataclasses.asdict(calibration)
        self._call({"op": "calibrate", "calibration": self._calibration})

    def reset(self) -> None:
        self._stands = None
        self._call({"op": "reset"})

    def estimate(self, sample: PerceptionSample, speed_mps: float, dt: float, yaw_rate_radps: float = 0.0) -> float:
        self._clock += dt
        reply = self._call({"op": "estimate", "sample": encode_sample(sample), "speed": float(speed_mps), "dt": float(dt),
                            "yaw_rate": float(yaw_rate_radps)})
        status = {"service_restarts": float(self.restarts), "service_refusals": float(self.refusals)}
        distance = None if reply is None else reply.get("distance")
        if not isinstance(distance, (int, float)) or isinstance(distance, bool):  # no answer, or not a distance
            self._last = {"service_fallback": 1.0, "service_rtt_ms": math.nan, **status}
            self._stands = None
            return float(sample.d_meas)  # the car's own depth distance, unrepaired
        self._rtts.append(self.latency_s * 1000.0)
        diagnostics = reply.get("diagnostics")
        self._last = {**(diagnostics if isinstance(diagnostics, dict) else {}), "service_fallback": 0.0,
                      "service_rtt_ms": self.latency_s * 1000.0, **status}
        stands = reply.get("stands")
        self._stands = stands if isinstance(stands, bool) else None
        return float(distance)

    def diagnostics(self) -> dict[str, float]:
        return dict(self._last)

    def stands(self) -> bool | None:
        return self._stands

    def would_pass(self, **kwargs) -> bool:
        reply = self._call({"op": "would_pass", "kwargs": kwargs})
        return True if reply is None else bool(reply.get("answer", True))

    def close(self) -> None:
        """Ends the session: the service logs it with the round trips the car measured."""
        if self._socket is not None and not self._needs_reset:
            rtt = np.asarray(self._rtts, float)
            summary = {"steps": int(rtt.size), **({"rtt_p50_ms": float(np.percentile(rtt, 50)),
                                                   "rtt_p99_ms": float(np.percentile(rtt, 99))} if rtt.size else {})}
            try:
                self._request({"op": "bye", **summary}, BYE_TIMEOUT_MS)
            except (TimeoutError, ServiceError, WireError):
                pass  # a goodbye is a courtesy: the service expires an idle session anyway
        self._close()

    # -- the transport ------------------------------------------------------------------
    def _call(self, message: dict) -> dict | None:
        """One request; None when the service gave no usable answer (none in time, a malformed one,
        a defence it had to restart) or the car is waiting to retry."""
        if self._clock < self._down_until:
            return None
        try:
            if self._needs_reset:  # the service came back: its defence starts afresh
                self._reopen()
            reply = self._request(message)
        except ServiceError as err:
            if "no session" not in str(err):
                raise
            self._reopen()  # a service restarted between two requests: a new session, then the request
            reply = self._request(message)
        except (TimeoutError, WireError) as err:
            self._down_until = self._clock + self.retry_s
            self._needs_reset = True
            self.latency_s = self.timeout_ms / 1000.0
            if isinstance(err, TimeoutError) and str(err):  # a failed handshake, not a silence
                self.refusals += 1
                if self.refusals == 1:
                    LOG.warning("the link to %s: %s; the car falls back to its own depth distance", self.endpoint, err)
            return None
        if "restarted" in reply:  # the defence raised and was rebuilt: this step has no answer
            self.restarts += 1
            return None
        return reply

    def _reopen(self) -> None:
        self._hello(self.timeout_ms)
        if self._calibration is not None:
            self._request({"op": "calibrate", "calibration": self._calibration})
        self._request({"op": "reset"})
        self._needs_reset = False
        self.restarts += 1

    def _hello(self, timeout_ms: float | None = None) -> dict:
        return self._request({"op": "hello", "protocol": PROTOCOL, "estimator": self.name, "options": self.options},
                             self.connect_s * 1000.0 if timeout_ms is None else timeout_ms)

    def _open(self):
        import zmq

        self._ctx = self._ctx or zmq.Context.instance()
        sock = self._ctx.socket(zmq.REQ)
        sock.setsockopt(zmq.LINGER, 0)
        sock.setsockopt(zmq.MAXMSGSIZE, MAX_MESSAGE_BYTES)
        if self.keys is not None:
            self.keys.apply(sock)
        self._monitor = sock.get_monitor_socket(zmq.EVENT_HANDSHAKE_FAILED_AUTH | zmq.EVENT_HANDSHAKE_FAILED_NO_DETAIL
                                                | zmq.EVENT_HANDSHAKE_FAILED_PROTOCOL | zmq.EVENT_HANDSHAKE_SUCCEEDED)
        sock.connect(self.endpoint)
        return sock

    def _request(self, message: dict, timeout_ms: float | None = None, handshake_wait_ms: float = 0.0) -> dict:
        """The service's answer to ``message``. TimeoutError when none came in time (its message
        says why where the handshake failed), ServiceError for an error answer, WireError for one
        that is not a message."""
        import zmq

        if self._socket is None:
            self._socket = self._open()
        start = time.perf_counter()
        wait_ms = self.timeout_ms if timeout_ms is None else timeout_ms
        # A REQ socket whose connection a failed handshake just dropped has no peer to queue for: without a
        # send timeout it would block until one came back, which a refused car's never does.
        self._socket.setsockopt(zmq.SNDTIMEO, max(1, int(wait_ms)))
        try:
            self._socket.send(pack(message))
            sent = True
        except zmq.Again:
            sent = False
        left_ms = max(0.0, wait_ms - (time.perf_counter() - start) * 1000.0)
        if not sent or not self._socket.poll(left_ms, zmq.POLLIN):
            failure = handshake_failure(self._monitor, handshake_wait_ms)
            self._close()  # a REQ socket that got no answer cannot send again: open a new one next time
            raise TimeoutError(f"the service at {self.endpoint} cannot be authenticated: {failure}" if failure else "")
        reply = unpack(self._socket.recv())
        self.latency_s = time.perf_counter() - start
        if "error" in reply:
            raise ServiceError(f"the defence service at {self.endpoint}: {reply['error']}")
        return reply

    def _close(self) -> None:
        if self._socket is not None:
            self._socket.disable_monitor()
            self._monitor.close(0)
            self._socket.close(0)
            self._socket = self._monitor = None

    def __del__(self) -> None:
        try:
            self._close()
        except Exception:
            pass
