"""The gate that votes: its truth table, Proposition 1, and a spoofed LiDAR that cannot move the output."""

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from racf.odca import SOURCES, GateConfig, vote

NAN = math.nan
GATE = GateConfig(tau_m=0.1, trust_confidence=0.5)
K_TOL = 0.2


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


def test_the_two_witness_gate_lets_the_lidar_alone_overrule_the_depth():
    source, base, trusted = vote(1.00, 0.9, 1.80, 1.05, K_TOL, NAN, GATE, kinematics_votes=False)
    assert SOURCES[source] == "lidar" and base == 1.80 and trusted
    source, base, _ = vote(1.60, 0.2, NAN, 1.00, K_TOL, NAN, GATE, kinematics_votes=False)
    assert SOURCES[source] == "kinematics"  # unconfirmed depth: kinematics still bases the repair


distance = st.floats(0.2, 10.0)
maybe = st.one_of(st.just(NAN), distance)


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
