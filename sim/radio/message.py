"""A vehicle's broadcast of its own state, and its signed bytes.

The message is a fixed 36-byte little-endian record (version, sender, sequence number, the time it
was sent on the fleet's shared clock, the sender's x, y and yaw in the map frame, its speed, its
acceleration and whether it brakes), followed by its 64-byte Ed25519 signature over those bytes:
100 bytes on the air. A message that does not parse, names a sender the car does not trust, or
whose signature does not verify is no message (:func:`open_signed` says which).
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass

from nacl.exceptions import BadSignatureError
from nacl.signing import SigningKey, VerifyKey

__all__ = ["V2VMessage", "Broadcast", "MESSAGE_BYTES", "SIGNED_BYTES", "VERSION", "sign", "open_signed",
           "parse", "Opened", "REFUSALS"]

VERSION = 1
#: Why a received message is refused, the one vocabulary of the radio and the car's receiver, in the
#: order the checks run: its bytes (``malformed``), its sender (``unknown sender``: not in the car's
#: trust store), its signature (``bad signature``), its number and time (``replayed``: not past the
#: sender's last; ``out of window``: further past it than the sender can have sent since), its age
#: (``stale``: too old, or from the future).
REFUSALS = ("malformed", "unknown sender", "bad signature", "replayed", "out of window", "stale")
_LAYOUT = struct.Struct("<BHIdfffffB")
#: The message's bytes before the signature.
MESSAGE_BYTES = _LAYOUT.size
#: The message and its Ed25519 signature.
SIGNED_BYTES = MESSAGE_BYTES + 64


@dataclass(frozen=True)
class Broadcast:
    """What a vehicle says of itself at one instant (a world manager's, before it is signed).

    Attributes:
        sender: the vehicle's id in the fleet (its key's).
        x_m, y_m, yaw_rad: its pose, map frame (its body origin).
        speed_mps, accel_mps2: along its heading.
        braking: its brake is on.
    """

    sender: int
    x_m: float
    y_m: float
    yaw_rad: float
    speed_mps: float
    accel_mps2: float
    braking: bool


@dataclass(frozen=True)
class V2VMessage:
    """One message on the air: a broadcast, numbered and stamped by its sender."""

    seq: int
    t_s: float
    state: Broadcast

    def to_bytes(self) -> bytes:
        s = self.state
        return _LAYOUT.pack(VERSION, s.sender, self.seq, self.t_s, s.x_m, s.y_m, s.yaw_rad, s.speed_mps, s.accel_mps2,
                            int(s.braking))


def parse(raw: bytes) -> V2VMessage | None:
    """The message in ``raw``'s first :data:`MESSAGE_BYTES` (None: not a version-1 message of finite numbers)."""
    if len(raw) < MESSAGE_BYTES:
        return None
    version, sender, seq, t, x, y, yaw, v, a, brake = _LAYOUT.unpack(raw[:MESSAGE_BYTES])
    if version != VERSION or brake > 1 or not all(math.isfinite(f) for f in (t, x, y, yaw, v, a)):
        return None
    return V2VMessage(seq, t, Broadcast(sender, x, y, yaw, v, a, bool(brake)))


def sign(message: V2VMessage, key: SigningKey) -> bytes:
    """The message's bytes followed by their Ed25519 signature with ``key``."""
    body = message.to_bytes()
    return body + key.sign(body).signature


@dataclass(frozen=True)
class Opened:
    """What the car made of one received message: the message (None unless it verified) and why not."""

    message: V2VMessage | None
    refused: str = ""  # "" (verified), or the first three of REFUSALS


def open_signed(raw: bytes, trusted: dict[int, VerifyKey]) -> Opened:
    """Checks ``raw`` against the trust store ``trusted`` (sender -> public key)."""
    message = parse(raw) if len(raw) == SIGNED_BYTES else None
    if message is None:
        return Opened(None, "malformed")
    key = trusted.get(message.state.sender)
    if key is None:
        return Opened(None, "unknown sender")
    try:
        key.verify(raw[:MESSAGE_BYTES], raw[MESSAGE_BYTES:])
    except BadSignatureError:
        return Opened(None, "bad signature")
    return Opened(message)
