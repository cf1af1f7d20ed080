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
  afresh (``reset``), and that is logged too (``service_restarts`` in the result row).
"""

from __future__ import annotations

import dataclasses
import math
import time
from typing import Any

import numpy as np

from racf.controllers import PerceptionSample
from racf.errors import UserError
from racf.controllers.detector import Detection
from racf.controllers.existence import ExistenceWitnesses

__all__ = ["RemoteEstimator", "ServiceError", "encode_sample", "decode_sample", "pack", "unpack", "PROTOCOL",
           "DEFAULT_TIMEOUT_MS", "DEFAULT_RETRY_S"]

#: The wire protocol's version: a server answers a hello from another version with an error.
PROTOCOL = 1
DEFAULT_TIMEOUT_MS = 50.0
DEFAULT_RETRY_S = 1.0
#: How long a car waits for a service to answer at all before it says none is there.
PING_TIMEOUT_S = 2.0


class ServiceError(RuntimeError):
    """The service refused a request (its message says why)."""


def _array(a: np.ndarray) -> dict:
    a = np.ascontiguousarray(a)
    return {"__nd__": True, "dtype": a.dtype.str, "shape": list(a.shape), "data": a.tobytes()}


def _default(obj: Any):
    if isinstance(obj, np.ndarray):
        return _array(obj)
    if isinstance(obj, (np.floating, np.integer, np.bool_)):
        return obj.item()
    if isinstance(obj, tuple):
        return list(obj)
    raise TypeError(f"cannot send {type(obj).__name__} to the service")


def _hook(obj: dict):
    if obj.get("__nd__"):
        return np.frombuffer(obj["data"], dtype=np.dtype(obj["dtype"])).reshape(obj["shape"]).copy()
    return obj


def pack(message: dict) -> bytes:
    import msgpack

    return msgpack.packb(message, default=_default, use_bin_type=True)


def unpack(raw: bytes) -> dict:
    import msgpack

    return msgpack.unpackb(raw, object_hook=_hook, raw=False, strict_map_key=False)


def encode_sample(sample: PerceptionSample) -> dict:
    """A sample as plain values and raw buffers (the detection's mask bit-packed)."""
    det = sample.detection
    out = {f.name: getattr(sample, f.name) for f in dataclasses.fields(sample) if f.name not in ("detection", "witnesses")}
    if det is not None:
        out["detection"] = {"mask": np.packbits(np.asarray(det.mask, bool)), "shape": list(det.mask.shape),
                            "box": list(det.box), "confidence": det.confidence, "area_px": det.area_px,
                            "centroid": list(det.centroid)}
    if sample.witnesses is not None:
        out["witnesses"] = dataclasses.asdict(sample.witnesses)
    return out


def decode_sample(raw: dict) -> PerceptionSample:
    raw = dict(raw)
    det = raw.pop("detection", None)
    wit = raw.pop("witnesses", None)
    detection = None
    if det is not None:
        h, w = det["shape"]
        mask = np.unpackbits(det["mask"], count=h * w).reshape(h, w).astype(bool)
        detection = Detection(mask, tuple(int(v) for v in det["box"]), float(det["confidence"]), int(det["area_px"]),
                              tuple(float(v) for v in det["centroid"]))
    witnesses = None
    if wit is not None:
        witnesses = ExistenceWitnesses(**{k: tuple(v) if isinstance(v, list) else v for k, v in wit.items()})
    return PerceptionSample(detection=detection, witnesses=witnesses, **raw)


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
    """

    def __init__(self, endpoint: str, name: str, options: dict | None = None, timeout_ms: float = DEFAULT_TIMEOUT_MS,
                 retry_s: float = DEFAULT_RETRY_S, connect_s: float = 60.0) -> None:
        self.endpoint, self.name, self.options = endpoint, name, dict(options or {})
        self.timeout_ms, self.retry_s = float(timeout_ms), float(retry_s)
        self._socket = None
        self._ctx = None
        self._clock = 0.0
        self._down_until = -math.inf
        self._needs_reset = False
        self._last: dict = {}
        self._stands: bool | None = None
        self.latency_s = 0.0
        self.restarts = 0
        self.connect_s = float(connect_s)
        try:  # a live service answers a ping at once; the hello may wait while it builds the defence
            self._request({"op": "ping"}, PING_TIMEOUT_S * 1000.0)
            hello = self._hello()
        except TimeoutError:
            self._close()
            raise UserError(f"no defence service answers at {endpoint}; start one with `racf serve` (or `racf serve "
                            f"--defence {name}`)") from None
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
        if reply is None:  # no answer: the car's own depth distance, unrepaired
            self._last = {"service_fallback": 1.0, "service_rtt_ms": math.nan,
                          "service_restarts": float(self.restarts)}
            self._stands = None
            return float(sample.d_meas)
        self._last = {**reply.get("diagnostics", {}), "service_fallback": 0.0,
                      "service_rtt_ms": self.latency_s * 1000.0, "service_restarts": float(self.restarts)}
        self._stands = reply.get("stands")
        return float(reply["distance"])

    def diagnostics(self) -> dict[str, float]:
        return dict(self._last)

    def stands(self) -> bool | None:
        return self._stands

    def would_pass(self, **kwargs) -> bool:
        reply = self._call({"op": "would_pass", "kwargs": kwargs})
        return True if reply is None else bool(reply["answer"])

    def close(self) -> None:
        self._close()

    # -- the transport ------------------------------------------------------------------
    def _call(self, message: dict) -> dict | None:
        """One request; None when the service is down (no answer in time, or waiting to retry)."""
        if self._clock < self._down_until:
            return None
        try:
            if self._needs_reset:  # the service came back: its defence starts afresh
                self._hello(self.timeout_ms)
                if getattr(self, "_calibration", None) is not None:
                    self._request({"op": "calibrate", "calibration": self._calibration})
                self._request({"op": "reset"})
                self._needs_reset = False
                self.restarts += 1
            return self._request(message)
        except TimeoutError:
            self._down_until = self._clock + self.retry_s
            self._needs_reset = True
            self.latency_s = self.timeout_ms / 1000.0
            return None

    def _hello(self, timeout_ms: float | None = None) -> dict:
        return self._request({"op": "hello", "protocol": PROTOCOL, "estimator": self.name, "options": self.options},
                             self.connect_s * 1000.0 if timeout_ms is None else timeout_ms)

    def _request(self, message: dict, timeout_ms: float | None = None) -> dict:
        import zmq

        if self._socket is None:
            self._ctx = self._ctx or zmq.Context.instance()
            self._socket = self._ctx.socket(zmq.REQ)
            self._socket.setsockopt(zmq.LINGER, 0)
            self._socket.connect(self.endpoint)
        start = time.perf_counter()
        self._socket.send(pack(message))
        if not self._socket.poll(self.timeout_ms if timeout_ms is None else timeout_ms, zmq.POLLIN):
            self._close()  # a REQ socket that got no answer cannot send again: open a new one next time
            raise TimeoutError
        reply = unpack(self._socket.recv())
        self.latency_s = time.perf_counter() - start
        if "error" in reply:
            raise ServiceError(f"the defence service at {self.endpoint}: {reply['error']}")
        return reply

    def _close(self) -> None:
        if self._socket is not None:
            self._socket.close(0)
            self._socket = None

    def __del__(self) -> None:
        try:
            self._close()
        except Exception:
            pass

