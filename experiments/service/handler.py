"""The service's answers: the protocol's requests, one defence per car.

``hello`` picks one of the defences the operator serves and opens the car's session (its own
estimator, built as an episode builds it; each offered defence is warmed up first, so that what it
loads on first use is loaded before the car's first timed request). The operator sets every option
when the service starts (``racf serve --defence NAME --estimator-option ...``): a hello names the
options it expects, and is refused unless they are the operator's. A car never names a file the
service opens, nor a value it computes with: 20 spellings of one checkpoint once cost the service
1.45 s and 13.6 MB each, and a served car its round trips. ``calibrate`` hands the estimator the
car's build, ``reset`` / ``estimate`` / ``would_pass`` are the ``DistanceEstimator`` protocol,
``bye`` ends the session, ``ping`` asks whether anyone is there (and which protocol it speaks).
Every request carries an id (an int) and every answer names it, errors included, so that a car
refuses an answer to another request.

Every request is untrusted: one that is not what the protocol allows is answered with an
error naming what is wrong (:class:`BadRequest`), and a defence that raises is rebuilt for that
session alone and the car told (``restarted``); neither stops the service.
"""

from __future__ import annotations

import time

from racf.controllers import CameraModel
from racf.experiments.car.software import CarCalibration
from racf.experiments.car.estimators import make_estimator
from racf.experiments.link.wire import (MAX_REQUEST_ID, PROTOCOL, InvalidAnswer, WireError, decode_sample,
                                           wire_distance)
from racf.experiments.service.sessions import Session, Sessions, warn

__all__ = ["DefenceService", "BadRequest", "warm_up"]


class BadRequest(ValueError):
    """A request the protocol does not allow (says what is wrong)."""


def _number(message: dict, key: str) -> float:
    value = message.get(key)
    if not isinstance(value, (int, float)) or isinstance(value, bool):
        raise BadRequest(f"{key} must be a number, got {type(value).__name__}")
    return float(value)


class DefenceService:
    """Answers the protocol's requests; one estimator per car.

    Args:
        offers: the defences it serves, each with the operator's options, the only ones a car may
            ask for (None: every registered defence, each with its defaults). Each is built and
            warmed now: a bad name or option fails before the service listens.
        sessions: the sessions' bounds (:class:`~racf.experiments.service.sessions.Sessions`).
    """

    def __init__(self, offers: dict[str, dict] | None = None, sessions: Sessions | None = None) -> None:
        self.offers = None if offers is None else {name: dict(options) for name, options in offers.items()}
        self._warm: set[str] = set()
        for name, options in (self.offers or {}).items():
            self._warm_up(name, options)
        # Not `sessions or Sessions()`: Sessions has a length, and an empty one is falsy.
        self.sessions = Sessions() if sessions is None else sessions
        self.requests = 0

    @property
    def names(self) -> tuple[str, ...] | None:
        """The defences it serves (None: every registered one)."""
        return None if self.offers is None else tuple(self.offers)

    def offered(self, name: str) -> dict:
        """The operator's options of ``name`` (the defaults where it serves every registered defence)."""
        return {} if self.offers is None else self.offers[name]

    def _warm_up(self, name: str, options: dict) -> None:
        # At most one warm-up per offered defence: the offers are the operator's, fixed at start.
        if name not in self._warm:
            warm_up(make_estimator(name, options))
            self._warm.add(name)

    def handle(self, identity: bytes, client: str, message: dict, connection: int | None = None) -> dict:
        """The answer to one decoded request from the car at socket ``identity`` (``client``: who;
        ``connection``: the connection it came on, whose end ends the session), naming its id."""
        request_id = message.get("id")
        try:
            reply = self._handle(identity, client, message, connection)
        except Exception as err:  # the service's own fault: the car hears it (by its id), the log one line a second
            warn("raised", "request %r from %s raised %s: %s", message.get("op"), client, type(err).__name__, err)
            reply = {"error": f"the service failed on this request: {type(err).__name__}: {err}"}
        if _is_request_id(request_id):  # an id that is not one is not echoed
            reply["id"] = request_id
        return reply

    def _handle(self, identity: bytes, client: str, message: dict, connection: int | None) -> dict:
        self.requests += 1
        op = message.get("op")
        try:
            if not isinstance(op, str):
                raise BadRequest(f"op must be a request's name (a string), got {type(op).__name__}")
            if op == "hello" and message.get("protocol") != PROTOCOL:  # first: another protocol's car sends no id
                return {"error": f"protocol {message.get('protocol')!r}; this service speaks {PROTOCOL}"}
            request_id = message.get("id")
            if not _is_request_id(request_id):
                raise BadRequest(f"id must be an int in [0, {MAX_REQUEST_ID}] (protocol {PROTOCOL}), "
                                 f"got {request_id!r}")
            if op == "ping":
                return {"pong": True, "protocol": PROTOCOL}
            if op == "hello":
                return self._hello(identity, client, message, connection)
            session = self.sessions.get(identity)
            if session is None:
                return {"error": "no session: say hello first", "no_session": True}
            if op == "bye":
                self.sessions.close(identity, "the car closed it", message)
                return {}
            if op not in _DEFENCE_OPS:
                return {"error": f"unknown request {op!r}; allowed: ping, hello, bye, {', '.join(_DEFENCE_OPS)}"}
            call = _DEFENCE_OPS[op](session, message)  # the request read: a BadRequest here is the car's
            return self._defend(session, op, call)
        except (BadRequest, WireError) as err:
            warn("request", "bad %s request from %s: %s", op if isinstance(op, str) else "?", client, err)
            return {"error": f"bad request: {err}"}

    def _hello(self, identity: bytes, client: str, message: dict, connection: int | None = None) -> dict:
        name, options = message.get("estimator"), message.get("options") or {}
        if not isinstance(name, str) or not isinstance(options, dict):
            raise BadRequest("hello needs estimator (a name) and options (a map)")
        from racf.plugins import ESTIMATORS

        if self.names is not None and name not in self.names:
            return {"refused": f"this service serves {', '.join(self.names)}, not {name!r} "
                               f"(start `racf serve --defence {name}`)"}
        if name not in ESTIMATORS:
            return {"refused": f"this service has no defence {name!r} (it has {', '.join(ESTIMATORS)}); a plug-in "
                               f"defence must be installed where the service runs, or given to it with "
                               f"`racf serve --plugin FILE`"}
        if options != self.offered(name):
            return {"refused": f"this service runs {name} with its operator's options {self.offered(name)}, not "
                               f"{options}: a car picks a defence, never its options (start `racf serve --defence "
                               f"{name} --estimator-option ...` with the ones it asks for)"}
        try:
            self._warm_up(name, options)
            estimator = make_estimator(name, options)
        except Exception as err:  # a plug-in may raise anything on options it refuses
            return {"refused": f"{name} with options {options} cannot be built: {type(err).__name__}: {err}"}
        why = self.sessions.open(identity, Session(estimator, client, name, dict(options), connection=connection))
        if why is not None:
            return {"refused": why}
        return {"estimator": name, "options": options, "protocol": PROTOCOL,
                "existence": bool(getattr(estimator, "existence", False)),
                "second_detector": getattr(estimator, "second_detector", None),
                "n_parameters": getattr(estimator, "n_parameters", 0),
                "n_frozen_parameters": getattr(estimator, "n_frozen_parameters", None)}

    def _defend(self, session: Session, op: str, call) -> dict:
        """Runs the defence's part of a request; a defence that raises is rebuilt for this session."""
        start = time.perf_counter()
        try:
            reply = call(session.estimator)
        except Exception as err:  # the defence's own fault: this car's defence starts afresh
            session.restarts += 1
            warn("restart", "%s raised in the session of %s (%s: %s); restarted it", session.name, session.client,
                 type(err).__name__, err)
            session.estimator = make_estimator(session.name, session.options)
            if session.calibration is not None:
                _calibrate(session, session.calibration)(session.estimator)
            session.estimator.reset()
            return {"restarted": f"{session.name} raised {type(err).__name__}: {err}"}
        if op != "reset":  # a reset alone is no work: it keeps no session alive past its idle time
            self.sessions.worked(session)
        if op == "estimate":
            session.steps += 1
            session.service_ms.append((time.perf_counter() - start) * 1000.0)
        return reply


