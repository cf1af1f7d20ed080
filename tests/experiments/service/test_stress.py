"""``racf bench service-stress``, small: the three trials run against a real ``racf serve`` process
and print what must hold."""

from __future__ import annotations

import pytest

import json

from tests.conftest import run_cli


@pytest.mark.slow  # the bench, small: about 10 s
def test_the_stress_bench_prints_what_must_hold(capsys):
    code, out = run_cli(["bench", "service-stress", "--defence", "raw", "--fuzz", "300", "--connections", "30",
                         "--cars", "2", "--seconds", "2", "--json"])
    result = json.loads(out)
    assert code == 0 and result["alive"]
    assert result["fuzz"]["pings_answered"] == result["fuzz"]["batches"] == 1 and result["fuzz"]["alive"]
    assert result["connections"] == {"connections": 30, "answered": 30}
    cars = result["cars"]
    assert cars["cars"] == 2 and cars["steps"] >= 150 and cars["lost"] == 0
    assert 0 < cars["rtt_p50_ms"] <= cars["rtt_p99_ms"] <= cars["rtt_max_ms"]
    assert cars["server_mb_end"] > 0
