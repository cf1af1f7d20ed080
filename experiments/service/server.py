"""``racf serve``: defences in their own process, one instance per car, behind ZeroMQ.

A ROUTER socket takes each car's requests (``racf.experiments.link.remote`` speaks the other
end; :mod:`~racf.experiments.service.handler` answers them). No message stops it: a frame set
that is not a request (``[identity, b"", payload]`` from a REQ socket, ``[identity, payload]``
from a DEALER) is dropped, a payload that is not a message is answered with an error, each in
one logged line; ZeroMQ's ``MAXMSGSIZE`` cuts off a peer that sends more than a message may
hold. A peer that does not finish what it started is cut off too: libzmq allocates a frame's
declared size when its header arrives, and 300 connections that each sent 1 MiB less one byte
once held 320 MB for as long as they stayed open. The handshake must end within ``HANDSHAKE_MS``,
and each connection is pinged every ``HEARTBEAT_MS``: a peer whose answer does not arrive within
``HEARTBEAT_TIMEOUT_MS`` (it cannot, behind a frame it never completes) is dropped with what it
held. With keys (:mod:`~racf.experiments.link.curve`) the socket is a CURVE server and a
ZAP handler admits only the listed cars.

A session ends with its connection: the socket's monitor reports each closed connection by its
file descriptor, and each request says which descriptor it came on (``SRCFD``). libzmq's one I/O
thread reports a closed connection before it accepts the next, so a descriptor the system hands out
again is read as ended before any request arrives on it (the monitor is drained before each request).
"""

from __future__ import annotations

import math

from racf.errors import UserError
from racf.experiments.link.curve import ServerKeys
from racf.experiments.link.wire import MAX_MESSAGE_BYTES, WireError, pack, unpack
from racf.experiments.service.handler import DefenceService, warm_up
from racf.experiments.service.sessions import LOG, Sessions, warn

#: On a plain link a client is its address: any process on the car's host, or behind its NAT, is the same client.
PLAIN_CAPS = ("plain link: the per-client cap counts network addresses, which every process on a host (or behind "
              "a NAT) shares; it bounds mistakes, not attackers (serve with --keys to cap per car key)")

__all__ = ["DefenceService", "serve", "warm_up", "HANDSHAKE_MS", "HEARTBEAT_MS", "HEARTBEAT_TIMEOUT_MS"]

#: A connection's ZeroMQ handshake must end within this, ms (libzmq's default: 30 s).
HANDSHAKE_MS = 2000
#: Every connection is pinged this often, ms, and dropped when nothing whole comes back within the timeout.
HEARTBEAT_MS, HEARTBEAT_TIMEOUT_MS = 1000, 3000


def serve(endpoint: str, offers: dict[str, dict] | None = None, ready=None,
          max_requests: float = math.inf, stop=None, keys: ServerKeys | None = None,
          sessions: Sessions | None = None) -> int:
    """Serves the defences ``offers`` (name -> the operator's options; None: every registered one with
    its defaults) at ``endpoint`` until interrupted,
    ``stop`` (a ``threading.Event``) is set or ``max_requests`` are answered (then it stops
    answering, as a dead service would); returns the requests answered. ``ready(endpoint)`` is
    called once the socket is bound. ``keys``: serve over CURVE, to the admitted cars only."""
    import zmq

    service = DefenceService(offers, sessions)
    ctx = zmq.Context.instance()
    auth = _authenticator(ctx, keys) if keys is not None else None
    sock = ctx.socket(zmq.ROUTER)
    sock.setsockopt(zmq.LINGER, 0)
    sock.setsockopt(zmq.MAXMSGSIZE, MAX_MESSAGE_BYTES)
    sock.setsockopt(zmq.HANDSHAKE_IVL, HANDSHAKE_MS)
    sock.setsockopt(zmq.HEARTBEAT_IVL, HEARTBEAT_MS)
    sock.setsockopt(zmq.HEARTBEAT_TIMEOUT, HEARTBEAT_TIMEOUT_MS)
    if keys is not None:
        sock.curve_secretkey, sock.curve_publickey, sock.curve_server = keys.secret, keys.public, True
    monitor = sock.get_monitor_socket(zmq.EVENT_DISCONNECTED)
    try:
        sock.bind(endpoint)
    except zmq.ZMQError as err:
        sock.disable_monitor()
        monitor.close(0)
        sock.close(0)
        if auth is not None:
            auth.stop()
        raise UserError(f"cannot listen at {endpoint}: {err}") from None
    bound = sock.getsockopt_string(zmq.LAST_ENDPOINT)
    if keys is None:
        LOG.warning(PLAIN_CAPS)
    if ready is not None:
        ready(bound)
    poller = zmq.Poller()
    poller.register(sock, zmq.POLLIN)
    poller.register(monitor, zmq.POLLIN)
    try:
        while service.requests < max_requests and not (stop is not None and stop.is_set()):
            service.sessions.expire()
            ready_sockets = dict(poller.poll(100))
            _end_closed_connections(monitor, service.sessions)
            if sock in ready_sockets:
                _answer(sock, service)
    finally:
        service.sessions.close_all("the service stopped")
        sock.disable_monitor()
        monitor.close(0)
        sock.close(0)
        if auth is not None:
            auth.stop()
    return service.requests


def _end_closed_connections(monitor, sessions: Sessions) -> None:
    """Ends the sessions of every connection the monitor reports closed (those waiting now)."""
    import zmq
    from zmq.utils.monitor import recv_monitor_message

    while monitor.poll(0):
        event = recv_monitor_message(monitor)
        if event["event"] == zmq.EVENT_DISCONNECTED:
            sessions.end_connection(int(event["value"]))


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
        reply = service.handle(identity, client, message, connection=_connection(frames[-1]))
    sock.send_multipart([identity, *envelope, pack(reply)])


def _client(frame) -> str:
    """Who sent a frame: the car's CURVE key where it authenticated (all of it: the per-client cap is
    per key), else its address."""
    for prop in ("User-Id", "Peer-Address"):
        try:
            value = frame.get(prop)
        except Exception:  # a property this transport does not have (inproc, ipc)
            continue
        if value:
            return value if prop == "Peer-Address" else f"car key {value}"
    return "a local peer"


def _connection(frame) -> int | None:
    """The file descriptor of the connection a frame came on (None where the transport has none)."""
    import zmq

    try:
        fd = frame.get(zmq.SRCFD)
    except Exception:  # inproc has no descriptor
        return None
    return fd if isinstance(fd, int) and fd >= 0 else None


def _authenticator(ctx, keys: ServerKeys):
    """The ZAP handler that admits the cars whose public keys are in ``keys.admitted``."""
    from zmq.auth.thread import ThreadAuthenticator

    auth = ThreadAuthenticator(ctx, log=LOG.getChild("auth"))
    auth.start()
    auth.configure_curve(domain="*", location=str(keys.admitted))
    return auth