def _calibrate(session: Session, raw) -> callable:
    if not isinstance(raw, dict):
        raise BadRequest("calibration must be a map")
    try:
        fields = dict(raw)
        fields["camera"] = CameraModel(**fields["camera"])
        for key in ("camera_xy_m", "lidar_xy_m"):
            fields[key] = tuple(float(v) for v in fields[key])
        calibration = CarCalibration(**fields)
    except Exception as err:
        raise BadRequest(f"not a car calibration ({type(err).__name__}: {str(err)[:120]})") from None
    session.calibration = raw

    def apply(est):
        configure = getattr(est, "use_calibration", None)
        if callable(configure):
            configure(calibration)
        return {}

    return apply


def _estimate(session: Session, message: dict):
    sample = decode_sample(message.get("sample"))
    speed, dt, yaw = _number(message, "speed"), _number(message, "dt"), _number(message, "yaw_rate")

    def apply(est):
        d = est.estimate(sample, speed, dt, yaw_rate_radps=yaw)
        try:
            distance = wire_distance(d)  # the protocol's rule, the one the car applies
        except InvalidAnswer as err:
            return {"error": f"{session.name} answered no distance the protocol allows: {err}"}
        verdict = getattr(est, "stands", None)
        return {"distance": distance, "diagnostics": _floats(est.diagnostics()),
                "stands": verdict() if callable(verdict) else None}

    return apply


def _would_pass(session: Session, message: dict):
    kwargs = message.get("kwargs")
    if not isinstance(kwargs, dict) or not all(isinstance(k, str) for k in kwargs):
        raise BadRequest("would_pass needs kwargs (a map of names)")
    return lambda est: {"answer": bool(est.would_pass(**kwargs))}


def _reset(session: Session, message: dict):
    def apply(est):
        est.reset()
        return {}

    return apply


_DEFENCE_OPS = {"calibrate": lambda session, message: _calibrate(session, message.get("calibration")),
                "reset": _reset, "estimate": _estimate, "would_pass": _would_pass}


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
            out[str(key)] = float(value)
        except (TypeError, ValueError):
            out[str(key)] = str(value)
    return out


def _is_request_id(value) -> bool:
    """Whether ``value`` is a request id protocol 2 allows: an int (not a bool) in [0, MAX_REQUEST_ID]."""
    return isinstance(value, int) and not isinstance(value, bool) and 0 <= value <= MAX_REQUEST_ID
