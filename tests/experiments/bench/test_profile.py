"""The step profile: disjoint parts whose shares sum to one, each part measured."""

import pytest

from racf.experiments.bench.profile import PARTS, step_profile


@pytest.mark.slow  # two whole episodes under the profiler
def test_the_shares_are_disjoint_parts_of_the_whole_episode():
    result = step_profile("attack+odca", sign=2, speed=2.0)
    shares = result["shares"]
    assert set(shares) == set(PARTS) | {"rest"}
    assert sum(shares.values()) == pytest.approx(1.0)
    assert all(v >= 0 for v in shares.values())
    assert all(shares[part] > 0.005 for part in PARTS), shares  # each part found, none silently zero
