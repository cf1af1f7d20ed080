"""The service tests' shared fixture: the car's own measure of how long it waited unanswered."""

import pytest


@pytest.fixture
def unanswered_waits(monkeypatch) -> list[float]:
    """Each wait (ms) the car measured when no answer came (``NoAnswer.waited_ms``), in order: what a
    loaded machine does not stretch the way it stretches a command's or a step's whole wall time."""
    from racf.experiments.link import remote

    waits: list[float] = []
    told = remote.NoAnswer.__init__

    def counted(self, handshake, waited_ms):
        waits.append(waited_ms)
        told(self, handshake, waited_ms)

    monkeypatch.setattr(remote.NoAnswer, "__init__", counted)
    return waits
