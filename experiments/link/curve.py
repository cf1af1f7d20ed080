"""CurveZMQ for the link between a car and ``racf serve``: who may talk, and who may answer.

A key folder (``racf serve keys DIR``) holds the service's pair and each car's:

    DIR/server.key            the service's public key: every car pins it
    DIR/server.key_secret     the service's secret key: only the service reads it
    DIR/cars/NAME.key_secret  a car's pair: only that car reads it
    DIR/admitted/NAME.key     a car's public key: the service admits the cars listed here

Secret files are created readable by their owner alone (mode 0600, in folders of mode 0700,
whatever the umask): no moment exists in which another user of the machine could read one. A key
folder is checked as OpenSSH's ``StrictModes`` checks one before a key in it is used or written: a
folder (or ``cars/``, ``admitted/``) that is a symbolic link, is not the user's own, or that others
may write, and a key file that is not the user's own, that others may write, or (a secret) read,
is refused in one line naming the fix: whoever can write ``admitted/`` admits any car, and a
link leads the keys where its maker chose. Every target is checked before anything is written,
so a refused folder is left as it was.

With CURVE (ZMTP's CURVE mechanism, libsodium's Curve25519 bundled in pyzmq's wheels) the car
authenticates the service by the key it pins and the service admits only listed cars, once per
connection; every message is then encrypted and authenticated. A man in the middle can neither
read a request nor forge an answer: the car's handshake with it fails.

The handshake's failure is the only thing a car hears of a refusal, so :func:`handshake_failure`
reads the socket's monitor events and says which one it was.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from racf.errors import UserError
from racf.keyfiles import check_file, check_folder, make_folder, write_new

__all__ = ["CarKeys", "ServerKeys", "make_keys", "handshake_failure", "is_loopback", "DEFAULT_CAR", "car_names",
           "refusal", "Handshake"]

DEFAULT_CAR = "car"
#: Who may read what racf serve keys writes: secrets their owner alone, folders their owner alone.
SECRET_MODE, FOLDER_MODE, PUBLIC_MODE = 0o600, 0o700, 0o644


@dataclass(frozen=True)
class CarKeys:
    """A car's key pair and the service key it pins (z85-encoded bytes)."""

    public: bytes
    secret: bytes
    server: bytes
    name: str = DEFAULT_CAR
    folder: str = ""

    @classmethod
    def load(cls, folder: str | Path, car: str | None = None) -> "CarKeys":
        """The pair of car ``car`` in ``folder`` (None: the only car there)."""
        folder = Path(folder)
        cars = car_names(folder)
        if car is None:
            if len(cars) != 1:
                have = f"it holds {', '.join(cars)}: name one with --service-car NAME" if cars else \
                    f"it holds none; make a key folder with `racf serve keys {folder}`"
                raise UserError(f"which car's key in {folder / 'cars'}? {have}")
            car = cars[0]
        elif car not in cars:
            held = f"it holds {', '.join(cars)}" if cars else "it holds none"
            raise UserError(f"no key of car {car!r} in {folder / 'cars'} ({held}); make one with "
                            f"`racf serve keys DIR --car {car}` and admit it where the service runs")
        for sub in (folder, folder / "cars"):
            check_folder(sub)
        public, secret = _load(folder / "cars" / f"{car}.key_secret", "this car's key pair", folder)
        server, _ = _load(folder / "server.key", "the service's public key", folder)
        return cls(public, secret, server, car, str(folder))

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
        admitted = folder / "admitted"
        for sub in (folder, admitted):
            check_folder(sub)
        public, secret = _load(folder / "server.key_secret", "the service's key pair", folder)
        if not any(admitted.glob("*.key")):
            raise UserError(f"no admitted car keys in {admitted}: make them with `racf serve keys {folder}`")
        for key in sorted(admitted.iterdir()):
            check_file(key)
        return cls(public, secret, admitted)


def car_names(folder: str | Path) -> list[str]:
    """The cars whose pairs ``folder`` holds (``cars/NAME.key_secret``), sorted."""
    return sorted(p.name[:-len(".key_secret")] for p in (Path(folder) / "cars").glob("*.key_secret"))


def _load(path: Path, what: str, folder: Path) -> tuple[bytes, bytes | None]:
    import zmq.auth

    if not path.is_file():
        raise UserError(f"{what} is not at {path}; make a key folder with `racf serve keys {folder}`")
    check_file(path)
    try:
        return zmq.auth.load_certificate(path)
    except Exception as err:  # a file that is not a ZeroMQ certificate: one line, whatever the parser says
        raise UserError(f"{path} is not a ZeroMQ key file ({type(err).__name__}: {err}); make a key folder with "
                        f"`racf serve keys {folder}`") from None


