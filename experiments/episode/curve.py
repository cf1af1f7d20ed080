"""CurveZMQ for the link between a car and ``racf serve``: who may talk, and who may answer.

A key folder (``racf serve keys DIR``) holds the service's pair and each car's:

    DIR/server.key            the service's public key: every car pins it
    DIR/server.key_secret     the service's secret key: only the service reads it
    DIR/cars/NAME.key_secret  a car's pair: only that car reads it
    DIR/admitted/NAME.key     a car's public key: the service admits the cars listed here

With CURVE (ZMTP's CURVE mechanism, libsodium's Curve25519 bundled in pyzmq's wheels) the car
authenticates the service by the key it pins and the service admits only listed cars, once per
connection; every message is then encrypted and authenticated. A man in the middle can neither
read a request nor forge an answer: the car's handshake with it fails.

The handshake's failure is the only thing a car hears of a refusal, so :func:`handshake_failure`
reads the socket's monitor events and says which one it was.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from racf.errors import UserError

__all__ = ["CarKeys", "ServerKeys", "make_keys", "handshake_failure", "is_loopback", "DEFAULT_CAR"]

DEFAULT_CAR = "car"


@dataclass(frozen=True)
class CarKeys:
    """A car's key pair and the service key it pins (z85-encoded bytes)."""

    public: bytes
    secret: bytes
    server: bytes

    @classmethod
    def load(cls, folder: str | Path, car: str = DEFAULT_CAR) -> "CarKeys":
        folder = Path(folder)
        public, secret = _load(folder / "cars" / f"{car}.key_secret", "this car's key pair", folder)
        server, _ = _load(folder / "server.key", "the service's public key", folder)
        return cls(public, secret, server)

    def apply(self, socket) -> None:
        """Makes ``socket`` (before it connects) a CURVE client that talks only to the pinned service."""
        socket.curve_secretkey, socket.curve_publickey, socket.curve_serverkey = self.secret, self.public, self.server


@dataclass(frozen=True)
class ServerKeys:
    """The service's key pair and the folder of admitted cars' public keys."""

    public: bytes
    secret: bytes
    admitted: Path

    @classmethod
    def load(cls, folder: str | Path) -> "ServerKeys":
        folder = Path(folder)
        public, secret = _load(folder / "server.key_secret", "the service's key pair", folder)
        admitted = folder / "admitted"
        if not any(admitted.glob("*.key")):
            raise UserError(f"no admitted car keys in {admitted}: make them with `racf serve keys {folder}`")
        return cls(public, secret, admitted)


def _load(path: Path, what: str, folder: Path) -> tuple[bytes, bytes | None]:
    import zmq.auth

    if not path.is_file():
        raise UserError(f"{what} is not at {path}; make a key folder with `racf serve keys {folder}`")
    try:
        return zmq.auth.load_certificate(path)
    except Exception as err:  # a file that is not a ZeroMQ certificate: one line, whatever the parser says
        raise UserError(f"{path} is not a ZeroMQ key file ({type(err).__name__}: {err}); make a key folder with "
                        f"`racf serve keys {folder}`") from None


def make_keys(folder: str | Path, cars: tuple[str, ...] = (DEFAULT_CAR,)) -> list[Path]:
    """Writes the service's pair and one pair per car into ``folder`` (refusing to overwrite any);
    returns the files written."""
    import zmq.auth

    folder = Path(folder)
    targets = [folder / "server.key_secret", *(folder / "cars" / f"{car}.key_secret" for car in cars)]
    existing = [p for p in targets if p.exists()]
    if existing:
        raise UserError(f"{existing[0]} exists; keys are never overwritten (choose another folder or remove it)")
    for sub in ("cars", "admitted"):
        (folder / sub).mkdir(parents=True, exist_ok=True)
    written = [Path(p) for p in zmq.auth.create_certificates(folder, "server")]
    for car in cars:
        public, secret = (Path(p) for p in zmq.auth.create_certificates(folder / "cars", car))
        admitted = folder / "admitted" / public.name
        admitted.write_bytes(public.read_bytes())
        public.unlink()  # the car's public key lives where the service admits it
        secret.chmod(0o600)
        written += [secret, admitted]
    (folder / "server.key_secret").chmod(0o600)
    return written


#: What each handshake failure a car's socket reports means, from the car's side.
_FAILURES = {
    "HANDSHAKE_FAILED_AUTH": "the service refused this car's key (not among its admitted cars)",
    "HANDSHAKE_FAILED_NO_DETAIL": "the peer is not the service whose key this car pins (a wrong key, or a "
                                  "man in the middle)",
    # libzmq reports a box that fails its authentication after the handshake this way too.
    "HANDSHAKE_FAILED_PROTOCOL": "the peer broke CurveZMQ: one end has no keys, or a message failed its "
                                 "authentication (a man in the middle)",
}


def handshake_failure(monitor, wait_ms: float = 0.0) -> str | None:
    """The newest handshake failure among the events waiting on ``monitor`` (a socket's monitor
    socket), in words; None when there was none. With ``wait_ms``, where the socket reached a peer but
    no failure has come yet, the handshake's events are waited for up to that long (a loaded machine
    delivers them late); where nothing listens there is no handshake to wait for."""
    import time

    import zmq
    from zmq.utils.monitor import recv_monitor_message

    failure, connected = None, False
    deadline = time.monotonic() + wait_ms / 1000.0

    def left_ms() -> int:
        waiting = connected and failure is None
        return max(0, int((deadline - time.monotonic()) * 1000.0)) if waiting else 0

    while monitor is not None and monitor.poll(left_ms()):
        event = zmq.Event(recv_monitor_message(monitor)["event"])
        connected |= event == zmq.EVENT_CONNECTED
        if event.name in _FAILURES:
            failure = _FAILURES[event.name]
        elif event == zmq.EVENT_HANDSHAKE_SUCCEEDED:
            failure = None
    return failure


def is_loopback(endpoint: str) -> bool:
    """Whether a bind address reaches only this machine (an ``ipc://`` path, or a loopback host)."""
    import ipaddress

    if endpoint.startswith(("ipc://", "inproc://")):
        return True
    host = endpoint.split("://", 1)[-1].rsplit(":", 1)[0].strip("[]")
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False  # a hostname or an interface name ('*', 'eth0'): reachable from elsewhere
