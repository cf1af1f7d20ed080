"""The service's sessions: bounded per client and in all, idle ones dropped, each ending in one line."""

from __future__ import annotations

import logging

from racf.experiments.service.sessions import Session, Sessions


def _session(client: str) -> Session:
    return Session(object(), client, "raw", {})


def test_a_client_over_its_bound_gives_up_its_oldest_session(caplog):
    sessions = Sessions(per_client=2, total=10)
    with caplog.at_level(logging.INFO, logger="racf.serve"):
        for identity in (b"a", b"b", b"c"):
            assert sessions.open(identity, _session("10.0.0.1")) is None
        assert sessions.open(b"d", _session("10.0.0.2")) is None
    assert sessions.get(b"a") is None and sessions.get(b"b") and sessions.get(b"c") and sessions.get(b"d")
    assert "more than 2 sessions from one client" in caplog.text


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


def test_a_goodbye_carries_the_cars_round_trips_into_the_line(caplog):
    sessions = Sessions()
    sessions.open(b"a", _session("x"))
    with caplog.at_level(logging.INFO, logger="racf.serve"):
        sessions.close(b"a", "the car closed it", {"rtt_p50_ms": 1.5, "rtt_p99_ms": 4.0})
    assert "round trip 1.50/4.00 ms p50/p99 (car)" in caplog.text


def test_the_least_recently_used_session_gives_way_not_one_that_drives():
    import time

    sessions = Sessions(per_client=2)
    sessions.open(b"driving", _session("10.0.0.1"))
    sessions.open(b"left", _session("10.0.0.1"))
    time.sleep(0.01)
    sessions.get(b"driving")  # asked a moment ago: it is driving
    sessions.open(b"new", _session("10.0.0.1"))
    assert sessions.get(b"driving") and sessions.get(b"new") and sessions.get(b"left") is None
