"""Quanser's LiDAR read and 1-degree filter: hand-worked scans, the A2M12's 1600 samples, a property.

Angles are degrees, as the driver's own; ranges metres; 0 = no return.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sim.sensors.lidar_driver import DriverConfig, deliver, filter_rplidar_data, quanser_read

WALL_M = 2.0
POLE_M = 0.5


def _bins(out: np.ndarray) -> dict[int, float]:
    """The non-zero bins of a scan, as {bin: range}."""
    return {int(j): float(out[j]) for j in np.flatnonzero(out)}


def _pick_indices(n: int, read: int) -> list[int]:
    """The driver's picks written out with Python's round (half to even), for an independent check."""
    return [round(k * n / read) for k in range(read)]


# -- (a) a hand-worked 8-sample scan ---------------------------------------------------------

# A wall (about 3 m, slanted from 2.8 to 3.1 m) with a near object (0.5 m) at 10 to 10.25 deg,
# a no-return at 12 deg, and one angle given past 360 (373.75 = 13.75 deg).
EIGHT_ANGLES = np.array([8.5, 9.25, 10.0, 10.25, 11.25, 12.0, 13.0, 373.75])
EIGHT_RANGES = np.array([2.8, 3.1, 0.5, 0.5, 3.0, 0.0, 3.0, 3.0])
EIGHT_EXPECTED = {
    9: 3.0,  # between 8.5 (2.8) and 9.25 (3.1): t = 0.5 / 0.75 = 2/3, 2.8 + 0.3 * 2/3
    10: 0.5,  # exactly on the sample at 10 deg
    11: 2.375,  # mixed: between 10.25 (0.5, object) and 11.25 (3.0, wall), t = 0.75
    # 12: the 12 deg sample is a no-return, so 11.25 -> 13.0 is a 1.75 deg gap > 1.1: 0
    13: 3.0,  # exactly on the sample at 13 deg
    # 8 and 14: the gap 13.75 -> 8.5 round the circle is 354.75 deg: 0
}


def test_hand_worked_eight_sample_scan():
    out = filter_rplidar_data(EIGHT_ANGLES, EIGHT_RANGES)
    assert out.shape == (360,)
    got = _bins(out)
    assert got.keys() == EIGHT_EXPECTED.keys()
    for j, r in EIGHT_EXPECTED.items():
        assert got[j] == pytest.approx(r, abs=1e-12), j
    # The mixed point is neither the object nor the wall: the real driver's false point.
    assert POLE_M < got[11] < 3.0


def test_sample_order_does_not_matter():
    order = np.array([5, 2, 7, 0, 3, 6, 1, 4])
    np.testing.assert_array_equal(
        filter_rplidar_data(EIGHT_ANGLES[order], EIGHT_RANGES[order]), filter_rplidar_data(EIGHT_ANGLES, EIGHT_RANGES)
    )


# -- (b) a uniform wall through deliver() ------------------------------------------------------


def test_wall_through_evenly_spaced_picks_fills_every_bin():
    # 1536 = 4 * 384 samples a revolution: the picks are exactly 0.9375 deg apart (< 1.1).
    cfg = DriverConfig(samples_per_rev=1536)
    out = deliver(cfg.sample_angles_deg, np.full(1536, WALL_M), cfg)
    np.testing.assert_array_equal(out, np.full(360, WALL_M))


def test_wall_at_1600_per_rev_loses_the_bins_in_wide_pick_gaps():
    # 1600 / 384 = 25/6 samples a pick: the picks are 4 or 5 samples apart, i.e. 0.9 or
    # 1.125 deg (0.9375 only on average). 1.125 > 1.1, so bins inside those gaps read 0.
    cfg = DriverConfig()
    angles = cfg.sample_angles_deg
    out = deliver(angles, np.full(1600, WALL_M), cfg)
    assert set(np.unique(out)) == {0.0, WALL_M}

    picks = np.array(_pick_indices(1600, 384))
    steps = np.diff(np.r_[picks, picks[0] + 1600])
    assert sorted(set(steps.tolist())) == [4, 5]
    assert int((steps == 5).sum()) == 64  # 64 gaps of 1.125 deg
    # The zero bins are exactly the whole degrees strictly inside those gaps.
    lo = picks[steps == 5] * 360 / 1600
    inside = {j % 360 for a in lo for j in range(math.floor(a) + 1, math.ceil(a + 1.125 - 1e-9))}
    assert set(np.flatnonzero(out == 0).tolist()) == inside
    assert len(inside) == 80  # 80 of 360 bins: 22 % of a clean wall reads "no return"


# -- (c) dropped picks zero-fill the gaps --------------------------------------------------------


def test_dropping_every_other_pick_zero_fills_the_gaps():
    angles = np.arange(384) * 0.9375  # the 384 picks, evenly spread
    ranges = np.full(384, WALL_M)
    np.testing.assert_array_equal(filter_rplidar_data(angles, ranges), np.full(360, WALL_M))
    ranges[1::2] = 0.0  # every other pick is a no-return: the valid ones are 1.875 deg apart
    out = filter_rplidar_data(angles, ranges)
    # Only bins lying exactly on a surviving pick keep a range: k * 1.875 whole <=> 8 | k,
    # i.e. every 15 deg.
    assert _bins(out) == {j: WALL_M for j in range(0, 360, 15)}


# -- (d) wrap-around across 0 deg ------------------------------------------------------------------


@pytest.mark.parametrize(
    "angles, ranges",
    [([359.5, 0.5], [1.0, 3.0]), ([-0.5, 360.5], [1.0, 3.0]), ([0.5, 719.5], [3.0, 1.0])],
)
def test_interpolation_wraps_across_zero(angles, ranges):
    out = filter_rplidar_data(np.array(angles), np.array(ranges))
    assert _bins(out) == {0: 2.0}  # 359.5 (1 m) -> 0.5 (3 m) is a 1 deg gap across 0: t = 0.5


def test_wrap_interpolation_weight_and_gap():
    out = filter_rplidar_data(np.array([359.75, 0.75]), np.array([1.0, 3.0]))
    assert _bins(out) == {0: 1.5}  # t = 0.25 / 1.0
    # 359.25 -> 0.5 is a 1.25 deg gap across 0: zero-filled like any other.
    assert not filter_rplidar_data(np.array([359.25, 0.5]), np.array([1.0, 3.0])).any()


def test_tiny_negative_angle_wraps_onto_bin_zero():
    out = filter_rplidar_data(np.array([-1e-30, 200.0]), np.array([1.25, 3.0]))
    assert _bins(out) == {0: 1.25, 200: 3.0}


# -- (e) a thin pole in the A2M12's 1600 samples ----------------------------------------------------


def _pole_survival(samples_per_rev: int) -> tuple[np.ndarray, set[int], float]:
    """Which of the pole positions (one sample at 0.5 m before a 2 m wall) deliver() shows."""
    cfg = DriverConfig(samples_per_rev=samples_per_rev)
    angles = cfg.sample_angles_deg
    seen = np.zeros(samples_per_rev, bool)
    nearest = []
    for i in range(samples_per_rev):
        ranges = np.full(samples_per_rev, WALL_M)
        ranges[i] = POLE_M
        out = deliver(angles, ranges, cfg)
        hit = (out > 0) & (out < WALL_M - 1e-9)
        seen[i] = hit.any()
        if seen[i]:
            nearest.append(out[hit].min())
    return seen, set(_pick_indices(samples_per_rev, 384)), float(np.mean(nearest))


def test_thin_pole_seen_only_where_a_pick_lands_on_it():
    seen, picked, mean_nearest = _pole_survival(1600)
    assert set(np.flatnonzero(seen).tolist()) <= picked  # never seen unless read
    assert len(picked) / 1600 == 0.24
    # Measured: 352 of 1600 positions (22 %), not all 384 picks (24 %): a pick next to a
    # 1.125 deg gap whose 0.9 deg side holds no whole degree (and that is not on one) only
    # feeds zero-filled bins.
    assert int(seen.sum()) == 352
    assert seen.mean() == pytest.approx(384 / 1600, abs=0.025)
    # When seen, the pole mostly reads as a mixed range, about 1.0 m against its true 0.5 m.
    assert 0.9 < mean_nearest < 1.1


def test_thin_pole_with_evenly_spaced_picks_survives_exactly_384_in_1536():
    seen, picked, _ = _pole_survival(1536)
    assert set(np.flatnonzero(seen).tolist()) == picked
    assert seen.mean() == 384 / 1536


# -- edge cases ---------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "ranges", [[], [0.0, 0.0, 0.0], [np.nan, -1.0, np.inf]], ids=["empty", "zeros", "nan-negative-inf"]
)
def test_no_valid_sample_gives_all_zeros(ranges):
    angles = np.arange(len(ranges), dtype=float)
    out = filter_rplidar_data(angles, np.array(ranges, dtype=float))
    np.testing.assert_array_equal(out, np.zeros(360))


def test_one_valid_sample_fills_only_the_bin_it_lies_on():
    assert _bins(filter_rplidar_data(np.array([42.0]), np.array([1.5]))) == {42: 1.5}
    # Off a bin, it fills nothing (the gap round a lone sample is the whole circle).
    assert not filter_rplidar_data(np.array([42.5]), np.array([1.5])).any()
    # Other samples being no-returns changes nothing.
    assert _bins(filter_rplidar_data(np.array([41.5, 42.0, 42.5]), np.array([0.0, 1.5, np.nan]))) == {42: 1.5}


def test_bin_on_a_sample_takes_its_range_not_a_blend():
    out = filter_rplidar_data(np.array([9.5, 10.0, 10.5]), np.array([3.0, 0.7, 3.0]))
    assert out[10] == 0.7


def test_gap_equal_to_max_gap_is_bridged_wider_is_not():
    # "wider than max_gap" zero-fills: a gap of exactly max_gap still interpolates.
    assert _bins(filter_rplidar_data(np.array([9.5, 10.5]), np.array([1.0, 2.0]), max_gap_deg=1.0)) == {10: 1.5}
    assert not filter_rplidar_data(np.array([9.5, 10.5625]), np.array([1.0, 2.0]), max_gap_deg=1.0).any()


@pytest.mark.parametrize("bad", [0.0, -1.0, np.nan, np.inf, -np.inf])
def test_bad_ranges_are_no_return(bad):
    out = filter_rplidar_data(np.array([9.5, 10.0, 10.5]), np.array([1.0, bad, 2.0]))
    assert _bins(out) == {10: 1.5}  # the middle sample is dropped; 9.5 -> 10.5 is 1 deg


def test_non_finite_angle_is_no_return():
    out = filter_rplidar_data(np.array([9.5, np.nan, 10.5]), np.array([1.0, 0.2, 2.0]))
    assert _bins(out) == {10: 1.5}


def test_repeated_angle_keeps_the_first_given():
    assert _bins(filter_rplidar_data(np.array([360.0, 0.0]), np.array([1.0, 2.0]))) == {0: 1.0}
    assert _bins(filter_rplidar_data(np.array([0.0, 360.0]), np.array([2.0, 1.0]))) == {0: 2.0}


def test_length_mismatch_names_both_lengths():
    with pytest.raises(ValueError, match=r"angles_deg has 3 .* ranges_m has 2"):
        filter_rplidar_data(np.zeros(3), np.zeros(2))
    with pytest.raises(ValueError, match=r"angles_deg has 5 .* ranges_m has 4"):
        quanser_read(np.zeros(5), np.zeros(4), read_per_rev=2)


def test_deliver_needs_one_whole_revolution():
    with pytest.raises(ValueError, match=r"samples_per_rev=1600 .* got 1599"):
        deliver(np.zeros(1599), np.zeros(1599))


def test_quanser_read_picks_match_pythons_round():
    n = 1600
    angles = np.arange(n) * 0.225
    ranges = np.arange(n, dtype=float)
    read_a, read_r = quanser_read(angles, ranges)
    idx = _pick_indices(n, 384)
    assert idx[3] == 12 and idx[9] == 38  # ties 12.5 and 37.5 go to even
    np.testing.assert_array_equal(read_r, ranges[idx])
    np.testing.assert_array_equal(read_a, angles[idx])
    with pytest.raises(ValueError, match="read_per_rev"):
        quanser_read(np.zeros(10), np.zeros(10), read_per_rev=11)


@pytest.mark.parametrize(
    "kwargs, field",
    [
        ({"samples_per_rev": 0}, "samples_per_rev"),
        ({"samples_per_rev": 1600.0}, "samples_per_rev"),
        ({"read_per_rev": 1601}, "read_per_rev"),
        ({"read_per_rev": True}, "read_per_rev"),
        ({"n_bins": 0}, "n_bins"),
        ({"max_gap_deg": 0.0}, "max_gap_deg"),
        ({"max_gap_deg": 360.0}, "max_gap_deg"),
        ({"max_gap_deg": float("nan")}, "max_gap_deg"),
    ],
)
def test_config_rejects_out_of_range_fields(kwargs, field):
    with pytest.raises(ValueError, match=rf"{field} must be .*\[|{field} must be .*\("):
        DriverConfig(**kwargs)


# -- (f) property: ranges stay between the valid inputs, zeros only where the gap rule says --------------

_bad_range = st.sampled_from([0.0, -1.0, math.nan, math.inf])
_range = st.one_of(st.floats(0.05, 20.0), _bad_range)
# Angles on a 1/16 deg lattice (exact in binary, wrapped from [-360, 720)), so the oracle's
# "on a bin" and "gap > max_gap" are exact and cannot disagree with the module by rounding.
_angle16 = st.integers(-5760, 11519).map(lambda k: k / 16)


def _oracle(angles, ranges, n_bins, max_gap):
    """Brute force over every (bin, sample) pair: (zero?, expected range) for each bin."""
    a = np.asarray(angles, float)
    r = np.asarray(ranges, float)
    ok = np.isfinite(r) & (r > 0)
    a, r = np.mod(a[ok], 360.0), r[ok]
    bins = np.arange(n_bins) * (360.0 / n_bins)
    if a.size == 0:
        return np.ones(n_bins, bool), np.zeros(n_bins)
    back = np.mod(bins[:, None] - a[None, :], 360.0)  # degrees back from each bin to each sample
    fwd = np.mod(a[None, :] - bins[:, None], 360.0)
    prev, nxt = back.argmin(1), fwd.argmin(1)  # argmin: the first given among equals
    rows = np.arange(n_bins)
    on = back[rows, prev] == 0
    gap = back[rows, prev] + fwd[rows, nxt]
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.where(gap > 0, back[rows, prev] / gap, 0.0)
    val = np.where(on, r[prev], r[prev] + (r[nxt] - r[prev]) * t)
    zero = ~on & (gap > max_gap)
    return zero, np.where(zero, 0.0, val)


@settings(max_examples=150, deadline=None)
@given(
    samples=st.lists(st.tuples(_angle16, _range), max_size=40),
    n_bins=st.sampled_from([360, 720]),
    max_gap=st.sampled_from([0.5, 1.1, 3.0]),
)
def test_property_ranges_bounded_and_zeros_only_in_gaps(samples, n_bins, max_gap):
    angles = np.array([s[0] for s in samples], float)
    ranges = np.array([s[1] for s in samples], float)
    out = filter_rplidar_data(angles, ranges, n_bins=n_bins, max_gap_deg=max_gap)
    zero, expected = _oracle(angles, ranges, n_bins, max_gap)
    valid = ranges[np.isfinite(ranges) & (ranges > 0)]
    if valid.size:
        nz = out[out != 0]
        assert np.all((nz >= valid.min()) & (nz <= valid.max()))
    np.testing.assert_array_equal(out == 0, zero)
    np.testing.assert_allclose(out, expected, rtol=1e-12, atol=0)


@settings(max_examples=100, deadline=None)
@given(
    samples=st.lists(
        st.tuples(st.floats(-720.0, 720.0), st.one_of(st.floats(0.01, 30.0), _bad_range)), min_size=1, max_size=60
    )
)
def test_property_any_float_angles_stay_between_valid_ranges(samples):
    angles = np.array([s[0] for s in samples], float)
    ranges = np.array([s[1] for s in samples], float)
    out = filter_rplidar_data(angles, ranges)
    assert out.shape == (360,) and np.all(np.isfinite(out))
    valid = ranges[np.isfinite(ranges) & (ranges > 0)]
    nz = out[out != 0]
    if valid.size == 0:
        assert nz.size == 0
    else:
        assert np.all((nz >= valid.min()) & (nz <= valid.max()))
