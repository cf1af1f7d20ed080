"""The service's answers, called directly: every answer names its request, a defence's distance goes out
only as the protocol allows, the options a service was started with are the only ones it serves, and
a defence rebuilt after it raised is calibrated again."""

from __future__ import annotations

import math

import pytest

from racf.controllers import PerceptionSample
from racf.experiments.episode.plan import car_calibration
from racf.experiments.link.wire import PROTOCOL, check_answer, encode_sample, pack, unpack
from racf.experiments.service.handler import DefenceService
from racf.experiments.service.sessions import Sessions
from racf.plugins import load_plugin_file

HELLO = {"op": "hello", "id": 1, "protocol": PROTOCOL, "estimator": "raw", "options": {}}


def _estimate(d: float, rid: int = 2) -> dict:
    return {"op": "estimate", "id": rid, "sample": encode_sample(PerceptionSample(None, d, 0.9, d, 0.0)),
            "speed": 1.0, "dt": 0.02, "yaw_rate": 0.0}


def test_every_answer_names_its_request_errors_too():
    service = DefenceService({"raw": {}})
    assert service.handle(b"a", "x", {"op": "ping", "id": 7}) == {"pong": True, "protocol": PROTOCOL, "id": 7}
    assert service.handle(b"a", "x", {"op": "estimate", "id": 8})["id"] == 8  # no session: an error, named
    assert "id" not in service.handle(b"a", "x", {"op": "ping", "id": "7"})  # an id that is not one is not echoed
    hello = check_answer("hello", service.handle(b"a", "x", HELLO), 1)
    assert hello["protocol"] == PROTOCOL and hello["existence"] is False and hello["n_parameters"] == 0


@pytest.mark.parametrize("d, words", [(math.inf, "not a number in the protocol's [0, 50] m"),
                                      (-0.5, "not a number in the protocol's [0, 50] m"),
                                      (50.5, "not a number in the protocol's [0, 50] m")])
def test_a_distance_the_protocol_does_not_allow_is_never_sent(d, words):
    service = DefenceService({"raw": {}})
    service.handle(b"a", "x", HELLO)
    reply = service.handle(b"a", "x", _estimate(d))
    assert "distance" not in reply and words in reply["error"] and reply["id"] == 2


def test_no_target_goes_out_as_none_and_an_answer_in_range_as_it_is():
    service = DefenceService({"raw": {}})
    service.handle(b"a", "x", HELLO)
    assert service.handle(b"a", "x", _estimate(math.nan))["distance"] is None
    for d in (0.0, 1.25, 50.0):
        assert service.handle(b"a", "x", _estimate(d))["distance"] == d


def test_the_options_a_service_was_started_with_are_the_only_ones_it_serves():
    service = DefenceService({"ekf": {"config": {"depth_std_m": 0.05}}})
    hello = {**HELLO, "estimator": "ekf"}
    assert "refused" in service.handle(b"a", "x", {**hello, "options": {"config": {"depth_std_m": 0.2}}})
    assert "refused" in service.handle(b"a", "x", hello)  # no options is other options too
    assert "refused" not in service.handle(b"a", "x", {**hello, "options": {"config": {"depth_std_m": 0.05}}})


def test_another_protocols_hello_is_told_which_this_service_speaks():
    reply = DefenceService({"raw": {}}).handle(b"a", "x", {"op": "hello", "protocol": 1, "estimator": "raw"})
    assert reply["error"] == f"protocol 1; this service speaks {PROTOCOL}"


def test_the_sessions_given_are_the_sessions_used_even_empty():
    sessions = Sessions(per_client=1)
    service = DefenceService({"raw": {}}, sessions=sessions)
    assert service.sessions is sessions
    service.handle(b"a", "x", HELLO)
    assert "refused" in service.handle(b"b", "x", HELLO)


CALIBRATED = '''
from racf.controllers.estimators import RawDepthEstimator


class Calibrated(RawDepthEstimator):
    name = "calibrated"

    def __init__(self):
        super().__init__()
        self.calibration, self.calls = None, 0

    def use_calibration(self, calibration):
        self.calibration = calibration

    def estimate(self, sample, speed_mps, dt, yaw_rate_radps=0.0):
        self.calls += 1
        if self.calls == 2:
            raise RuntimeError("tripped")
        return 1.0 if self.calibration is not None else 2.0
'''


def test_a_defence_rebuilt_after_it_raised_is_calibrated_and_reset_again(tmp_path, plugin_env):
    import dataclasses

    path = tmp_path / "calibrated.py"
    path.write_text(CALIBRATED)
    load_plugin_file(path)
    service = DefenceService({"calibrated": {}})
    service.handle(b"a", "x", {**HELLO, "estimator": "calibrated"})
    # As the car sends it: through msgpack, whose tuples come back as lists.
    calibration = unpack(pack({"c": dataclasses.asdict(car_calibration(320, 240))}))["c"]
    assert service.handle(b"a", "x", {"op": "calibrate", "id": 2, "calibration": calibration}) == {"id": 2}
    assert service.handle(b"a", "x", _estimate(3.0, 3))["distance"] == 1.0
    assert "restarted" in service.handle(b"a", "x", _estimate(3.0, 4))
    session = service.sessions.get(b"a")
    assert session.restarts == 1 and session.estimator.calibration == car_calibration(320, 240)
    assert service.handle(b"a", "x", _estimate(3.0, 5))["distance"] == 1.0  # calibrated, not the 2.0 of a bare one


