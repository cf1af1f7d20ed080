"""The defence as a service: the car's side of ``racf serve``.

The paper ran ODCA "on an offboard server over a local network", about 49 ms a cycle. Here a
defence can run in its own process (``racf serve``) and the car reaches it over ZeroMQ, each
request a msgpack map with numpy arrays as raw buffers. ZeroMQ, not gRPC: one request a control
step of a few kilobytes needs no schema compiler or HTTP/2 stack, a REQ/ROUTER pair gives each
car its own session on one server, and a loopback round trip is tens of microseconds
(``racf bench service`` measures it).

:class:`RemoteEstimator` is a ``DistanceEstimator`` like any other: the car calls it each
step and the service's defence (one instance per car) answers. The car trusts nothing it is
sent: an answer counts only if the protocol's check (:func:`~racf.experiments.link.wire.check_answer`)
passes it: it names this request's id, and its distance is a finite number in [0, 50] m or
says "no target". Anything else is a step without an answer, and nothing a service says ends
the episode:

- **A slow answer.** The measured round trip is the estimate's ``latency_s``; the runner
  delays the action by each whole control period it overran (an answer within the period is
  in time for that step's action, as on the paper's 20 Hz loop).
- **No answer, or one the check refuses** (out of range, of the wrong kind, an error, an
  answer to another request, a refused or late re-hello). The car falls back to its onboard
  defence (``onboard``: ODCA from its ONNX export by default, run every step beside the served one
  so that its state is the episode's; without one, its own depth distance, ``d_meas``, unrepaired)
  for that step (``service_fallback``; ``service_onboard`` where the onboard defence drove),
  counts a refused answer (``service_invalid``), logs the first of each kind once, and asks
  again after ``retry_s`` of its own time in a new session (``service_new_sessions``), its
  defence started afresh. A defence the service had to rebuild is no answer either
  (``service_restarts``: the service's own count, as its log names it).
- **An answer the car's own witnesses outvote.** A served answer is one more reading. Where the car
  runs an onboard defence (else its own depth distance), a served distance farther than the onboard
  one by more than ``OUTVOTE_M`` (or "no target" where the onboard defence has one) is outvoted: the
  nearer, the car's own, drives; a served "nothing stands" where the car's own witnesses say a target
  does is outvoted too (``service_outvoted``: steps the served answer was set aside). A lie the
  protocol's check cannot see (a distance in range, the ids kept) costs the car nothing it would not
  have without the service.
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
from racf.experiments.link.outvote import OUTVOTE_M, outvote
from racf.experiments.link.curve import CarKeys, Handshake, handshake_failure, refusal
from racf.experiments.link.wire import (DEFAULT_RETRY_S, DEFAULT_TIMEOUT_MS, MAX_MESSAGE_BYTES, PROTOCOL,
                                           InvalidAnswer, WireError, check_answer, decode_sample, encode_sample,
                                           pack, unpack)

__all__ = ["RemoteEstimator", "NoAnswer", "outvote", "OUTVOTE_M", "encode_sample", "decode_sample", "pack", "unpack", "PROTOCOL",
           "DEFAULT_TIMEOUT_MS", "DEFAULT_RETRY_S"]

LOG = logging.getLogger("racf.link")
#: How long a car waits for a service's first answer before it looks at its link: nothing listening
#: and a failed handshake are said then; a peer that listens is waited for up to ``connect_s``.
PING_TIMEOUT_S = 2.0
#: How long a failed first answer waits for the handshake's events to say why, ms: only when the
#: session opens (a step's timeout never waits for them: the car falls back at once).
HANDSHAKE_WAIT_MS = 1000.0
#: How often a car opening its session looks at its link's events while it waits, ms.
_SLICE_MS = 20.0
#: How long closing a session waits for the service to take the car's goodbye.
BYE_TIMEOUT_MS = 200.0


class NoAnswer(TimeoutError):
    """No answer came in ``waited_ms``; ``handshake`` says what the link saw (a peer, a refusal)."""

    def __init__(self, handshake: Handshake, waited_ms: float) -> None:
        super().__init__(handshake.failure or ("no answer" if handshake.connected else "nothing listens"))
        self.handshake, self.waited_ms = handshake, waited_ms


#: The link's failures during an episode: each is a step without an answer, never the episode's end.
_FAILURES = (NoAnswer, InvalidAnswer, WireError)


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
        keys: the car's CURVE keys and the service key it pins (``racf.experiments.link.curve``);
            None: a plain link.
        onboard: the car's own defence (a ``DistanceEstimator``), fed every step and used where the
            service gives no answer; None: the car's depth distance, unrepaired.
    """

    def __init__(self, endpoint: str, name: str, options: dict | None = None, timeout_ms: float = DEFAULT_TIMEOUT_MS,
                 retry_s: float = DEFAULT_RETRY_S, connect_s: float = 60.0, keys: CarKeys | None = None,
                 onboard=None) -> None:
        self.endpoint, self.name, self.options = endpoint, name, dict(options or {})
        self.onboard = onboard
        self.timeout_ms, self.retry_s, self.keys = float(timeout_ms), float(retry_s), keys
        self._socket = self._monitor = self._ctx = None
        self._clock = 0.0
        self._down_until = -math.inf
        self._needs_session = False
        self._request_id = 0
        self._last: dict = {}
        self._said: set[str] = set()
        self._stands: bool | None = None
        self._calibration = None
        self._rtts: list[float] = []
        self.latency_s = 0.0
        self.restarts = 0  # the service rebuilt this car's defence (it raised)
        self.new_sessions = 0  # sessions the car opened again after a failure
        self.invalid = 0  # answers the protocol's check refused
        self.refusals = 0  # answers lost to a failed handshake (a peer that is not the pinned service)
        self.outvoted = 0  # served answers the car's own witnesses outvoted
        self.connect_s = float(connect_s)
        ping_ms = None
        try:  # a live service answers a ping at once; the hello may wait while it builds the defence
            self._request({"op": "ping"}, self.connect_s * 1000.0, fail_fast_ms=PING_TIMEOUT_S * 1000.0)
            ping_ms = self.latency_s * 1000.0
            hello = self._request(self._hello_message(), self.connect_s * 1000.0)
        except NoAnswer as err:
            self._close()
            raise UserError(self._unreachable(err, ping_ms)) from None
        except (InvalidAnswer, WireError) as err:
            self._close()
            raise UserError(f"the service at {endpoint}: {err}") from None
        if "refused" in hello:
            self._close()
            raise UserError(f"the service at {endpoint}: {hello['refused']}")
        if ping_ms > self.timeout_ms:
            LOG.warning("the service at %s answers late: its first answer took %.0f ms, and a step waits %.0f ms; "
                        "expect fallbacks, or give the car a longer --estimator-timeout-ms", endpoint, ping_ms,
                        self.timeout_ms)
        self.service = hello
        self.existence = bool(hello.get("existence", False))
        self.second_detector = hello.get("second_detector")
        self.n_parameters = hello.get("n_parameters", 0)
        if hello.get("n_frozen_parameters") is not None:
            self.n_frozen_parameters = hello["n_frozen_parameters"]

    def _unreachable(self, err: NoAnswer, ping_ms: float | None) -> str:
        """Why no session opened, in one line: nothing listens, a refused handshake, or a late service."""
        if err.handshake.failure is not None:
            return refusal(err.handshake.failure, self.keys, self.endpoint)
        if ping_ms is None and not err.handshake.connected:
            return (f"no defence service answers at {self.endpoint}: nothing listens there; start one with "
                    f"`racf serve --bind {self.endpoint} --defence {self.name}`")
        seen = f"its ping took {ping_ms:.0f} ms" if ping_ms is not None else "round trip seen: none"
        return (f"the service at {self.endpoint} answers late: nothing in {err.waited_ms / 1000.0:.0f} s ({seen}); "
                f"a loaded service needs a longer --estimator-timeout-ms, or fewer cars")

    # -- the DistanceEstimator protocol --------------------------------------------------
    def use_calibration(self, calibration) -> None:
        self._calibration = dataclasses.asdict(calibration)
        configure = getattr(self.onboard, "use_calibration", None)
        if callable(configure):
            configure(calibration)
        self._call({"op": "calibrate", "calibration": self._calibration})

    def reset(self) -> None:
        self._stands = None
        self._said.clear()
        if self.onboard is not None:
            self.onboard.reset()
        self._call({"op": "reset"})

    def estimate(self, sample: PerceptionSample, speed_mps: float, dt: float, yaw_rate_radps: float = 0.0) -> float:
        self._clock += dt
        # The onboard defence sees every step, so that where it must drive its state is the episode's.
        own = math.nan if self.onboard is None else float(self.onboard.estimate(sample, speed_mps, dt, yaw_rate_radps))
        reply = self._call({"op": "estimate", "sample": encode_sample(sample), "speed": float(speed_mps), "dt": float(dt),
                            "yaw_rate": float(yaw_rate_radps)})
        status = {"service_restarts": float(self.restarts), "service_new_sessions": float(self.new_sessions),
                  "service_invalid": float(self.invalid), "service_refusals": float(self.refusals)}
        if reply is None:  # no answer the car may act on
            if self.onboard is None:
                self._last = {"service_fallback": 1.0, "service_onboard": 0.0, "service_rtt_ms": math.nan, **status}
                self._stands = None
                return float(sample.d_meas)  # the car's own depth distance, unrepaired
            stands = getattr(self.onboard, "stands", None)
            self._stands = stands() if callable(stands) else None
            self._last = {**self.onboard.diagnostics(), "service_fallback": 1.0, "service_onboard": 1.0,
                          "service_rtt_ms": math.nan, **status}
            return own
        self._rtts.append(self.latency_s * 1000.0)
        served = math.nan if reply["distance"] is None else float(reply["distance"])
        own = own if self.onboard is not None else float(sample.d_meas)
        distance, stands, outvoted = outvote(served, reply["stands"], own, self._own_stands(sample))
        self.outvoted += outvoted
        self._last = {**reply["diagnostics"], "service_fallback": 0.0, "service_onboard": 0.0,
                      "service_rtt_ms": self.latency_s * 1000.0, **status,
                      "service_outvoted": float(self.outvoted)}
        self._stands = stands
        return distance

    def _own_stands(self, sample: PerceptionSample) -> bool | None:
        """Whether the car's own witnesses say a target stands: the onboard defence's verdict where it
        gives one, else the detector's."""
        verdict = getattr(self.onboard, "stands", None)
        said = verdict() if callable(verdict) else None
        return bool(sample.detected) if said is None else bool(said)

    def diagnostics(self) -> dict[str, float]:
        return dict(self._last)

    def stands(self) -> bool | None:
        return self._stands

    def would_pass(self, **kwargs) -> bool:
        reply = self._call({"op": "would_pass", "kwargs": kwargs})
        return True if reply is None else reply["answer"]

    def close(self) -> None:
        """Ends the session: the service logs it with the round trips the car measured."""
        if self._socket is not None and not self._needs_session:
            rtt = np.asarray(self._rtts, float)
            summary = {"steps": int(rtt.size), **({"rtt_p50_ms": float(np.percentile(rtt, 50)),
                                                   "rtt_p99_ms": float(np.percentile(rtt, 99))} if rtt.size else {})}
            try:
                self._request({"op": "bye", **summary}, BYE_TIMEOUT_MS)
            except _FAILURES:
                pass  # a goodbye is a courtesy: the session ends with the connection anyway
        self._close()

    # -- the link's failures --------------------------------------------------------------
    def _call(self, message: dict) -> dict | None:
        """One request's checked answer; None when there is none the car may act on (none in time,
        one the protocol's check refuses, a defence the service rebuilt) or the car waits to retry."""
        self.latency_s = 0.0  # a step that asks nothing waits for nothing
        if self._clock < self._down_until:
            return None
        try:
            if self._needs_session:
                self._open_session()
            try:
                return self._request(message)
            except InvalidAnswer as err:
                if err.kind != "no_session":
                    raise
                self._open_session()  # a service restarted between two requests: a new session, then the request
                return self._request(message)
        except InvalidAnswer as err:
            if err.kind == "restarted":  # the session stands, its defence starts afresh: no answer this step
                self.restarts += 1
                self._say(err.kind, str(err))
                return None
            if err.kind != "refused":  # a refused hello is the service's no, not an answer the car refused
                self.invalid += 1
            self._fail(err.kind, str(err))
        except WireError as err:
            self.invalid += 1
            self._fail("malformed", str(err))
        except NoAnswer as err:
            self.latency_s = err.waited_ms / 1000.0
            if err.handshake.failure is not None:  # a failed handshake, not a silence
                self.refusals += 1
                self._fail("refused_link", f"{err.handshake.failure}")
            else:
                self._fail("late", f"no answer in {self.timeout_ms:.0f} ms (answers seen: "
                                   f"{self._rtt_words()}); a loaded service needs a longer --estimator-timeout-ms")
        return None

    def _fail(self, kind: str, why: str) -> None:
        """A step without an answer: the car asks again after ``retry_s`` of its own time, on a new
        connection and in a new session (the old one's state is not to be trusted)."""
        self._down_until = self._clock + self.retry_s
        self._needs_session = True
        self._close()
        self._say(kind, why)

    def _say(self, kind: str, why: str) -> None:
        """Logs the first failure of each kind in an episode, in one line."""
        if kind not in self._said:
            self._said.add(kind)
            LOG.warning("the defence service at %s: %s; the car falls back to %s", self.endpoint, why,
                        "its own depth distance" if self.onboard is None else
                        f"its onboard defence ({getattr(self.onboard, 'name', type(self.onboard).__name__)})")

    def _rtt_words(self) -> str:
        if not self._rtts:
            return "none yet"
        rtt = np.asarray(self._rtts, float)
        return f"p50 {np.percentile(rtt, 50):.1f} ms, max {rtt.max():.1f} ms"

    def _open_session(self) -> None:
        hello = self._request(self._hello_message())
        if "refused" in hello:
            raise InvalidAnswer("refused", f"it refused a new session: {hello['refused']}")
        if self._calibration is not None:
            self._request({"op": "calibrate", "calibration": self._calibration})
        self._request({"op": "reset"})
        self._needs_session = False
        self.new_sessions += 1

    def _hello_message(self) -> dict:
        return {"op": "hello", "protocol": PROTOCOL, "estimator": self.name, "options": self.options}

    # -- the transport ------------------------------------------------------------------
    def _open(self):
        import zmq

        self._ctx = self._ctx or zmq.Context.instance()
        sock = self._ctx.socket(zmq.REQ)
        sock.setsockopt(zmq.LINGER, 0)
        sock.setsockopt(zmq.MAXMSGSIZE, MAX_MESSAGE_BYTES)
        if self.keys is not None:
            self.keys.apply(sock)
        self._monitor = sock.get_monitor_socket(zmq.EVENT_CONNECTED | zmq.EVENT_HANDSHAKE_FAILED_AUTH
                                                | zmq.EVENT_HANDSHAKE_FAILED_NO_DETAIL
                                                | zmq.EVENT_HANDSHAKE_FAILED_PROTOCOL | zmq.EVENT_HANDSHAKE_SUCCEEDED)
        sock.connect(self.endpoint)
        return sock

    def _request(self, message: dict, timeout_ms: float | None = None, fail_fast_ms: float | None = None) -> dict:
        """The service's checked answer to ``message`` (sent with the next request id). NoAnswer when
        none came in time, InvalidAnswer for one the protocol's check refuses, WireError for one that
        is not a message. With ``fail_fast_ms``: after that long without an answer, the link is looked
        at, and the car gives up at once where nothing listens or the handshake failed."""
        import zmq

        if self._socket is None:
            self._socket = self._open()
        self._request_id += 1
        request_id = self._request_id
        start = time.perf_counter()
        wait_ms = self.timeout_ms if timeout_ms is None else timeout_ms
        # A REQ socket whose connection a failed handshake just dropped has no peer to queue for: without a
        # send timeout it would block until one came back, which a refused car's never does.
        self._socket.setsockopt(zmq.SNDTIMEO, max(1, int(min(wait_ms, fail_fast_ms or wait_ms))))
        try:
            self._socket.send(pack({**message, "id": request_id}))
            answered, handshake = self._await(start, wait_ms, fail_fast_ms)
        except zmq.Again:
            answered, handshake = False, None
        if not answered:
            if handshake is None or handshake.failure is None:
                wait = HANDSHAKE_WAIT_MS if fail_fast_ms else 0.0  # why, where the session opens; never on a step
                handshake = _merge(handshake, handshake_failure(self._monitor, wait))
            self._close()  # a REQ socket that got no answer cannot send again: open a new one next time
            raise NoAnswer(handshake, (time.perf_counter() - start) * 1000.0)
        reply = unpack(self._socket.recv())
        self.latency_s = time.perf_counter() - start
        return check_answer(message["op"], reply, request_id)

    def _await(self, start: float, wait_ms: float, fail_fast_ms: float | None) -> tuple[bool, Handshake | None]:
        """Waits for the answer up to ``wait_ms`` after ``start``. With ``fail_fast_ms`` the link's events are
        read as it waits: a failed handshake ends the wait at once, and so does a peer never reached by
        ``fail_fast_ms`` (nothing listens). A step's request (no ``fail_fast_ms``) waits on the socket alone."""
        import zmq

        def elapsed_ms() -> float:
            return (time.perf_counter() - start) * 1000.0

        if fail_fast_ms is None:
            return bool(self._socket.poll(max(0.0, wait_ms - elapsed_ms()), zmq.POLLIN)), None
        seen = Handshake(False, None)
        while True:
            if self._socket.poll(min(_SLICE_MS, max(0.0, wait_ms - elapsed_ms())), zmq.POLLIN):
                return True, seen
            seen = _merge(seen, handshake_failure(self._monitor))
            if seen.failure is not None or elapsed_ms() >= wait_ms or (elapsed_ms() >= fail_fast_ms
                                                                       and not seen.connected):
                return False, seen

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


def _merge(first: Handshake | None, later: Handshake) -> Handshake:
    """What the link showed over two reads of its events (a connection seen in either counts)."""
    if first is None:
        return later
    return Handshake(first.connected or later.connected, later.failure or first.failure)
