"""The gate that votes: its truth tables (three witnesses, and four with the size), Proposition 1, a spoofed
LiDAR that cannot move the output, and a size witness that can only veto what lies beyond it."""

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from racf.odca import SOURCES, GateConfig, vote

NAN = math.nan
GATE = GateConfig(tau_m=0.1, trust_confidence=0.5)
K_TOL = 0.2
distance = st.floats(0.2, 10.0)
maybe = st.one_of(st.just(NAN), distance)


# (depth, confidence, lidar, d_kin, prior) -> (source, base): the README's truth table.
TABLE = [
    ((1.00, 0.9, 1.05, 1.02, NAN), ("depth", 1.00)),  # all agree
    ((1.00, 0.9, 1.05, NAN, NAN), ("depth", 1.00)),  # depth + LiDAR
    ((1.00, 0.9, NAN, 1.10, NAN), ("depth", 1.00)),  # depth + kinematics
    ((1.00, 0.9, 1.80, 1.05, NAN), ("depth", 1.00)),  # LiDAR outvoted (a spoof)
    ((1.00, 0.9, NAN, NAN, NAN), ("depth", 1.00)),  # first sight, confident: nothing to vote against
    ((1.00, 0.2, NAN, NAN, 1.3), ("depth (unconfirmed)", 1.00)),  # first sight, unsure: repaired around it
    ((1.60, 0.9, 1.02, 1.00, NAN), ("lidar+kinematics", 1.02)),  # depth outvoted (a bias)
    ((1.15, 0.9, 1.00, 1.01, NAN), ("lidar+kinematics", 1.00)),  # a ramp inside d_kin's tolerance, LiDAR confirms d_kin
    ((1.08, 0.9, 0.95, 1.01, NAN), ("depth", 1.08)),  # off the LiDAR but within tau of d_kin: clean noise
    ((NAN, 0.0, 1.02, 1.00, NAN), ("lidar+kinematics", 1.02)),  # blackout, LiDAR confirmed
    ((1.60, 0.9, 1.02, NAN, NAN), ("lidar", 1.02)),  # depth against LiDAR, no kinematics yet
    ((1.60, 0.9, NAN, 1.00, NAN), ("kinematics", 1.00)),  # depth against kinematics
    ((NAN, 0.0, NAN, 1.00, NAN), ("kinematics", 1.00)),  # blackout, no LiDAR
    ((NAN, 0.0, 1.80, 1.00, NAN), ("kinematics", 1.00)),  # blackout + spoofed LiDAR
    ((1.60, 0.9, 2.20, 1.00, NAN), ("kinematics", 1.00)),  # patch + spoof: three different answers
    ((NAN, 0.0, NAN, NAN, 1.30), ("prior", 1.30)),  # nothing but the forecast
    ((NAN, 0.0, NAN, NAN, NAN), ("none", NAN)),  # no target: no distance
]


@pytest.mark.parametrize("inputs,expected", TABLE)
def test_truth_table(inputs, expected):
    d, c, l, k, mu = inputs
    source, base, _ = vote(d, c, l, k, K_TOL, mu, GATE)
    assert SOURCES[source] == expected[0]
    assert (math.isnan(base) and math.isnan(expected[1])) or base == expected[1]


S_TOL = 0.15

# (depth, confidence, lidar, d_kin, d_size) -> (source, base): the four-witness gate (size tolerance 0.15 m).
SIZE_TABLE = [
    ((1.00, 0.2, NAN, NAN, 1.05), ("depth", 1.00)),  # first sight, unsure, but the box's size confirms it
    ((1.00, 0.2, NAN, NAN, 1.60), ("depth (unconfirmed)", 1.00)),  # nearer than the box: it may be occluded
    ((1.60, 0.9, NAN, NAN, 1.00), ("size", 1.00)),  # first sight, beyond the box: a bias pushing it away
    ((1.60, 0.9, 1.61, 1.58, 1.00), ("size", 1.00)),  # a frustum spoof moved all three: the box vetoes them
    ((1.60, 0.9, 1.61, 1.00, 1.00), ("kinematics", 1.00)),  # depth and LiDAR spoofed, d_kin honest
    ((NAN, 0.0, NAN, NAN, 1.00), ("size", 1.00)),  # blackout from first sight, the scan plane misses the plate
    ((NAN, 0.0, 2.50, NAN, 1.00), ("size", 1.00)),  # ... and the LiDAR sees the wall behind it
    ((NAN, 0.0, 1.02, NAN, 1.00), ("lidar", 1.02)),  # blackout, the LiDAR within the box's bound
    ((NAN, 0.0, NAN, 1.05, 1.00), ("kinematics", 1.05)),  # blackout: the branch carries, the size agrees
    ((1.00, 0.9, 1.05, 1.02, 1.60), ("depth", 1.00)),  # a sticker shrank the box: nothing nearer is vetoed
    ((1.00, 0.9, 1.05, 1.02, 1.00), ("depth", 1.00)),  # all four agree
    ((1.00, 0.9, 1.05, NAN, 0.50), ("size", 0.50)),  # depth and LiDAR both beyond a (wrongly) large box
]