def test_a_session_counts_its_estimates_and_diagnostics_keep_their_words():
    from racf.experiments.service.handler import _floats

    service = DefenceService({"raw": {}})
    service.handle(b"a", "x", HELLO)
    for k in range(3):
        service.handle(b"a", "x", _estimate(2.0, 2 + k))
    session = service.sessions.get(b"a")
    assert session.steps == 3 and len(session.service_ms) == 3
    assert all(1e-4 < ms < 1000.0 for ms in session.service_ms)  # the defence's own time, in milliseconds
    assert _floats({"w": 1, "gate": "lidar", "bad": None}) == {"w": 1.0, "gate": "lidar", "bad": "None"}


def test_the_largest_id_is_answered_and_one_beyond_refused():
    from racf.experiments.link.wire import MAX_REQUEST_ID

    service = DefenceService({"raw": {}})
    assert service.handle(b"a", "x", {"op": "ping", "id": MAX_REQUEST_ID}) == {"pong": True, "protocol": PROTOCOL,
                                                                               "id": MAX_REQUEST_ID}
    beyond = service.handle(b"a", "x", {"op": "ping", "id": MAX_REQUEST_ID + 1})
    assert "id must be an int" in beyond["error"] and "id" not in beyond
    assert service.handle(b"a", "x", {"op": "ping", "id": 0}) == {"pong": True, "protocol": PROTOCOL, "id": 0}


def test_a_car_picks_a_defence_and_never_its_options_not_even_where_every_defence_is_served():
    for service in (DefenceService({"ekf": {}}), DefenceService(None)):
        for options in ({"bogus": 1}, {"config": {"depth_std_m": 0.2}}):
            reply = service.handle(b"a", "x", {**HELLO, "estimator": "ekf", "options": options})
            assert reply["refused"].startswith("this service runs ekf with its operator's options {}, not ")
            assert "a car picks a defence, never its options" in reply["refused"] and len(service.sessions) == 0
        assert "refused" not in service.handle(b"a", "x", {**HELLO, "estimator": "ekf"})


def test_a_checkpoint_a_car_names_is_never_opened():
    # The shipped head's path spelt another way: refused before any file is read.
    service = DefenceService({"raw": {}})
    reply = service.handle(b"a", "x", {**HELLO, "estimator": "odca", "options": {"checkpoint": "checkpoints/./odca"}})
    assert "this service serves raw, not 'odca'" in reply["refused"]
    everything = DefenceService(None)
    reply = everything.handle(b"a", "x", {**HELLO, "estimator": "odca", "options": {"checkpoint": "/etc/passwd"}})
    assert "never its options" in reply["refused"] and "odca" not in everything._warm


def test_would_pass_takes_a_map_of_names_and_answers_true_or_false():
    service = DefenceService({"raw": {}})
    service.handle(b"a", "x", HELLO)
    reply = service.handle(b"a", "x", {"op": "would_pass", "id": 3,
                                       "kwargs": {"depth": 1.5, "speed_mps": 1.0, "dt": 0.02}})
    assert reply["answer"] in (True, False) and reply["id"] == 3
    for kwargs in ({1: 2}, [1], "depth"):
        reply = service.handle(b"a", "x", {"op": "would_pass", "id": 4, "kwargs": kwargs})
        assert "would_pass needs kwargs (a map of names)" in reply["error"]


def test_an_op_that_is_no_name_is_a_bad_request_answered_by_its_id():
    service = DefenceService({"raw": {}})
    for op in ([1], {"a": 1}, 3, None):
        reply = service.handle(b"a", "x", {"op": op, "id": 5})
        assert reply["id"] == 5 and reply["error"].startswith("bad request: op must be a request's name (a string)")


def test_a_reset_or_a_ping_keeps_no_session_alive_past_its_idle_time():
    import time

    sessions = Sessions(idle_s=0.05)
    service = DefenceService({"raw": {}}, sessions=sessions)
    service.handle(b"a", "x", HELLO)
    service.handle(b"b", "y", HELLO)
    for _ in range(8):  # 0.08 s: car a only resets and pings; car b estimates
        service.handle(b"a", "x", {"op": "reset", "id": 3})
        service.handle(b"a", "x", {"op": "ping", "id": 4})
        service.handle(b"b", "y", _estimate(1.0))
        time.sleep(0.01)
        sessions.expire(every_s=0.0)
    assert sessions.get(b"a") is None and sessions.get(b"b") is not None
