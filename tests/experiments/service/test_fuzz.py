"""No message stops the service: any frame set, any payload, the protocol's requests with their fields
broken, is answered with an error or dropped, and a car asking next is answered."""

from __future__ import annotations

import math

import msgpack
import numpy as np
import pytest
import zmq
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from racf.experiments.link.wire import MAX_MESSAGE_BYTES, PROTOCOL, pack, unpack
from racf.experiments.service.stress import fuzz, ping
from tests.conftest import start_service


@pytest.fixture(scope="module")
def endpoint():
    stops = []
    yield start_service("raw", stops)
    for stop, thread in stops:
        stop.set()
        thread.join(5)


def _send(endpoint: str, frames: list[bytes], wait_ms: float = 500.0) -> list[bytes] | None:
    """Sends ``frames`` from a DEALER (the ROUTER sees them after the identity); its answer, or None."""
    sock = zmq.Context.instance().socket(zmq.DEALER)
    sock.setsockopt(zmq.LINGER, 0)
    sock.connect(endpoint)
    try:
        sock.send_multipart(frames)
        return sock.recv_multipart() if sock.poll(wait_ms) else None
    finally:
        sock.close(0)


def _error(answer: list[bytes] | None) -> str:
    assert answer is not None, "no answer"
    return unpack(answer[-1])["error"]


def _hello_then(endpoint: str, request: dict) -> dict:
    """A REQ car that opens a session, then sends ``request``; the answer."""
    sock = zmq.Context.instance().socket(zmq.REQ)
    sock.setsockopt(zmq.LINGER, 0)
    sock.connect(endpoint)
    try:
        hello = {"op": "hello", "id": 1, "protocol": PROTOCOL, "estimator": "raw", "options": {}}
        for message in (hello, {"id": 2, **request} if isinstance(request, dict) else request):
            sock.send(pack(message) if isinstance(message, dict) else message)
            assert sock.poll(5000)
            answer = unpack(sock.recv())
        return answer
    finally:
        sock.close(0)


ND = {"__nd__": True, "dtype": "<f8", "shape": [2], "data": b"\0" * 16}
#: (what, frames after the identity, words of the error; None: dropped without an answer)
CORPUS = [
    ("five frames", [b"", b"a", b"b", b"c", b"d"], None),
    ("a non-empty delimiter", [b"x", pack({"op": "ping", "id": 1})], None),
    ("no frames but the delimiter", [b""], "not a msgpack message"),
    ("random bytes", [b"", b"\xc1\xff\x00garbage"], "not a msgpack message"),
    ("trailing bytes", [b"", pack({"op": "ping", "id": 1}) + b"\x01"], "not a msgpack message"),
    ("a list", [b"", msgpack.packb([1, 2, 3])], "a message is a map, got list"),
    ("a number, without the delimiter", [msgpack.packb(7)], "a message is a map, got int"),
    ("an object array", [b"", pack({"op": "ping", "a": {**ND, "dtype": "|O"}})], "dtype '|O' is not allowed"),
    ("an array whose bytes lie", [b"", pack({"op": "ping", "a": {**ND, "shape": [10**6, 10**6]}})], "does not match"),
    ("a negative shape", [b"", pack({"op": "ping", "a": {**ND, "shape": [-2]}})], "not a list of at most 4 sizes"),
    ("a deep nest", [b"", msgpack.packb({"a": [[[[[[[[[[1]]]]]]]]]] * 5000})], "not a msgpack message"),
    ("a long string", [b"", msgpack.packb({"op": "x" * 10_000})], "not a msgpack message"),
    ("estimate before hello", [b"", pack({"op": "estimate", "id": 1})], "no session"),
    ("an unknown op", [b"", pack({"op": "launch", "id": 1})], "no session"),
    ("another protocol", [b"", pack({"op": "hello", "protocol": 99})], f"this service speaks {PROTOCOL}"),
    ("a name that is a number", [b"", pack({"op": "hello", "id": 1, "protocol": PROTOCOL, "estimator": 5})],
     "needs estimator"),
    ("a request without an id", [b"", pack({"op": "ping"})], "id must be an int"),
    ("an id that is not an int", [b"", pack({"op": "ping", "id": "7"})], "id must be an int"),
    ("an id that is a bool", [b"", pack({"op": "ping", "id": True})], "id must be an int"),
    ("a negative id", [b"", pack({"op": "ping", "id": -1})], "id must be an int"),
]


@pytest.mark.parametrize("what, frames, words", CORPUS, ids=[c[0] for c in CORPUS])
def test_a_malformed_frame_set_is_answered_or_dropped(endpoint, what, frames, words):
    answer = _send(endpoint, frames)
    if words is None:
        assert answer is None
    else:
        assert words in _error(answer)
    assert ping(endpoint)


