"""``racf serve``'s session limits do what its flags say, through the command line: the per-client
and total caps refuse, idle sessions end, a session ends with its connection, and a car already
driving is never evicted by another client from its address."""

from __future__ import annotations

import subprocess
import sys
import threading
import time

import pytest
import zmq

from racf.controllers import PerceptionSample
from racf.experiments.link.remote import RemoteEstimator
from racf.experiments.link.wire import PROTOCOL, pack, unpack

LIMITS = ["--max-sessions", "8", "--sessions-per-client", "4", "--idle-s", "1"]


@pytest.fixture(scope="module")
def served():
    """``racf serve --defence raw`` with LIMITS, in its own process, on every address of the machine
    without keys (--insecure); yields (its loopback endpoint, its stderr file)."""
    import tempfile

    log = tempfile.NamedTemporaryFile("w+", suffix=".log")
    proc = subprocess.Popen([sys.executable, "-m", "racf.experiments.cli", "serve", "--defence", "raw", "--bind",
                             "tcp://0.0.0.0:0", "--insecure", *LIMITS], stdout=subprocess.PIPE, stderr=log, text=True)
    line = proc.stdout.readline()
    assert line.startswith("listening at "), line
    port = line.split("listening at ", 1)[1].split()[0].rsplit(":", 1)[1]
    yield f"tcp://127.0.0.1:{port}", log
    proc.terminate()
    proc.wait(10)
    log.close()


def _hello(endpoint: str, source: str | None = None) -> tuple[zmq.Socket, dict]:
    """A new socket (from ``source``, a loopback address) that says hello; the socket and the answer."""
    sock = zmq.Context.instance().socket(zmq.REQ)
    sock.setsockopt(zmq.LINGER, 0)
    host_port = endpoint.split("://", 1)[1]
    sock.connect(f"tcp://{source}:0;{host_port}" if source else endpoint)
    sock.send(pack({"op": "hello", "id": 1, "protocol": PROTOCOL, "estimator": "raw", "options": {}}))
    assert sock.poll(5000), "no answer to a hello"
    return sock, unpack(sock.recv())


def _asks(sock: zmq.Socket) -> dict:
    sock.send(pack({"op": "reset", "id": 2}))
    assert sock.poll(5000)
    return unpack(sock.recv())


def _close(socks) -> None:
    for sock in socks:
        sock.close(0)
    time.sleep(0.3)  # the service reads the connections' ends


def test_four_of_ten_hellos_from_one_address_are_granted(served):
    endpoint, _ = served
    opened = [_hello(endpoint) for _ in range(10)]
    granted = [sock for sock, answer in opened if "refused" not in answer]
    refused = [answer["refused"] for _, answer in opened if "refused" in answer]
    try:
        assert len(granted) == 4 and len(refused) == 6
        assert "most sessions per client (4)" in refused[0]
        assert all("error" not in _asks(sock) for sock in granted)  # the first four were not evicted
    finally:
        _close(sock for sock, _ in opened)


def test_no_session_answers_after_it_idled_past_idle_s(served):
    endpoint, _ = served
    opened = [_hello(endpoint)[0] for _ in range(4)]
    try:
        time.sleep(2.5)  # idle 1 s, looked at once a second
        assert all(_asks(sock).get("no_session") is True for sock in opened)
    finally:
        _close(opened)


def test_sixty_four_addresses_that_close_their_sockets_do_not_lock_out_a_new_car(served):
    endpoint, _ = served
    opened = [_hello(endpoint, f"127.0.0.{k + 2}") for k in range(64)]
    assert sum("refused" not in answer for _, answer in opened) == 8  # the service's total
    assert "most sessions (8)" in next(a["refused"] for _, a in opened if "refused" in a)
    for sock, _ in opened:
        sock.close(0)
    start = time.monotonic()
    while True:  # a new car gets a session within 2 s of their sockets closing
        sock, answer = _hello(endpoint, "127.0.0.99")
        sock.close(0)
        if "refused" not in answer:
            break
        assert time.monotonic() - start < 2.0, answer
        time.sleep(0.05)
    time.sleep(0.3)


