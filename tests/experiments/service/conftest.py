"""The defence service in a thread, for the tests of ``racf.experiments.service``."""

from __future__ import annotations

import threading

import pytest

from racf.experiments.service.server import serve


def start_service(defence, stops: list, max_requests: float = float("inf"), keys=None,
                  endpoint: str = "tcp://127.0.0.1:0", **kwargs) -> str:
    """``serve(defence, ...)`` in a daemon thread (its stop appended to ``stops``); returns its endpoint."""
    bound, stop, ready = [], threading.Event(), threading.Event()
    names = None if defence is None else (defence,)
    thread = threading.Thread(target=serve, args=(endpoint, names),
                              kwargs={"ready": lambda e: (bound.append(e), ready.set()), "max_requests": max_requests,
                                      "stop": stop, "keys": keys, **kwargs}, daemon=True)
    thread.start()
    assert ready.wait(60)
    stops.append((stop, thread))
    return bound[0]


@pytest.fixture
def service():
    """A function that starts a service (see :func:`start_service`) and returns its endpoint; every
    one is stopped after the test."""
    stops = []
    yield lambda defence, max_requests=float("inf"), **kw: start_service(defence, stops, max_requests, **kw)
    for stop, thread in stops:
        stop.set()
        thread.join(5)