def make_keys(folder: str | Path, cars: tuple[str, ...] = (DEFAULT_CAR,)) -> list[Path]:
    """Writes the service's pair and one pair per car into ``folder`` (refusing to overwrite any);
    returns the files written. Each secret file is created with mode 0600 (never wider, not even
    for a moment), in folders of mode 0700."""
    import zmq

    folder = Path(folder)
    subs = (folder, folder / "cars", folder / "admitted")
    for sub in subs:
        check_folder(sub)
    targets = [folder / "server.key_secret", folder / "server.key",
               *(folder / sub / f"{car}{end}" for car in cars for sub, end in (("cars", ".key_secret"),
                                                                             ("admitted", ".key")))]
    existing = [p for p in targets if os.path.lexists(p)]  # a link, even one that leads nowhere, is there
    if existing:
        raise UserError(f"{existing[0]} exists; keys are never overwritten (choose another folder or remove it)")
    for sub in subs:
        make_folder(sub)
    for sub in subs[:2]:  # an existing folder of the user's own holds secrets too: its own alone
        sub.chmod(FOLDER_MODE)
    written = []
    for name, secret_path, public_path in (("server", folder / "server.key_secret", folder / "server.key"),
                                           *((car, folder / "cars" / f"{car}.key_secret",
                                              folder / "admitted" / f"{car}.key") for car in cars)):
        public, secret = zmq.curve_keypair()
        _write_certificate(secret_path, public, secret, SECRET_MODE)
        _write_certificate(public_path, public, None, PUBLIC_MODE)
        written += [public_path, secret_path] if name == "server" else [secret_path, public_path]
    return written


def _write_certificate(path: Path, public: bytes, secret: bytes | None, mode: int) -> None:
    """A ZeroMQ certificate (the format ``zmq.auth.load_certificate`` reads), created with ``mode``."""
    import datetime

    what = "**Secret** Certificate\n#   Do not give this file to anyone" if secret else "Public Certificate"
    text = (f"#   ****  Generated on {datetime.datetime.now()} by racf serve keys  ****\n#   ZeroMQ CURVE {what}\n\n"
            f"metadata\ncurve\n    public-key = \"{public.decode()}\"\n"
            + (f"    secret-key = \"{secret.decode()}\"\n" if secret else ""))
    write_new(path, text.encode(), mode)


#: What each handshake failure a car's socket reports means, from the car's side.
_FAILURES = {
    "HANDSHAKE_FAILED_AUTH": "the service refused this car's key (not among its admitted cars)",
    "HANDSHAKE_FAILED_NO_DETAIL": "the peer is not the service whose key this car pins (a wrong key, or a "
                                  "man in the middle)",
    # libzmq reports a box that fails its authentication after the handshake this way too.
    "HANDSHAKE_FAILED_PROTOCOL": "the peer broke CurveZMQ: one end has no keys, or a message failed its "
                                 "authentication (a man in the middle)",
}


def refusal(failure: str, keys: "CarKeys | None", endpoint: str) -> str:
    """What a car that failed the handshake with ``endpoint`` must be told, in one line: it has no keys,
    it pins another service's key, or the service does not admit its key (``failure``: the event's words)."""
    if keys is None:
        return (f"the service at {endpoint} speaks CurveZMQ and this car has no keys: give it the key folder the "
                f"service was started with (--service-keys DIR, made by `racf serve keys DIR`)")
    where = f"{keys.folder}/cars/{keys.name}.key_secret" if keys.folder else f"car {keys.name!r}"
    if failure == _FAILURES["HANDSHAKE_FAILED_AUTH"]:
        return (f"the service at {endpoint} does not admit this car's key ({where}): copy "
                f"admitted/{keys.name}.key into the admitted/ folder of the keys the service runs with, and "
                f"restart it")
    if failure == _FAILURES["HANDSHAKE_FAILED_NO_DETAIL"]:
        return (f"the peer at {endpoint} is not the service whose key this car pins ({keys.folder}/server.key): "
                f"the wrong key folder, or a man in the middle")
    return (f"the service at {endpoint} cannot be authenticated: {failure}; give the car the key folder the "
            f"service was started with (--service-keys DIR)")


@dataclass(frozen=True)
class Handshake:
    """What a car's socket monitor said of its link: whether it reached a peer (a TCP connection: something
    listens) and the newest handshake failure, in words (None: none)."""

    connected: bool
    failure: str | None


def handshake_failure(monitor, wait_ms: float = 0.0) -> Handshake:
    """Reads the events waiting on ``monitor`` (a socket's monitor socket). With ``wait_ms``, where the
    socket reached a peer but its handshake has not ended yet, its events are waited for up to that
    long (a loaded machine delivers them late); where nothing listens there is no handshake to wait for."""
    import time

    import zmq
    from zmq.utils.monitor import recv_monitor_message

    failure, connected, ended = None, False, False
    deadline = time.monotonic() + wait_ms / 1000.0

    def left_ms() -> int:
        return max(0, int((deadline - time.monotonic()) * 1000.0)) if connected and not ended else 0

    while monitor is not None and monitor.poll(left_ms()):
        event = zmq.Event(recv_monitor_message(monitor)["event"])
        connected |= event == zmq.EVENT_CONNECTED
        if event.name in _FAILURES:
            failure, ended = _FAILURES[event.name], True
        elif event == zmq.EVENT_HANDSHAKE_SUCCEEDED:
            failure, ended = None, True
    return Handshake(connected, failure)


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
