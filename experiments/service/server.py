"""``racf serve``: defences in their own process, one instance per car, behind ZeroMQ.

A ROUTER socket takes each car's requests (``racf.experiments.episode.remote`` speaks the other
end): ``hello`` names the defence and its options and opens the car's session (its own
estimator, built as an episode builds it; the first of a kind is warmed up first, so that
what it loads on first use is loaded before the car's first timed request), ``calibrate`` hands
the estimator the car's build, ``reset`` / ``estimate`` / ``would_pass`` are the
``DistanceEstimator`` protocol. A session idle for ``idle_s`` is dropped.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

from racf.controllers import CameraModel
from racf.experiments.episode.car import CarCalibration
from racf.experiments.episode.estimators import make_estimator
from racf.experiments.episode.remote import PROTOCOL, decode_sample, pack, unpack

__all__ = ["DefenceService", "serve"]


@dataclass
class _Session:
    estimator: object
    seen: float = field(default_factory=time.monotonic)


class DefenceService:
    """Answers the protocol's requests; one estimator per car.

    Args:
        names: the defences it serves (None: every registered one). The first is built and warmed
            now: a bad name fails before the service listens.
        options: options of the first defence it serves, the only ones it accepts for it (None:
            any the car asks for).
    """

    def __init__(self, names: tuple[str, ...] | None = None, options: dict | None = None, idle_s: float = 600.0) -> None:
        self.names, self.options, self.idle_s = names, options, idle_s
        self._warm: set[str] = set()
        if names:
            self._warm_up(names[0], options or {})
        self.sessions: dict[bytes, _Session] = {}
        self.requests = 0

    def _warm_up(self, name: str, options: dict) -> None:
        key = f"{name}:{sorted(options.items())}"
        if key not in self._warm:
            warm_up(make_estimator(name, options))
            self._warm.add(key)

    def handle(self, client: bytes, message: dict) -> dict:
        self.requests += 1
        op = message.get("op")
        if op == "ping":
            return {"pong": True}
        if op == "hello":
            if message.get("protocol") != PROTOCOL:
                return {"error": f"protocol {message.get('protocol')!r}; this service speaks {PROTOCOL}"}
            name, options = message.get("estimator"), dict(message.get("options") or {})
            if self.names is not None and name not in self.names:
                return {"refused": f"this service serves {', '.join(self.names)}, not {name!r} "
                                   f"(start `racf serve --defence {name}`)"}
            if self.names is not None and self.options is not None and name == self.names[0] and options != self.options:
                return {"refused": f"this service runs {name} with options {self.options}, not {options}"}
            self._warm_up(name, options)
            estimator = make_estimator(name, options)
            self.sessions[client] = _Session(estimator)
            self._drop_idle()
            return {"estimator": name, "options": options, "protocol": PROTOCOL,
                    "existence": bool(getattr(estimator, "existence", False)),
                    "second_detector": getattr(estimator, "second_detector", None),
                    "n_parameters": getattr(estimator, "n_parameters", 0),
                    "n_frozen_parameters": getattr(estimator, "n_frozen_parameters", None)}
        session = self.sessions.get(client)
        if session is None:
            return {"error": "no session: say hello first"}
        session.seen = time.monotonic()
        est = session.estimator
        if op == "calibrate":
            configure = getattr(est, "use_calibration", None)
            if callable(configure):
                raw = dict(message["calibration"])
                raw["camera"] = CameraModel(**raw["camera"])
                for key in ("camera_xy_m", "lidar_xy_m"):
                    raw[key] = tuple(raw[key])
                configure(CarCalibration(**raw))
            return {}
        if op == "reset":
            est.reset()
            return {}
        if op == "estimate":
            d = est.estimate(decode_sample(message["sample"]), message["speed"], message["dt"],
                             yaw_rate_radps=message["yaw_rate"])
            verdict = getattr(est, "stands", None)
            return {"distance": float(d), "diagnostics": _floats(est.diagnostics()),
                    "stands": verdict() if callable(verdict) else None}
        if op == "would_pass":
            return {"answer": bool(est.would_pass(**message["kwargs"]))}
        return {"error": f"unknown request {op!r}"}

    def _drop_idle(self) -> None:
        now = time.monotonic()
        for client in [c for c, s in self.sessions.items() if now - s.seen > self.idle_s]:
            del self.sessions[client]


def warm_up(estimator, steps: int = 100) -> None:
    """Runs ``estimator`` over a made-up approach (3 m to 1 m at 1 m/s, depth and LiDAR agreeing), so
    that what it loads or compiles on first use (ODCA's prior) is loaded before the first car asks:
    a cold first answer would miss the car's timeout. A defence that cannot take such samples is
    left cold."""
    from racf.controllers import PerceptionSample
    from racf.experiments.episode.plan import car_calibration

    try:
        configure = getattr(estimator, "use_calibration", None)
        if callable(configure):
            configure(car_calibration(320, 240))
        estimator.reset()
        for k in range(steps):
            d = 3.0 - 2.0 * k / steps
            estimator.estimate(PerceptionSample(None, d, 0.9, d, 0.0), 1.0, 0.02)
        estimator.reset()
    except Exception:  # noqa: BLE001 - warming is a courtesy; a real request will say what is wrong
        pass


def _floats(values: dict) -> dict:
    out = {}
    for key, value in values.items():
        try:
            out[key] = float(value)
        except (TypeError, ValueError):
            out[key] = str(value)
    return out


def serve(endpoint: str, names: tuple[str, ...] | None = None, options: dict | None = None, ready=None,
          max_requests: float = math.inf, stop=None) -> int:
    """Serves the defences ``names`` (None: every registered one) at ``endpoint`` until interrupted,
    ``stop`` (a ``threading.Event``) is set or ``max_requests`` are answered (then it stops
    answering, as a dead service would); returns the requests answered. ``ready(endpoint)`` is
    called once the socket is bound."""
    import zmq

    service = DefenceService(names, options)
    ctx = zmq.Context.instance()
    sock = ctx.socket(zmq.ROUTER)
    sock.setsockopt(zmq.LINGER, 0)
    try:
        sock.bind(endpoint)
    except zmq.ZMQError as err:
        from racf.errors import UserError

        sock.close(0)
        raise UserError(f"cannot listen at {endpoint}: {err}") from None
    bound = sock.getsockopt_string(zmq.LAST_ENDPOINT)
    if ready is not None:
        ready(bound)
    try:
        while service.requests < max_requests and not (stop is not None and stop.is_set()):
            if not sock.poll(100):
                continue
            client, empty, raw = sock.recv_multipart()
            try:
                reply = service.handle(client, unpack(raw))
            except Exception as err:  # the defence raised: the car hears it as an error, the service lives on
                reply = {"error": f"{type(err).__name__}: {err}"}
            sock.send_multipart([client, empty, pack(reply)])
    finally:
        sock.close(0)
    return service.requests