def test_a_driving_car_loses_no_answer_beside_a_process_cycling_hellos_from_its_address(served):
    endpoint, _ = served
    stop = threading.Event()
    cycled = []

    def cycle():  # holds up to 6 sessions from the car's address, then lets them all go, again and again
        held = []
        while not stop.is_set():
            held.append(_hello(endpoint)[0])
            cycled.append(1)
            if len(held) == 6:
                _close(held)
                held = []
        _close(held)

    car = RemoteEstimator(endpoint, "raw", timeout_ms=2000.0)
    car.reset()
    thread = threading.Thread(target=cycle, daemon=True)
    thread.start()
    try:
        fell = 0
        for k in range(300):
            car.estimate(PerceptionSample(None, 2.0, 0.9, 2.0, 0.0), 1.0, 0.02)
            fell += car.diagnostics()["service_fallback"] == 1.0
            time.sleep(0.002)
    finally:
        stop.set()
        thread.join(10)
        car.close()
    assert len(cycled) > 10 and fell == 0 and car.new_sessions == 0


def test_a_plain_service_says_once_that_per_address_caps_are_no_defence_and_insecure_warns(served):
    _, log = served
    log.flush()
    text = open(log.name).read()
    assert text.count("per-client cap counts network addresses") == 1
    warnings = [line for line in text.splitlines() if "served without keys (--insecure)" in line]
    assert len(warnings) == 1 and warnings[0].startswith("racf serve: warning: tcp://0.0.0.0:0")


def test_sessions_end_with_their_connections_long_before_they_idle():
    """A service that keeps idle sessions ten minutes: cars that close their sockets free their places
    at once (with a full service of two, a third car gets one within a second of theirs closing)."""
    from racf.experiments.service.sessions import Sessions
    from tests.conftest import start_service

    stops = []
    endpoint = start_service("raw", stops, sessions=Sessions(idle_s=600.0, per_client=5, total=2))
    try:
        first = [_hello(endpoint) for _ in range(2)]
        assert all("refused" not in answer for _, answer in first)
        late, answer = _hello(endpoint)
        late.close(0)
        assert "most sessions (2)" in answer["refused"]
        _close(sock for sock, _ in first)
        start = time.monotonic()
        while True:
            sock, answer = _hello(endpoint)
            sock.close(0)
            if "refused" not in answer:
                break
            assert time.monotonic() - start < 1.0, answer
            time.sleep(0.05)
    finally:
        for stop, thread in stops:
            stop.set()
            thread.join(5)


@pytest.mark.slow  # it waits out the handshake's and the heartbeat's timeouts (about 5 s)
def test_a_frame_never_finished_is_dropped_with_its_connection(served):
    """A peer that sends a 1 MiB frame less one byte held the frame's memory as long as it stayed; it is
    dropped once a ping (every 1 s) gets nothing whole back within 3 s, and one that never finishes
    its handshake after 2 s."""
    from racf.experiments.service.probes import closed_within, half_sent
    from racf.experiments.service.server import HANDSHAKE_MS, HEARTBEAT_MS, HEARTBEAT_TIMEOUT_MS

    import socket

    endpoint, _ = served
    assert (HANDSHAKE_MS, HEARTBEAT_MS, HEARTBEAT_TIMEOUT_MS) == (2000, 1000, 3000)
    start = time.monotonic()
    peer = half_sent(endpoint, 1 << 20)
    silent = socket.create_connection(("127.0.0.1", int(endpoint.rsplit(":", 1)[1])))
    try:
        assert 1.5 <= closed_within(silent, 6.0) <= 4.0  # the handshake's 2 s
        assert closed_within(peer, 8.0) is not None and 3.0 <= time.monotonic() - start <= 7.0  # 1 s + 3 s
    finally:
        peer.close()
        silent.close()
    sock, answer = _hello(endpoint)  # and a car is served after them
    _close([sock])
    assert "refused" not in answer
