"""The fleet's keys: each vehicle's Ed25519 signing key, and the trust store a car carries.

In a real fleet a certificate authority issues each vehicle its key pair and the cars carry the
authority's certificates (IEEE 1609.2). The simulation stands for that with a fixed fleet: vehicle
``i``'s key is made from its name (the same on every machine, so an episode's signatures are the
same bytes everywhere), and a car's trust store holds the public keys of the fleet's vehicles. An
attacker outside the fleet has no key in it; an insider (a vehicle that lies) signs with its own.
"""

from __future__ import annotations

import hashlib

from nacl.signing import SigningKey, VerifyKey

__all__ = ["FLEET", "fleet_key", "trust_store"]

#: The fleet's vehicles: their ids (a lead car broadcasts as vehicle 1).
FLEET = tuple(range(1, 9))


def fleet_key(sender: int) -> SigningKey:
    """Vehicle ``sender``'s signing key (its seed: the SHA-256 of its name in the fleet)."""
    if sender not in FLEET:
        raise ValueError(f"vehicle {sender!r} is not in the fleet; its ids are {FLEET}")
    return SigningKey(hashlib.sha256(f"racf-fleet/vehicle-{sender}".encode()).digest())


def trust_store(senders=FLEET) -> dict[int, VerifyKey]:
    """The public keys a car trusts, by sender id."""
    return {s: fleet_key(s).verify_key for s in senders}
