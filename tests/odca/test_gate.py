"""Gate and fusion: Proposition 1 and the convex combination, as properties."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from odca import GateConfig, fuse, gate_weight

finite = st.floats(-50, 50, allow_nan=False)
gates = st.builds(lambda lo, span, g: GateConfig(lo, lo + span, g), st.floats(0, 1), st.floats(0.01, 2),
                  st.floats(0.1, 5))


@settings(max_examples=300, deadline=None)
@given(st.floats(0.01, 40), finite, gates, st.floats(0, 1))
def test_agreement_passes_the_measurement_through_exactly(d, rep, gate, share):
    r = share * gate.tau_low  # r_XS <= tau_low
    w = gate_weight(r, gate)
    assert w == 0.0
    assert fuse(d, rep, w) == d


@settings(max_examples=300, deadline=None)
@given(st.floats(0.01, 40), finite, gates, st.floats(0, 20))
def test_output_is_a_convex_combination(d, rep, gate, r):
    w = float(gate_weight(r, gate))
    assert 0.0 <= w <= 1.0
    out = float(fuse(d, rep, w))
    assert min(d, rep) - 1e-9 <= out <= max(d, rep) + 1e-9
    assert out == pytest.approx((1 - w) * d + w * rep, abs=1e-9)


def test_gate_shape_and_missing_residual():
    gate = GateConfig(0.1, 0.3, 2.0)
    np.testing.assert_allclose(gate_weight([0.0, 0.1, 0.2, 0.3, 5.0], gate), [0, 0, 0.25, 1, 1])
    assert gate_weight(np.nan, gate) == 1.0  # no LiDAR: repair only
    assert fuse(np.nan, 1.2, 1.0) == 1.2  # missing depth: the repair
    with pytest.raises(ValueError, match="tau_low < tau_high"):
        GateConfig(0.3, 0.2)
    with pytest.raises(ValueError, match="gamma"):
        GateConfig(0.1, 0.2, 0.0)


@settings(max_examples=300, deadline=None)
@given(st.floats(0.01, 40), finite, gates, st.floats(0, 1), st.floats(0, 1))
def test_without_lidar_a_trusted_depth_passes_and_anything_less_is_repaired(d, rep, gate, trust, c):
    gate = GateConfig(gate.tau_low, gate.tau_high, gate.gamma, trust)
    w = float(gate_weight(np.nan, gate, depth=d, confidence=c))
    if c >= trust:
        assert w == 0.0 and fuse(d, rep, w) == d
    else:
        assert w == 1.0
    assert gate_weight(np.nan, gate, depth=np.nan, confidence=1.0) == 1.0  # no depth: always the repair


def test_default_gate_never_trusts_a_depth_without_lidar():
    assert gate_weight(np.nan, GateConfig(), depth=1.0, confidence=1.0) == 1.0
    with pytest.raises(ValueError, match="trust_confidence"):
        GateConfig(0.1, 0.2, 1.0, 2.0)
