"""``racf bench-loop``: the closed loop's real-time factor and the workers' throughput, as ratios."""

import json

import pytest

from racf.experiments.cli import main


@pytest.mark.slow
def test_bench_loop_prints_its_ratios(capsys):
    assert main(["bench-loop", "-n", "1", "--rate-episodes", "1", "--no-ray", "--json"]) == 0
    r = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    for key in ("rtf_clean", "rtf_attack_odca", "episodes_per_min_1", "episodes_per_min_2", "scaling_efficiency"):
        assert r[key] > 0, key
    assert r["scaling_efficiency"] == pytest.approx(r["episodes_per_min_2"] / (2 * r["episodes_per_min_1"]))
    # Start-up is reported apart from the rates.
    assert r["ready_s_1"] > 0 and r["ready_s_2"] > 0 and "ready_s_ray" not in r
