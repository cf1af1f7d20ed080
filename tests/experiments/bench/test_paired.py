"""racf bench paired: two checkouts' loops timed in alternation, and its input checks."""

import json
from pathlib import Path

import pytest

from racf.errors import UserError
from racf.experiments.bench.paired import PairedResult, bench_paired, checkout_root

ROOT = Path(__file__).resolve().parents[3]


def test_the_ratio_is_the_median_of_new_over_old_round_by_round():
    result = PairedResult("attack+odca", 6, old_ms=(5.0, 6.0, 4.0), new_ms=(4.0, 6.6, 4.0))
    assert result.ratios == pytest.approx([0.8, 1.1, 1.0])
    assert result.ratio == pytest.approx(1.0)
    out = result.to_dict()
    assert out["old_rtf"] == pytest.approx(20.0 / 5.0) and out["new_rtf"] == pytest.approx(20.0 / 4.0)
    json.dumps(out, allow_nan=False)


def test_a_folder_without_racf_is_refused_in_one_line(tmp_path):
    with pytest.raises(UserError, match="must be a racf checkout"):
        checkout_root(tmp_path)
    assert checkout_root(ROOT) == ROOT.resolve()


@pytest.mark.slow
def test_this_checkout_against_itself_times_both_in_turn():
    seen = []
    result = bench_paired(ROOT, rounds=2, setting="clean", episodes=1, on_round=lambda *a: seen.append(a))
    assert len(result.old_ms) == len(result.new_ms) == 2 and [r for r, *_ in seen] == [0, 1]
    assert all(ms > 0 for ms in result.old_ms + result.new_ms)
    # How far the same code drifts on a loaded 2-core machine is not this test's business (CI saw
    # 2.3x on one cold round); that both workers ran and timed each round is.
    assert result.ratio == pytest.approx(result.new_ms[0] / result.old_ms[0] / 2 + result.new_ms[1] / result.old_ms[1] / 2)
