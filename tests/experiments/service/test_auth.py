"""CurveZMQ on the link: the car talks only to the service whose key it pins, the service only to the
cars it admits, and each refusal says which it was, in one line, before any episode."""

from __future__ import annotations

import pytest

from racf.controllers import PerceptionSample
from racf.errors import UserError
from racf.experiments.link.curve import CarKeys, ServerKeys, is_loopback, make_keys
from racf.experiments.link.remote import RemoteEstimator
from tests.conftest import run_cli


@pytest.fixture(scope="module")
def keys(tmp_path_factory):
    root = tmp_path_factory.mktemp("keys")
    make_keys(root / "ours")
    make_keys(root / "theirs")
    return root


def test_an_admitted_car_is_answered_over_curve(service, keys):
    endpoint = service("raw", keys=ServerKeys.load(keys / "ours"))
    car = RemoteEstimator(endpoint, "raw", keys=CarKeys.load(keys / "ours"))
    car.reset()
    assert car.estimate(PerceptionSample(None, 1.25, 0.9, 1.2, 0.0), 0.5, 0.02) == 1.25
    car.close()


WHO = {"no keys": "speaks CurveZMQ and this car has no keys",
       "a car the service does not admit": "does not admit this car's key",
       "a car pinning another service's key": "is not the service whose key this car pins ("}


@pytest.mark.parametrize("who", WHO)
def test_a_car_that_cannot_authenticate_is_told_why_in_its_own_line_within_3_s(service, keys, who, capsys,
                                                                                 unanswered_waits):
    """Three causes, three lines, each through the command line (exit 2) before any episode. Within
    3 s of the car's own waiting for the service: what it measures of its wait, which a loaded machine
    does not stretch as it stretches the command's whole wall time (its imports, its set-up)."""
    waits = unanswered_waits

    endpoint = service("raw", keys=ServerKeys.load(keys / "ours"))
    folder = {"no keys": None, "a car the service does not admit": keys / "stranger",
              "a car pinning another service's key": keys / "theirs"}[who]
    if who == "a car the service does not admit":  # our service's key pinned, a car key it never admitted
        if not folder.exists():
            make_keys(folder)
            (folder / "server.key").write_bytes((keys / "ours" / "server.key").read_bytes())
    code, _ = run_cli(["trial", "--setting", "attack", "--estimator-endpoint", endpoint,
                       *(["--service-keys", str(folder)] if folder else [])])
    took = sum(waits) / 1000.0
    err = capsys.readouterr().err.strip()
    assert code == 2 and "\n" not in err and WHO[who] in err and "cannot be authenticated" not in err
    assert all(words not in err for other, words in WHO.items() if other != who)
    assert waits and took < 3.0, f"told after {took:.1f} s of waiting"


def test_the_car_uses_the_key_it_is_told_to_or_the_only_one(tmp_path, service):
    make_keys(tmp_path / "k", cars=("other",))
    endpoint = service("raw", keys=ServerKeys.load(tmp_path / "k"))
    RemoteEstimator(endpoint, "raw", keys=CarKeys.load(tmp_path / "k")).close()  # the only car: taken
    assert CarKeys.load(tmp_path / "k", "other").name == "other"
    make_keys(tmp_path / "two", cars=("a", "b"))
    with pytest.raises(UserError, match="it holds a, b: name one with --service-car NAME"):
        CarKeys.load(tmp_path / "two")
    with pytest.raises(UserError, match="no key of car 'c'.*it holds a, b"):
        CarKeys.load(tmp_path / "two", "c")


def test_a_trial_names_its_car_with_service_car(tmp_path, service, capsys):
    make_keys(tmp_path / "k", cars=("a", "b"))
    endpoint = service("raw", keys=ServerKeys.load(tmp_path / "k"))
    code, _ = run_cli(["trial", "--setting", "clean", "--speed", "2.0", "--estimator-endpoint", endpoint,
                       "--service-keys", str(tmp_path / "k"), "--service-car", "b", "--json"])
    assert code == 0, capsys.readouterr().err
    code, _ = run_cli(["trial", "--setting", "clean", "--estimator-endpoint", endpoint,
                       "--service-keys", str(tmp_path / "k")])
    assert code == 2 and "--service-car" in capsys.readouterr().err


