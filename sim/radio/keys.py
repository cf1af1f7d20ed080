"""The fleet's keys: each vehicle's Ed25519 signing key, and the trust store of public keys a car carries.

In a real fleet an authority issues each vehicle its key pair and the cars carry the public keys
(IEEE 1609.2's certificates). Nobody derives a key from anything public:

- the simulation's fleet (:class:`FleetKeys`) is drawn from the world's own random stream at each
  episode's reset (the same bytes on every machine for one episode, and nowhere else): the world's
  radio signs with it, the car is provisioned with its public keys only (:meth:`FleetKeys.trust_store`),
  and an attack that needs a fleet key is an insider handed one vehicle's key by name
  (:meth:`FleetKeys.hand_over`, counted);
- a real fleet's keys are files (:func:`write_fleet_keys`, PyNaCl's generator; the car loads the
  public ones with :func:`load_trust_store`), in folders checked as OpenSSH's StrictModes checks
  them (:mod:`racf.keyfiles`).

Vehicle ``i``'s key was once the SHA-256 of the name "racf-fleet/vehicle-i": anyone could sign as any
vehicle, and the car took 80 messages from a made-up "vehicle 5" 0.6 m ahead for the car ahead.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
from nacl.encoding import HexEncoder
from nacl.signing import SigningKey, VerifyKey

from racf.keyfiles import check_file, check_folder, make_folder, write_new

__all__ = ["FLEET", "FleetKeys", "write_fleet_keys", "load_trust_store"]

#: The fleet's vehicles: their ids (a lead car broadcasts as vehicle 1).
FLEET = tuple(range(1, 9))


def _member(sender: int) -> int:
    if isinstance(sender, bool) or not isinstance(sender, (int, np.integer)) or int(sender) not in FLEET:
        raise ValueError(f"vehicle {sender!r} is not in the fleet; its ids are {FLEET}")
    return int(sender)


class FleetKeys:
    """The simulated fleet's signing keys, held by the world (see the module).

    Args:
        keys: vehicle id -> its signing key.
    """

    def __init__(self, keys: dict[int, SigningKey]) -> None:
        self._keys = {_member(s): k for s, k in keys.items()}
        self.handed_over: list[int] = []  # which vehicles' keys an insider was given, in order

    @classmethod
    def draw(cls, rng: np.random.Generator) -> "FleetKeys":
        """A fleet whose keys are 32 bytes each of ``rng`` (the world's stream: an episode's own)."""
        return cls({s: SigningKey(rng.bytes(32)) for s in FLEET})

    def signing_key(self, sender: int) -> SigningKey:
        """Vehicle ``sender``'s key, for the world's radio to sign what it says."""
        return self._keys[_member(sender)]

    def trust_store(self) -> dict[int, VerifyKey]:
        """The public keys a car is provisioned with, by sender id."""
        return {s: k.verify_key for s, k in self._keys.items()}

    def hand_over(self, sender: int) -> SigningKey:
        """Vehicle ``sender``'s key, handed to an insider (a vehicle that lies, or a thief): counted."""
        key = self.signing_key(sender)
        self.handed_over.append(_member(sender))
        return key


def write_fleet_keys(folder: str | Path, vehicles=FLEET) -> list[Path]:
    """A real fleet's keys, made with PyNaCl's generator: ``folder/vehicles/ID.signing_key`` (each
    vehicle's secret, 0600) and ``folder/trusted/ID.verify_key`` (what a car loads); never over a
    file that exists; returns the files written."""
    folder = Path(folder)
    subs = (folder, folder / "vehicles", folder / "trusted")
    for sub in subs:
        check_folder(sub)
    ids = [_member(v) for v in vehicles]
    targets = [p for v in ids for p in (folder / "vehicles" / f"{v}.signing_key", folder / "trusted" / f"{v}.verify_key")]
    existing = [p for p in targets if os.path.lexists(p)]
    if existing:
        raise FileExistsError(f"{existing[0]} exists; keys are never overwritten (choose another folder or remove it)")
    for sub in subs:
        make_folder(sub)
    written = []
    for v in ids:
        key = SigningKey.generate()
        secret, public = folder / "vehicles" / f"{v}.signing_key", folder / "trusted" / f"{v}.verify_key"
        write_new(secret, key.encode(HexEncoder) + b"\n", 0o600)
        write_new(public, key.verify_key.encode(HexEncoder) + b"\n", 0o644)
        written += [secret, public]
    return written


def load_trust_store(folder: str | Path) -> dict[int, VerifyKey]:
    """The public keys in ``folder`` (``ID.verify_key`` files, hex), by sender id; the folder and each
    file checked first. Raises ValueError naming a file that is no key of a fleet vehicle."""
    folder = Path(folder)
    check_folder(folder)
    trusted = {}
    for path in sorted(folder.glob("*.verify_key")):
        check_file(path)
        try:
            sender = _member(int(path.name.removesuffix(".verify_key")))
            trusted[sender] = VerifyKey(path.read_bytes().strip(), encoder=HexEncoder)
        except Exception as err:  # a name or bytes that are no key: one line naming the file
            raise ValueError(f"{path} is no vehicle's public key ({type(err).__name__}: {err})") from None
    if not trusted:
        raise ValueError(f"no vehicle's public key (ID.verify_key) in {folder}")
    return trusted
