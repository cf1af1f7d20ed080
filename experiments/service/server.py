"""``racf serve``: defences in their own process, one instance per car, behind ZeroMQ.

A ROUTER socket takes each car's requests (``racf.experiments.episode.remote`` speaks the other
end; :mod:`~racf.experiments.service.handler` answers them). No message stops it: a frame set
that is not a request (``[identity, b"", payload]`` from a REQ socket, ``[identity, payload]``
from a DEALER) is dropped, a payload that is not a message is answered with an error, each in
one logged line; ZeroMQ's ``MAXMSGSIZE`` cuts off a peer that sends more than a message may
hold. With keys (:mod:`~racf.experiments.episode.curve`) the socket is a CURVE server and a
ZAP handler admits only the listed cars.
"""

from __future__ import annotations

import math

from racf.errors import UserError
from racf.experiments.episode.curve import ServerKeys
from racf.experiments.episode.wire import MAX_MESSAGE_BYTES, WireError, pack, unpack
from racf.experiments.service.handler import DefenceService, warm_up
from racf.experiments.service.sessions import LOG, Sessions, warn

__all__ = ["DefenceService", "serve", "warm_up"]


def serve(endpoint: str, names: tuple[str, ...] | None = None, options: dict | None = None, ready=None,
          max_requests: float = math.inf, stop=None, keys: ServerKeys | None = None,
          sessions: Sessions | None = None) -> int:
    """Serves the defences ``names`` (None: every registered one) at ``endpoint`` until interrupted,
    ``stop`` (a ``threading.Event``) is set or ``max_requests`` are answered (then it stops
    answering, as a dead service would); returns the requests answered. ``ready(endpoint)`` is
    called once the socket is bound. ``keys``: serve over CURVE, to the admitted cars only."""
    import zmq

    service = DefenceService(names, options, sessions)
    ctx = zmq.Context.instance()
    auth = _authenticator(ctx, keys) if keys is not None else None
    sock = ctx.socket(zmq.ROUTER)
    sock.setsockopt(zmq.LINGER, 0)
    sock.setsockopt(zmq.MAXMSGSIZE, MAX_MESSAGE_BYTES)
    if keys is not None:
        sock.curve_secretkey, sock.curve_publickey, sock.curve_server = keys.secret, keys.public, True
    try:
        sock.bind(endpoint)
    except zmq.ZMQError as err:
        sock.close(0)
        if auth is not None:
            auth.stop()
        raise UserError(f"cannot listen at {endpoint}: {err}") from None
    bound = sock.getsockopt_string(zmq.LAST_ENDPOINT)
    if ready is not None:
        ready(bound)
    try:
        while service.requests < max_requests and not (stop is not None and stop.is_set()):
            service.sessions.expire()
            if sock.poll(100):
                _answer(sock, service)
    finally:
        service.sessions.close_all("the service stopped")
        sock.close(0)
        if auth is not None:
            auth.stop()
    return service.requests


def _answer(sock, service: DefenceService) -> None:
    """Reads one frame set and answers it, or drops it; nothing it holds can raise out of here."""
    frames = sock.recv_multipart(copy=False)
    identity = frames[0].bytes
    body = frames[1:]
    client = _client(frames[-1])
    if len(body) == 2 and body[0].bytes == b"":
        envelope, payload = [b""], body[1].bytes  # a REQ socket's request
    elif len(body) == 1:
        envelope, payload = [], body[0].bytes  # a DEALER's, without the delimiter: answered alike
    else:
        warn("frames", "dropped a frame set from %s: %d frames after the identity; a request is [b'', message]",
             client, len(body))
        return
    try:
        message = unpack(payload)
    except WireError as err:
        warn("message", "bad message from %s: %s", client, err)
        reply = {"error": f"bad message: {err}"}
    else:
        try:
            reply = service.handle(identity, client, message)
        except Exception as err:  # the service's own fault: the car hears it, the service lives on
            LOG.exception("request %r from %s raised", message.get("op"), client)
            reply = {"error": f"{type(err).__name__}: {err}"}
    sock.send_multipart([identity, *envelope, pack(reply)])


def _client(frame) -> str:
    """Who sent a frame: the car's CURVE key where it authenticated, else its address."""
    for prop in ("User-Id", "Peer-Address"):
        try:
            value = frame.get(prop)
        except Exception:  # a property this transport does not have (inproc, ipc)
            continue
        if value:
            return value if prop == "Peer-Address" else f"car key {value[:8]}"
    return "a local peer"


def _authenticator(ctx, keys: ServerKeys):
    """The ZAP handler that admits the cars whose public keys are in ``keys.admitted``."""
    from zmq.auth.thread import ThreadAuthenticator

    auth = ThreadAuthenticator(ctx, log=LOG.getChild("auth"))
    auth.start()
    auth.configure_curve(domain="*", location=str(keys.admitted))
    return auth