SESSION_CORPUS = [
    ("a sample that is a string", {"op": "estimate", "sample": "x", "speed": 1.0, "dt": 0.02, "yaw_rate": 0.0},
     "a sample is a map"),
    ("a sample missing its fields", {"op": "estimate", "sample": {"d_meas": 1.0}, "speed": 1.0, "dt": 0.02,
                                     "yaw_rate": 0.0}, "not a sample"),
    ("a sample with a field of text", {"op": "estimate", "sample": {"detection": None, "d_meas": "near", "c_meas": 1.0,
                                                                    "lidar_m": 1.0, "bearing_rad": 0.0},
                                       "speed": 1.0, "dt": 0.02, "yaw_rate": 0.0}, "must be a number"),
    ("a mask too large", {"op": "estimate", "sample": {"detection": {"mask": np.zeros(4, np.uint8), "shape": [10**5, 2],
                                                                     "box": [0, 0, 1, 1], "confidence": 1.0,
                                                                     "area_px": 1, "centroid": [0, 0]},
                                                       "d_meas": 1.0, "c_meas": 1.0, "lidar_m": 1.0,
                                                       "bearing_rad": 0.0},
                          "speed": 1.0, "dt": 0.02, "yaw_rate": 0.0}, "outside 1..4096"),
    ("a speed that is text", {"op": "estimate", "sample": {"detection": None, "d_meas": 1.0, "c_meas": 1.0,
                                                           "lidar_m": 1.0, "bearing_rad": 0.0},
                              "speed": "fast", "dt": 0.02, "yaw_rate": 0.0}, "speed must be a number"),
    ("a calibration of nonsense", {"op": "calibrate", "calibration": {"camera": 3}}, "not a car calibration"),
    ("would_pass with a list", {"op": "would_pass", "kwargs": [1]}, "needs kwargs"),
    ("an unknown op", {"op": "launch"}, "unknown request 'launch'"),
]


@pytest.mark.parametrize("what, request_, words", SESSION_CORPUS, ids=[c[0] for c in SESSION_CORPUS])
def test_a_malformed_request_in_a_session_is_an_error_and_the_service_serves_on(endpoint, what, request_, words):
    assert words in _hello_then(endpoint, request_)["error"]
    assert ping(endpoint)


def test_a_message_over_the_limit_is_cut_off_and_the_service_serves_on(endpoint):
    assert _send(endpoint, [b"", b"\x00" * (MAX_MESSAGE_BYTES + 1)], wait_ms=300) is None
    assert ping(endpoint)


msgpack_values = st.recursive(
    st.none() | st.booleans() | st.integers(-2**63, 2**64 - 1) | st.floats() | st.text(max_size=20)
    | st.binary(max_size=40),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8), inner, max_size=4),
    max_leaves=12)
ops = st.sampled_from(["ping", "hello", "calibrate", "reset", "estimate", "would_pass", "bye", "x"])


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.lists(st.binary(max_size=64), min_size=1, max_size=6))
def test_any_frames_leave_the_service_answering(endpoint, frames):
    _send(endpoint, frames, wait_ms=20)
    assert ping(endpoint)


@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(ops, st.dictionaries(st.sampled_from(["protocol", "estimator", "options", "sample", "speed", "dt", "yaw_rate",
                                            "calibration", "kwargs"]), msgpack_values, max_size=6))
def test_any_request_leaves_the_service_answering(endpoint, op, fields):
    request = {**fields, "op": op}
    answer = _hello_then(endpoint, msgpack.packb(request, use_bin_type=True))
    assert isinstance(answer, dict)
    assert ping(endpoint)


def test_a_thousand_fuzzed_frame_sets_in_batches(endpoint):
    """The stress bench's fuzz, small: a ping answered after every batch."""
    out = fuzz(endpoint, 1000, seed=1, batch=250)
    assert out == {**out, "requests": 1000, "batches": 4, "pings_answered": 4} and out["replies"] > 0
    assert not math.isnan(out["replies"])


def test_a_flood_of_bad_requests_is_a_few_log_lines_with_their_count(endpoint, caplog):
    """300 junk requests or more, over 3.3 s: a line a second for their kind, each with the count of
    those it stands for."""
    import logging
    import time

    sent, start = 0, time.monotonic()
    with caplog.at_level(logging.WARNING, logger="racf.serve"):
        while sent < 300 or time.monotonic() - start < 3.3:
            _send(endpoint, [b"", b"\xc1junk"], wait_ms=50)
            sent += 1
    took = time.monotonic() - start
    lines = [r.getMessage() for r in caplog.records if "bad message" in r.getMessage()]
    assert int(took) <= len(lines) <= took + 1 and sent >= 300  # one a second: neither fewer nor more
    assert all("more like it since the last line" in line for line in lines[1:])


def test_a_request_the_service_itself_fails_on_is_an_error_and_it_serves_on(monkeypatch):
    from racf.experiments.service.handler import DefenceService

    original = DefenceService._handle

    def flaky(self, identity, client, message, connection):
        if message.get("op") == "boom":
            raise RuntimeError("its own fault")
        return original(self, identity, client, message, connection)

    monkeypatch.setattr(DefenceService, "_handle", flaky)
    stops = []
    endpoint = start_service("raw", stops)
    try:
        reply = unpack(_send(endpoint, [b"", pack({"op": "boom", "id": 3})])[-1])
        assert reply == {"error": "the service failed on this request: RuntimeError: its own fault", "id": 3}
        assert ping(endpoint)
    finally:
        for stop, thread in stops:
            stop.set()
            thread.join(5)


def test_a_service_answers_max_requests_and_no_more():
    from racf.experiments.service.server import serve

    stops = []
    endpoint = start_service("raw", stops, max_requests=3)
    answered = [ping(endpoint, timeout_s=1.0) for _ in range(4)]
    stop, thread = stops[0]
    thread.join(5)
    assert answered == [True, True, True, False] and not thread.is_alive()
    assert serve("tcp://127.0.0.1:0", {"raw": {}}, max_requests=0) == 0


def test_a_taken_address_is_one_line():
    from racf.errors import UserError
    from racf.experiments.service.server import serve

    stops = []
    endpoint = start_service("raw", stops)
    try:
        with pytest.raises(UserError, match=f"cannot listen at {endpoint}: Address already in use"):
            serve(endpoint, {"raw": {}})
    finally:
        for stop, thread in stops:
            stop.set()
            thread.join(5)


def test_a_frame_without_a_connection_has_none():
    from racf.experiments.service.server import _connection

    assert _connection(zmq.Frame(b"x")) is None