@pytest.mark.parametrize("inputs,expected", SIZE_TABLE)
def test_four_witness_truth_table(inputs, expected):
    d, c, l, k, s = inputs
    source, base, _ = vote(d, c, l, k, K_TOL, NAN, GATE, size=s, size_tol=S_TOL)
    assert SOURCES[source] == expected[0]
    assert base == expected[1]


@settings(max_examples=400, deadline=None)
@given(maybe, st.floats(0, 1), maybe, maybe, maybe, distance)
def test_nothing_beyond_the_size_witness_is_ever_the_output(d, c, l, k, mu, s):
    """A box only ever shrinks, so whatever the gate rests on lies within the size's tolerance
    of d_size or nearer (the prior, used when nothing else is, aside)."""
    source, base, _ = vote(d, c, l, k, K_TOL, mu, GATE, size=s, size_tol=S_TOL)
    assert SOURCES[source] == "prior" or base <= s + S_TOL


@settings(max_examples=400, deadline=None)
@given(distance, st.floats(0, 1), maybe, maybe, maybe, st.floats(0, 1))
def test_without_a_size_witness_the_gate_is_the_three_witness_gate(d, c, l, k, mu, share):
    assert vote(d, c, l, k, K_TOL, mu, GATE) == vote(d, c, l, k, K_TOL, mu, GATE, size=NAN, size_tol=NAN)


@settings(max_examples=400, deadline=None)
@given(distance, st.floats(0, 1), maybe, st.floats(0, 1), st.floats(-1, 1))
def test_depth_confirmed_by_the_lidar_passes_unless_beyond_the_size(d, c, k, share, size_share):
    """Proposition 1 with four witnesses: depth within tau of the LiDAR passes unchanged while the
    box's size allows both (neither beyond d_size + tolerance); beyond it, it never passes."""
    l = d + 0.999 * share * GATE.tau_m
    # size_share >= 0: the box allows both; < 0: it says nearer than the depth by more than its tolerance.
    s = max(d, l) - 0.999 * S_TOL * size_share if size_share >= 0 else d - S_TOL * (1.001 - size_share)
    source, base, _ = vote(d, c, l, k, K_TOL, NAN, GATE, size=s, size_tol=S_TOL)
    assert (SOURCES[source] == "depth" and base == d) == (size_share >= 0)


def test_the_two_witness_gate_lets_the_lidar_alone_overrule_the_depth():
    source, base, trusted = vote(1.00, 0.9, 1.80, 1.05, K_TOL, NAN, GATE, kinematics_votes=False)
    assert SOURCES[source] == "lidar" and base == 1.80 and trusted
    source, base, _ = vote(1.60, 0.2, NAN, 1.00, K_TOL, NAN, GATE, kinematics_votes=False)
    assert SOURCES[source] == "kinematics"  # unconfirmed depth: kinematics still bases the repair


@settings(max_examples=400, deadline=None)
@given(distance, st.floats(0, 1), maybe, maybe, st.floats(0, 1), maybe)
def test_depth_that_agrees_with_a_witness_passes_unchanged(d, c, l, k, share, mu):
    """Proposition 1: depth within tau of the LiDAR passes whatever d_kin says; depth within
    d_kin's tolerance passes unless the LiDAR confirms d_kin against it (off both by > tau)."""
    source, base, _ = vote(d, c, d + 0.999 * share * GATE.tau_m, k, K_TOL, mu, GATE)
    assert SOURCES[source] == "depth" and base == d
    kin = d - 0.999 * share * K_TOL
    source, base, _ = vote(d, c, l, kin, K_TOL, mu, GATE)
    lidar_outvotes = l == l and abs(l - kin) <= K_TOL and abs(d - l) > GATE.tau_m and abs(d - kin) > GATE.tau_m
    assert (SOURCES[source] == "depth" and base == d) != lidar_outvotes


@settings(max_examples=400, deadline=None)
@given(maybe, st.floats(0, 1), distance, distance, maybe)
def test_a_lidar_that_disagrees_with_depth_and_kinematics_is_never_used(d, c, l, k, mu):
    if abs(l - k) <= K_TOL or (not math.isnan(d) and abs(l - d) <= GATE.tau_m):
        return
    source, base, trusted = vote(d, c, l, k, K_TOL, mu, GATE)
    assert not trusted and "lidar" not in SOURCES[source] and base != l


def test_bad_settings_are_clear_errors():
    with pytest.raises(ValueError, match="tau_m"):
        GateConfig(tau_m=0.0)
    with pytest.raises(ValueError, match="trust_confidence"):
        GateConfig(trust_confidence=2.0)
    with pytest.raises(ValueError, match="size_sigma"):
        GateConfig(size_sigma=-1.0)
