"""The service's sessions: bounded per client and in all, idle ones dropped, each ending in one line."""

from __future__ import annotations

import logging

from racf.experiments.service.sessions import Session, Sessions


def _session(client: str) -> Session:
    return Session(object(), client, "raw", {})


def test_a_client_at_its_bound_is_refused_and_no_session_of_its_is_ended():
    sessions = Sessions(per_client=2, total=10)
    for identity in (b"a", b"b"):
        assert sessions.open(identity, _session("10.0.0.1")) is None
    why = sessions.open(b"c", _session("10.0.0.1"))
    assert "10.0.0.1 holds this service's most sessions per client (2)" in why
    assert sessions.open(b"d", _session("10.0.0.2")) is None  # another client is not counted against it
    assert sessions.get(b"a") and sessions.get(b"b") and sessions.get(b"c") is None and len(sessions) == 3


def test_a_full_service_refuses_a_hello():
    sessions = Sessions(per_client=5, total=2)
    assert sessions.open(b"a", _session("x")) is None and sessions.open(b"b", _session("y")) is None
    assert "most sessions (2)" in sessions.open(b"c", _session("z"))
    assert len(sessions) == 2


def test_an_idle_session_expires_with_its_line(caplog):
    sessions = Sessions(idle_s=0.0)
    sessions.open(b"a", _session("x"))
    s = sessions.get(b"a")
    s.steps, s.service_ms = 3, [1.0, 2.0, 3.0]
    with caplog.at_level(logging.INFO, logger="racf.serve"):
        sessions.expire(every_s=0.0)
    assert len(sessions) == 0
    assert "session of x ended (idle 0 s): raw, 3 steps, service 2.00/2.98 ms p50/p99" in caplog.text
    assert ", 0 defence restarts, 0 s" in caplog.text


def test_a_goodbye_carries_the_cars_round_trips_into_the_line(caplog):
    sessions = Sessions()
    sessions.open(b"a", _session("x"))
    with caplog.at_level(logging.INFO, logger="racf.serve"):
        sessions.close(b"a", "the car closed it", {"rtt_p50_ms": 1.5, "rtt_p99_ms": 4.0})
    assert "round trip 1.50/4.00 ms p50/p99 (car)" in caplog.text


def test_a_driving_session_is_never_evicted_by_a_new_hello_from_its_address():
    sessions = Sessions(per_client=1)
    sessions.open(b"driving", _session("10.0.0.1"))
    for k in range(20):  # a process cycling hellos from the car's address
        assert sessions.open(b"cycler%d" % k, _session("10.0.0.1")) is not None
    assert sessions.get(b"driving") is not None and len(sessions) == 1


def test_a_hello_again_on_the_same_socket_replaces_its_own_session_within_the_bound():
    sessions = Sessions(per_client=1)
    sessions.open(b"car", _session("10.0.0.1"))
    first = sessions.get(b"car")
    assert sessions.open(b"car", _session("10.0.0.1")) is None
    assert sessions.get(b"car") is not first and len(sessions) == 1


def test_a_session_ends_with_its_connection_and_only_its_own(caplog):
    sessions = Sessions()
    sessions.open(b"a", Session(object(), "x", "raw", {}, connection=11))
    sessions.open(b"b", Session(object(), "x", "raw", {}, connection=12))
    with caplog.at_level(logging.INFO, logger="racf.serve"):
        sessions.end_connection(11)
    assert sessions.get(b"a") is None and sessions.get(b"b") is not None
    assert "session of x ended (its connection closed)" in caplog.text


def test_idle_is_measured_from_the_last_work_not_the_opening():
    import time

    sessions = Sessions(idle_s=0.05)
    sessions.open(b"a", _session("x"))
    sessions.get(b"a").opened -= 10.0  # opened long ago, worked just now
    sessions.get(b"a").seen -= 10.0
    sessions.worked(sessions.get(b"a"))
    sessions.expire(every_s=0.0)
    assert sessions.get(b"a") is not None
    time.sleep(0.06)
    sessions.expire(every_s=0.0)
    assert sessions.get(b"a") is None