def test_secret_files_are_0600_from_the_moment_they_exist(tmp_path, monkeypatch, capsys):
    """`racf serve keys` under the widest umask: every write into a key file finds it already as narrow as
    it will stay (the old way wrote 0644 and then narrowed it), in owner-only folders."""
    import os
    import stat

    seen = []
    real_write = os.write

    def watched(fd, data):
        seen.append(stat.S_IMODE(os.fstat(fd).st_mode))
        return real_write(fd, data)

    monkeypatch.setattr(os, "write", watched)
    old = os.umask(0)
    try:
        code, _ = run_cli(["serve", "keys", str(tmp_path / "k"), "--car", "a", "--car", "b"])
    finally:
        os.umask(old)
    assert code == 0, capsys.readouterr().err
    secrets = sorted((tmp_path / "k").rglob("*.key_secret"))
    assert len(secrets) == 3 and seen.count(0o600) == 3 and sorted(seen) == [0o600] * 3 + [0o644] * 3
    assert all(stat.S_IMODE(p.stat().st_mode) == 0o600 for p in secrets)
    for folder in (tmp_path / "k", tmp_path / "k" / "cars"):
        assert stat.S_IMODE(folder.stat().st_mode) == 0o700


def test_keys_are_never_overwritten_and_a_missing_pair_is_named(keys):
    with pytest.raises(UserError, match=r"server.key_secret exists; keys are never overwritten"):
        make_keys(keys / "ours")
    with pytest.raises(UserError, match="racf serve keys"):
        CarKeys.load(keys / "nowhere")


@pytest.mark.parametrize("endpoint, loopback", [("tcp://127.0.0.1:5555", True), ("tcp://localhost:1", True),
                                                ("tcp://[::1]:5555", True), ("ipc:///tmp/racf", True),
                                                ("tcp://0.0.0.0:5555", False), ("tcp://*:5555", False),
                                                ("tcp://192.168.1.4:5555", False), ("tcp://eth0:5555", False)])
def test_only_loopback_may_serve_without_keys(endpoint, loopback):
    assert is_loopback(endpoint) is loopback


def test_on_a_curve_link_the_per_client_cap_is_per_car_key(service, tmp_path):
    """Two cars on one address, each with its own key: each has its own cap of one session."""
    from racf.experiments.service.sessions import Sessions

    make_keys(tmp_path / "k", cars=("a", "b"))
    endpoint = service("raw", keys=ServerKeys.load(tmp_path / "k"), sessions=Sessions(per_client=1))
    a, b = (RemoteEstimator(endpoint, "raw", keys=CarKeys.load(tmp_path / "k", car)) for car in ("a", "b"))
    with pytest.raises(UserError, match=r"car key .* holds this service's most sessions per client \(1\)"):
        RemoteEstimator(endpoint, "raw", keys=CarKeys.load(tmp_path / "k", "a"))
    for car in (a, b):
        car.reset()
        assert car.estimate(PerceptionSample(None, 1.25, 0.9, 1.2, 0.0), 0.5, 0.02) == 1.25
        car.close()


def test_a_refusal_stays_said_when_the_socket_connects_again():
    """ZeroMQ reconnects after a failed handshake: the failure read from the monitor is the one that
    happened, whatever connection follows it; a later success clears it."""
    import struct

    import zmq

    from racf.experiments.link.curve import handshake_failure

    ctx = zmq.Context.instance()

    def monitor_with(events):
        a, b = ctx.socket(zmq.PAIR), ctx.socket(zmq.PAIR)
        address = f"inproc://monitor-{id(a)}"
        a.bind(address)
        b.connect(address)
        for event in events:
            a.send_multipart([struct.pack("=hi", int(event), 0), b"tcp://127.0.0.1:1"])
        return a, b

    cases = [([zmq.EVENT_CONNECTED, zmq.EVENT_HANDSHAKE_FAILED_AUTH, zmq.EVENT_CONNECTED], "refused this car's key"),
             ([zmq.EVENT_CONNECTED, zmq.EVENT_HANDSHAKE_FAILED_NO_DETAIL, zmq.EVENT_CONNECTED,
               zmq.EVENT_HANDSHAKE_SUCCEEDED], None)]
    for events, words in cases:
        a, b = monitor_with(events)
        seen = handshake_failure(b)
        a.close(0), b.close(0)
        assert seen.connected and (seen.failure is None if words is None else words in seen.failure)
