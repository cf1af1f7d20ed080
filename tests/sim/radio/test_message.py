"""A broadcast's bytes: what a sender signs is what the car reads, and any other bytes are refused."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
import numpy as np
from nacl.signing import SigningKey, VerifyKey

from racf.sim.radio import FLEET, SIGNED_BYTES, Broadcast, V2VMessage, open_signed, sign
from racf.sim.radio.message import MESSAGE_BYTES, parse
from tests.conftest import TEST_FLEET

_finite = st.floats(-1e3, 1e3, allow_nan=False, width=32)
_messages = st.builds(lambda sender, seq, t, x, y, yaw, v, a, brake: V2VMessage(seq, t, Broadcast(sender, x, y, yaw, v, a, brake)),
                      st.sampled_from(FLEET), st.integers(0, 2**32 - 1), st.floats(0, 1e4, allow_nan=False),
                      _finite, _finite, _finite, _finite, _finite, st.booleans())


@settings(max_examples=60, deadline=None)
@given(_messages)
def test_a_signed_message_reads_back_as_sent(message):
    raw = sign(message, TEST_FLEET.signing_key(message.state.sender))
    assert len(raw) == SIGNED_BYTES == MESSAGE_BYTES + 64
    opened = open_signed(raw, TEST_FLEET.trust_store())
    assert opened.refused == "" and opened.message == message


@settings(max_examples=60, deadline=None)
@given(_messages, st.integers(0, SIGNED_BYTES - 1), st.integers(1, 255))
def test_any_byte_changed_on_the_air_is_refused(message, where, flip):
    raw = bytearray(sign(message, TEST_FLEET.signing_key(message.state.sender)))
    raw[where] ^= flip
    assert open_signed(bytes(raw), TEST_FLEET.trust_store()).message is None


def test_a_key_outside_the_fleet_or_a_sender_the_car_does_not_trust_is_refused_and_says_which():
    message = V2VMessage(1, 0.5, Broadcast(1, 1.0, 2.0, 0.0, 0.6, 0.0, False))
    assert open_signed(sign(message, SigningKey(bytes(range(32)))), TEST_FLEET.trust_store()).refused == "bad signature"
    assert open_signed(sign(message, TEST_FLEET.signing_key(1)), {s: k for s, k in TEST_FLEET.trust_store().items() if s in (2, 3)}).refused == "unknown sender"
    assert open_signed(b"\x01" * 10, TEST_FLEET.trust_store()).refused == "malformed"
    assert open_signed(sign(message, TEST_FLEET.signing_key(2)), TEST_FLEET.trust_store()).refused == "bad signature"  # another's key


def test_a_message_of_another_version_or_not_finite_does_not_parse():
    good = V2VMessage(1, 0.5, Broadcast(1, 1.0, 2.0, 0.0, 0.6, 0.0, True)).to_bytes()
    assert parse(good).state.braking is True
    assert parse(b"\x02" + good[1:]) is None
    assert parse(V2VMessage(1, math.nan, Broadcast(1, 1.0, 2.0, 0.0, 0.6, 0.0, False)).to_bytes()) is None
    assert parse(good[:-1]) is None


def test_the_fleets_keys_come_from_the_world_s_stream_and_from_no_name():
    import hashlib

    from racf.sim.radio import FleetKeys

    again, other = FleetKeys.draw(np.random.default_rng(0)), FleetKeys.draw(np.random.default_rng(1))
    assert TEST_FLEET.signing_key(1).encode() == again.signing_key(1).encode() != other.signing_key(1).encode()
    assert len({TEST_FLEET.signing_key(s).verify_key.encode() for s in FLEET}) == len(FLEET)
    # The old keys were the SHA-256 of a public name: anyone could sign as any vehicle.
    named = {hashlib.sha256(f"racf-fleet/vehicle-{s}".encode()).digest() for s in FLEET}
    assert not named & {TEST_FLEET.signing_key(s).encode() for s in FLEET}
    with pytest.raises(ValueError, match="not in the fleet"):
        TEST_FLEET.signing_key(99)
    # The car is provisioned with public keys only; an insider is handed a key by name, and counted.
    assert all(isinstance(k, VerifyKey) for k in TEST_FLEET.trust_store().values())
    fleet = FleetKeys.draw(np.random.default_rng(2))
    assert fleet.hand_over(1) is fleet.signing_key(1) and fleet.handed_over == [1]


def test_a_brake_flag_other_than_0_or_1_and_a_message_of_the_wrong_length_are_refused():
    good = V2VMessage(1, 0.5, Broadcast(1, 1.0, 2.0, 0.0, 0.6, 0.0, False))
    raw = sign(good, TEST_FLEET.signing_key(1))
    assert parse(good.to_bytes()[:-1] + bytes([2])) is None
    assert open_signed(raw + b"\0", TEST_FLEET.trust_store()).refused == "malformed"
    assert open_signed(raw[:-1], TEST_FLEET.trust_store()).refused == "malformed"
    assert 1 in FLEET and 8 in FLEET and 0 not in FLEET and 9 not in FLEET
