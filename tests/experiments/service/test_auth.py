"""CurveZMQ on the link: the car talks only to the service whose key it pins, the service only to the
cars it admits, and each refusal says which it was, in one line, before any episode."""

from __future__ import annotations

import pytest

from racf.controllers import PerceptionSample
from racf.errors import UserError
from racf.experiments.episode.curve import CarKeys, ServerKeys, is_loopback, make_keys
from racf.experiments.episode.remote import RemoteEstimator
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


@pytest.mark.parametrize("who, words", [
    ("no keys", "one end has no keys"),
    ("a car the service does not admit", "refused this car's key"),
    ("a car pinning another service's key", "not the service whose key this car pins"),
])
def test_a_car_that_cannot_authenticate_is_refused_in_one_line(service, keys, who, words):
    endpoint = service("raw", keys=ServerKeys.load(keys / "ours"))
    ours, theirs = CarKeys.load(keys / "ours"), CarKeys.load(keys / "theirs")
    car_keys = {"no keys": None, "a car the service does not admit": CarKeys(theirs.public, theirs.secret, ours.server),
                "a car pinning another service's key": CarKeys(ours.public, ours.secret, theirs.server)}[who]
    with pytest.raises(UserError, match=words) as err:
        RemoteEstimator(endpoint, "raw", keys=car_keys)
    assert "\n" not in str(err.value) and "--service-keys" in str(err.value)


def test_a_trial_that_cannot_authenticate_stops_before_any_episode(service, keys, capsys):
    endpoint = service("raw", keys=ServerKeys.load(keys / "ours"))
    code, _ = run_cli(["trial", "--setting", "attack", "--estimator-endpoint", endpoint,
                       "--service-keys", str(keys / "theirs")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "\n" not in err and "not the service whose key this car pins" in err


def test_keys_are_never_overwritten_and_a_missing_pair_is_named(keys):
    with pytest.raises(UserError, match="never overwritten"):
        make_keys(keys / "ours")
    with pytest.raises(UserError, match="racf serve keys"):
        CarKeys.load(keys / "nowhere")


@pytest.mark.parametrize("endpoint, loopback", [("tcp://127.0.0.1:5555", True), ("tcp://localhost:1", True),
                                                ("tcp://[::1]:5555", True), ("ipc:///tmp/racf", True),
                                                ("tcp://0.0.0.0:5555", False), ("tcp://*:5555", False),
                                                ("tcp://192.168.1.4:5555", False), ("tcp://eth0:5555", False)])
def test_only_loopback_may_serve_without_keys(endpoint, loopback):
    assert is_loopback(endpoint) is loopback