def test_a_flood_of_ended_sessions_is_one_line_a_second_with_its_count(caplog):
    sessions = Sessions()
    with caplog.at_level(logging.INFO, logger="racf.serve"):
        for k in range(300):
            sessions.open(b"%d" % k, _session("x"))
            sessions.close(b"%d" % k, "the car closed it")
    lines = [r for r in caplog.records if "ended (the car closed it)" in r.getMessage()]
    assert 1 <= len(lines) <= 3 and len(sessions) == 0


def test_a_throttled_line_says_exactly_how_many_it_stands_for(caplog):
    import time

    from racf.experiments.service.sessions import Throttle

    throttle = Throttle(every_s=0.2)
    with caplog.at_level(logging.WARNING, logger="racf.serve"):
        for _ in range(5):
            throttle.log(logging.WARNING, "kind", "a line")
        time.sleep(0.25)
        throttle.log(logging.WARNING, "kind", "a line")
    assert [r.getMessage() for r in caplog.records] == ["a line", "a line (and 4 more like it since the last line)"]


def test_a_goodbye_without_both_round_trips_leaves_them_out_of_the_line(caplog):
    sessions = Sessions()
    sessions.open(b"a", _session("x"))
    with caplog.at_level(logging.INFO, logger="racf.serve"):
        sessions.close(b"a", "the car closed it", {"rtt_p50_ms": 1.5})
    assert "ended (the car closed it): raw, 0 steps, no estimates, 0 defence restarts" in caplog.text
    assert "round trip" not in caplog.text


def test_a_stopping_service_ends_every_session_and_says_so(caplog):
    sessions = Sessions()
    for k in range(3):
        sessions.open(b"%d" % k, _session(f"10.0.0.{k}"))
    with caplog.at_level(logging.INFO, logger="racf.serve"):
        sessions.close_all("the service stopped")
    assert len(sessions) == 0 and caplog.text.count("ended (the service stopped)") >= 1


def test_the_services_default_bounds_are_the_ones_racf_serve_states():
    from racf.experiments.cli import build_parser
    from racf.experiments.service.sessions import Sessions

    args = build_parser().parse_args(["serve"])
    bounds = Sessions()
    assert (bounds.idle_s, bounds.per_client, bounds.total, bounds.per_range) == (
        args.idle_s, args.sessions_per_client, args.max_sessions, args.sessions_per_range)
    assert (bounds.per_client, bounds.per_range, bounds.total) == (16, 64, 1024)


def test_one_host_s_many_addresses_are_capped_as_one_range():
    from racf.experiments.service.sessions import client_range

    assert client_range("127.0.0.5") == "127.0.0.0/24" and client_range("10.1.2.3") == "10.1.2.0/24"
    assert client_range("fe80::1:2:3:4") == "fe80::/64" and client_range("car key abc") == "car key abc"
    sessions = Sessions(per_client=16, total=1024, per_range=64)
    # 64 loopback addresses, 16 sessions each, would fill the 1,024 places; the range holds 64.
    refused = [sessions.open(b"%d-%d" % (a, k), _session(f"127.0.0.{a}")) for a in range(64) for k in range(16)]
    assert len(sessions) == 64 and refused[64].startswith("the addresses of 127.0.0.0/24 hold this service's most")
    assert sessions.open(b"car", _session("10.0.0.7")) is None  # a car elsewhere is served
    # Car keys are capped per key, not per range.
    keyed = Sessions(per_client=2, per_range=1)
    assert keyed.open(b"k1", _session("car key a")) is None and keyed.open(b"k2", _session("car key a")) is None


def test_a_long_session_keeps_the_times_of_its_last_estimates_only():
    from racf.experiments.service.sessions import TIMES_KEPT

    session = _session("x")
    for k in range(TIMES_KEPT + 1000):
        session.service_ms.append(float(k))
    assert len(session.service_ms) == TIMES_KEPT == 4096 and session.service_ms[0] == 1000.0


def test_a_kind_of_line_is_said_once_a_second():
    import time

    from racf.experiments.service.sessions import Throttle

    throttle, said = Throttle(), []
    for wait in (0.0, 0.6, 0.5):  # at 0 s, 0.6 s (within the second) and 1.1 s
        time.sleep(wait)
        before = len(said)
        throttle._last.setdefault("kind", [-float("inf"), 0])
        throttle.log(logging.WARNING, "kind", "a line")
        said.append(throttle._last["kind"][1] == 0)
    assert said == [True, False, True]
