"""Quanser's LiDAR read and 1-degree filter: hand-worked scans, the A2M12's 1600 samples, properties.

Angles are degrees, as the driver's own; ranges metres; 0 = no return. The filter's gap rule
is Quanser's half-open slice (bins ceil(a) <= k < floor(b) of a too-wide gap a -> b read 0)
and, by default, its unbridged ends (bins below round(first) and above round(last) read 0).
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from racf.sim.sensors.lidar_driver import (
    DriverConfig,
    deliver,
    filter_rplidar_data,
    quanser_read,
)

WALL_M = 2.0
POLE_M = 0.5


def _bins(out: np.ndarray) -> dict[int, float]:
    """The non-zero bins of a scan, as {bin: range}."""
    return {int(j): float(out[j]) for j in np.flatnonzero(out)}


def _scan(values: dict[int, float], n_bins: int = 360) -> np.ndarray:
    """The full (n_bins,) expected scan: the given bins, every other bin 0."""
    out = np.zeros(n_bins)
    for j, r in values.items():
        out[j] = r
    return out


def _pick_indices(n: int, read: int) -> list[int]:
    """The driver's picks written out with Python's round (half to even), for an independent check."""
    return [round(k * n / read) for k in range(read)]


# -- (a) a hand-worked 8-sample scan ---------------------------------------------------------

# A wall (about 3 m, slanted from 2.8 to 3.1 m) with a near object (0.5 m) at 10 to 10.25 deg,
# a no-return at 12 deg, and one angle given past 360 (373.75 = 13.75 deg).
EIGHT_ANGLES = np.array([8.5, 9.25, 10.0, 10.25, 11.25, 12.0, 13.0, 373.75])
EIGHT_RANGES = np.array([2.8, 3.1, 0.5, 0.5, 3.0, 0.0, 3.0, 3.0])
# The gap round the circle, 13.75 (3.0 m) -> 368.5 (2.8 m), is 354.75 deg wide.
EIGHT_COMMON = {
    # 8: below the first sample (8.5), but round(8.5) = 8 (half to even), so bin 8 keeps the
    # interpolation across the circle, 354.25 deg on from 13.75: 3.0 - 0.2 * 354.25 / 354.75.
    8: 2.8 + 0.2 * 0.5 / 354.75,
    9: 3.0,  # between 8.5 (2.8) and 9.25 (3.1): t = 0.5 / 0.75 = 2/3, 2.8 + 0.3 * 2/3
    10: 0.5,  # exactly on the sample at 10 deg (the gap after it, 0.25 deg, is narrow)
    11: 2.375,  # mixed: between 10.25 (0.5, object) and 11.25 (3.0, wall), t = 0.75
    # 12: the 12 deg sample is a no-return, so 11.25 -> 13.0 is a 1.75 deg gap > 1.1, and
    #     ceil(11.25) = 12 <= 12 < floor(13.0) = 13: 0
    13: 3.0,  # exactly on the sample at 13 deg (13 -> 13.75 is narrow)
}
# Quanser's (wrap=False): round(13.75) = 14, so bin 14 keeps the interpolation across the
# circle (0.25 deg on from 13.75) and bins 15 .. 359 and 0 .. 7 read 0.
EIGHT_NO_WRAP = EIGHT_COMMON | {14: 3.0 - 0.2 * 0.25 / 354.75}
# wrap=True: the 354.75 deg gap is too wide and zeroes ceil(13.75) = 14 <= k < floor(368.5) =
# 368, i.e. bins 14 .. 359 and 0 .. 7; bin 8 is less than a bin below 8.5 and keeps its range.
EIGHT_WRAP = EIGHT_COMMON


@pytest.mark.parametrize("wrap, expected", [(False, EIGHT_NO_WRAP), (True, EIGHT_WRAP)], ids=["quanser", "wrap"])
def test_hand_worked_eight_sample_scan(wrap, expected):
    out = filter_rplidar_data(EIGHT_ANGLES, EIGHT_RANGES, wrap=wrap)
    assert out.shape == (360,)
    np.testing.assert_allclose(out, _scan(expected), rtol=0, atol=1e-12)
    # The mixed point is neither the object nor the wall: the real driver's false point.
    assert POLE_M < out[11] < 3.0


def test_default_is_quanser_no_wrap():
    np.testing.assert_array_equal(
        filter_rplidar_data(EIGHT_ANGLES, EIGHT_RANGES), filter_rplidar_data(EIGHT_ANGLES, EIGHT_RANGES, wrap=False)
    )


def test_sample_order_does_not_matter():
    order = np.array([5, 2, 7, 0, 3, 6, 1, 4])
    for wrap in (False, True):
        np.testing.assert_array_equal(
            filter_rplidar_data(EIGHT_ANGLES[order], EIGHT_RANGES[order], wrap=wrap),
            filter_rplidar_data(EIGHT_ANGLES, EIGHT_RANGES, wrap=wrap),
        )


# -- (b) the half-open slice ---------------------------------------------------------------------


def _wall_with_gap(lo: float, hi: float) -> tuple[np.ndarray, np.ndarray]:
    """A 2 m wall sampled every 0.5 deg round the circle, with no sample strictly inside (lo, hi)."""
    grid = np.arange(720) * 0.5
    angles = np.r_[grid[grid < lo], lo, hi, grid[grid > hi]]
    return angles, np.full(angles.size, WALL_M)


@pytest.mark.parametrize("wrap", [False, True])
@pytest.mark.parametrize(
    "lo, hi, zeroed",
    [
        # 1.125 deg holding bin 11 but not 11 and 12: ceil(10.4) = 11, floor(11.525) = 11, an
        # empty slice. Bin 11 keeps the interpolation (both ends 2 m).
        (10.4, 11.525, []),
        # 1.125 deg holding 10 and 11: ceil(9.95) = 10, floor(11.075) = 11, so bin 10 only.
        (9.95, 11.075, [10]),
        # 3 deg: ceil(10.5) = 11, floor(13.5) = 13: bins 11 and 12; 13 is interpolated.
        (10.5, 13.5, [11, 12]),
        # 1.125 deg starting on a bin: the bin on the sample is zeroed, 11 is not.
        (10.0, 11.125, [10]),
        # 1.125 deg ending on a bin: 10 is zeroed, 11 lies on the sample and keeps it.
        (9.875, 11.0, [10]),
        # 1.1 deg exactly is not "more than 1.1": nothing.
        (9.9, 11.0, []),
    ],
)
def test_half_open_slice(lo, hi, zeroed, wrap):
    angles, ranges = _wall_with_gap(lo, hi)
    out = filter_rplidar_data(angles, ranges, wrap=wrap)
    assert np.flatnonzero(out == 0).tolist() == zeroed
    np.testing.assert_array_equal(out[out != 0], WALL_M)


def test_half_open_slice_interpolates_the_last_bin_of_a_wide_gap():
    angles = np.array([9.0, 10.5, 13.5, 14.0])
    ranges = np.array([1.0, 1.0, 4.0, 4.0])
    out = filter_rplidar_data(angles, ranges)
    # 9.0 -> 10.5 (1.5 wide) zeroes 9 <= k < 10: bin 9, on its sample; bin 10 is interpolated
    # (1 m both ends). 10.5 -> 13.5 (3 wide) zeroes 11 and 12; bin 13 is 2.5 of the 3 deg from
    # 1 m to 4 m: 3.5 m. Bin 14 is on its sample (13.5 -> 14 is narrow). Ends round to 9, 14.
    np.testing.assert_allclose(out, _scan({10: 1.0, 13: 3.5, 14: 4.0}), rtol=0, atol=1e-12)


def test_a_bin_on_a_sample_is_zeroed_by_a_wide_gap_after_it():
    out = filter_rplidar_data(np.array([10.0, 11.5]), np.array([1.0, 2.0]))
    # 10 -> 11.5 is 1.5 wide: bin 10 (on 10.0) is zeroed, bin 11 = 1 + 1 / 1.5. round(11.5) =
    # 12, so bin 12 keeps the interpolation across the circle: 0.5 deg on from 11.5 towards
    # 370 (1 m), a 358.5 deg gap.
    np.testing.assert_allclose(
        out, _scan({11: 1.0 + 1.0 / 1.5, 12: 2.0 - 0.5 / 358.5}), rtol=0, atol=1e-12
    )


def test_bin_on_a_sample_takes_its_range_not_a_blend():
    out = filter_rplidar_data(np.array([9.5, 10.0, 10.5]), np.array([3.0, 0.7, 3.0]))
    np.testing.assert_array_equal(out, _scan({10: 0.7}))


def test_gap_equal_to_max_gap_is_bridged_wider_is_not():
    # "More than max_gap" zero-fills: a gap of exactly max_gap still interpolates.
    out = filter_rplidar_data(np.array([9.5, 11.0]), np.array([1.0, 2.0]), max_gap_deg=1.5)
    np.testing.assert_allclose(out, _scan({10: 1.0 + 0.5 / 1.5, 11: 2.0}), rtol=0, atol=1e-12)
    # 1.5625 wide: bin 10 is zeroed, bin 11 (0.0625 below the next sample) interpolated.
    out = filter_rplidar_data(np.array([9.5, 11.0625]), np.array([1.0, 2.0]), max_gap_deg=1.5)
    np.testing.assert_array_equal(out, _scan({11: 1.0 + 1.5 / 1.5625}))
    # Wider than max_gap but holding no two whole bins: nothing zeroed (round(10.4375) = 10).
    out = filter_rplidar_data(np.array([9.5, 10.4375]), np.array([1.0, 2.0]), max_gap_deg=0.9)
    np.testing.assert_array_equal(out, _scan({10: 1.0 + 0.5 / 0.9375}))


def test_float_noise_on_a_whole_bin_does_not_move_the_slice():
    # 10 - 2e-15 is meant as 10 (an angle like 40 * 0.225 comes out a hair off): floor must
    # give 10, so that 8.875 -> 10 (1.125 wide) zeroes bin 9 (ends: round 9 and 10).
    ranges = np.array([WALL_M, WALL_M])
    exact = filter_rplidar_data(np.array([8.875, 10.0]), ranges)
    np.testing.assert_array_equal(exact, _scan({10: WALL_M}))
    np.testing.assert_array_equal(filter_rplidar_data(np.array([8.875, 10.0 - 2e-15]), ranges), exact)
    # And 9 + 2e-15 as 9: 9 -> 10.125 zeroes bin 9, on the sample.
    exact = filter_rplidar_data(np.array([9.0, 10.125]), ranges)
    np.testing.assert_array_equal(exact, _scan({10: WALL_M}))
    np.testing.assert_array_equal(filter_rplidar_data(np.array([9.0 + 2e-15, 10.125]), ranges), exact)


# -- (c) the ends: Quanser's unbridged first/last samples, and wrap=True -------------------------


def test_no_wrap_zeroes_beyond_the_rounded_ends():
    angles, ranges = np.array([9.6, 10.4, 11.2]), np.array([1.0, 2.0, 3.0])
    # round(9.6) = 10, round(11.2) = 11: only bins 10 (t = 0.5) and 11 (t = 0.75) survive.
    np.testing.assert_allclose(filter_rplidar_data(angles, ranges), _scan({10: 1.5, 11: 2.75}), rtol=0, atol=1e-12)
    # wrap=True: 11.2 -> 369.6 (358.4 deg) zeroes 12 <= k < 369, i.e. 12 .. 359 and 0 .. 8; bin
    # 9 lies 357.8 deg on from 11.2 (3 m) towards 369.6 (1 m).
    np.testing.assert_allclose(
        filter_rplidar_data(angles, ranges, wrap=True),
        _scan({9: 3.0 - 2.0 * 357.8 / 358.4, 10: 1.5, 11: 2.75}),
        rtol=0,
        atol=1e-12,
    )


def test_no_wrap_rounds_the_ends_half_to_even():
    angles, ranges = np.array([10.5, 11.5]), np.array([1.0, 2.0])
    # round(10.5) = 10 and round(11.5) = 12: bins 10 and 12 lie beyond the samples but inside
    # the rounded ends, and keep the interpolation across the 359 deg gap round the circle.
    np.testing.assert_allclose(
        filter_rplidar_data(angles, ranges),
        _scan({10: 2.0 - 358.5 / 359.0, 11: 1.5, 12: 2.0 - 0.5 / 359.0}),
        rtol=0,
        atol=1e-12,
    )
    # 11.5 and 12.5 both round to 12: bin 12 alone.
    np.testing.assert_array_equal(filter_rplidar_data(np.array([11.5, 12.5]), ranges), _scan({12: 1.5}))
    # wrap=True: 11.5 -> 370.5 zeroes 12 <= k < 370; bin 10 is half a bin below 10.5 and stays.
    np.testing.assert_allclose(
        filter_rplidar_data(angles, ranges, wrap=True),
        _scan({10: 2.0 - 358.5 / 359.0, 11: 1.5}),
        rtol=0,
        atol=1e-12,
    )


def test_no_wrap_zeroes_bin_zero_even_across_a_narrow_gap():
    # A full circle of samples at 0.6, 1.6, ..., 359.6: every gap, round 0 too, is 1 deg.
    angles = np.arange(360) + 0.6
    ranges = np.full(360, WALL_M)
    # Quanser's: round(0.6) = 1, so bin 0 (below the first sample) reads 0 though the gap
    # 359.6 -> 360.6 is narrow; round(359.6) = 360 zeroes nothing at the top.
    np.testing.assert_array_equal(filter_rplidar_data(angles, ranges), np.r_[0.0, np.full(359, WALL_M)])
    # wrap=True bridges it.
    np.testing.assert_array_equal(filter_rplidar_data(angles, ranges, wrap=True), np.full(360, WALL_M))
    # Shifted to 0.4, 1.4, ...: round(0.4) = 0 and round(359.4) = 359, so nothing is lost.
    np.testing.assert_array_equal(filter_rplidar_data(angles - 0.2, ranges), np.full(360, WALL_M))


@pytest.mark.parametrize(
    "angles, ranges",
    [([359.5, 0.5], [1.0, 3.0]), ([-0.5, 360.5], [1.0, 3.0]), ([0.5, 719.5], [3.0, 1.0])],
)
@pytest.mark.parametrize("wrap", [False, True])
def test_interpolation_across_zero(angles, ranges, wrap):
    out = filter_rplidar_data(np.array(angles), np.array(ranges), wrap=wrap)
    # 359.5 (1 m) -> 0.5 (3 m) is a 1 deg gap across 0: bin 0 at t = 0.5, either way (round(0.5)
    # = 0 and round(359.5) = 360 leave it alone). 0.5 -> 359.5 is 359 wide and zeroes 1 .. 358;
    # bin 359 is half a bin below 359.5 and keeps its interpolation, 358.5 / 359 of the way.
    np.testing.assert_allclose(out, _scan({0: 2.0, 359: 3.0 - 2.0 * 358.5 / 359.0}), rtol=0, atol=1e-12)


def test_wrap_interpolation_weight_and_gap():
    out = filter_rplidar_data(np.array([359.75, 0.75]), np.array([1.0, 3.0]), wrap=True)
    assert out[0] == 1.5  # t = 0.25 / 1.0
    # 359.25 -> 360.5 is a 1.25 deg gap across 0, too wide, but it holds one whole degree
    # only (ceil = floor = 360): nothing zeroed, bin 0 at t = 0.75 / 1.25.
    out = filter_rplidar_data(np.array([359.25, 0.5]), np.array([1.0, 3.0]), wrap=True)
    assert out[0] == pytest.approx(1.0 + 2.0 * 0.75 / 1.25, abs=1e-12)
    # 359.875 -> 361.0 (1.125 wide) holds 360 and 361: bin 0 is zeroed.
    out = filter_rplidar_data(np.array([359.875, 1.0]), np.array([1.0, 3.0]), wrap=True)
    assert out[0] == 0.0


def test_tiny_negative_angle_wraps_onto_bin_zero():
    # -1e-30 wraps to 0, not 360: then 0 -> 1.0 is a narrow gap and round(0) = 0 keeps bin 0.
    out = filter_rplidar_data(np.array([-1e-30, 1.0]), np.array([1.25, 3.0]))
    np.testing.assert_array_equal(out, _scan({0: 1.25, 1: 3.0}))


# -- (d) a uniform wall through deliver() ------------------------------------------------------


def test_wall_through_evenly_spaced_picks_fills_every_bin():
    # 1536 = 4 * 384 samples a revolution: the picks are exactly 0.9375 deg apart (< 1.1).
    cfg = DriverConfig(samples_per_rev=1536)
    out = deliver(cfg.sample_angles_deg, np.full(1536, WALL_M), cfg)
    np.testing.assert_array_equal(out, np.full(360, WALL_M))


CLEAN_1600_LOST = [14, 30, 59, 75, 104, 120, 149, 165, 194, 210, 239, 255, 284, 300, 329, 345]


def test_wall_at_1600_per_rev_loses_16_bins():
    # 1600 / 384 = 25/6 samples a pick: the picks are 4 or 5 samples apart, i.e. 0.9 or
    # 1.125 deg (0.9375 only on average). 1.125 > 1.1, but a 1.125 gap a -> b zeroes only
    # ceil(a) <= k < floor(b): a bin only where it holds two consecutive whole degrees.
    cfg = DriverConfig()
    out = deliver(cfg.sample_angles_deg, np.full(1600, WALL_M), cfg)
    assert set(np.unique(out)) == {0.0, WALL_M}

    picks = _pick_indices(1600, 384)
    steps = np.diff(np.r_[picks, picks[0] + 1600])
    assert sorted(set(steps.tolist())) == [4, 5]
    assert int((steps == 5).sum()) == 64  # 64 gaps of 1.125 deg
    # The half-open slices worked out in exact arithmetic (pick p is at 360 p / 1600 deg).
    lost = set()
    for p, step in zip(picks, steps, strict=True):
        a, b = Fraction(360 * p, 1600), Fraction(360 * (p + step), 1600)
        if b - a > Fraction(11, 10):
            lost |= {k % 360 for k in range(math.ceil(a), math.floor(b))}
    assert sorted(lost) == CLEAN_1600_LOST
    assert np.flatnonzero(out == 0).tolist() == CLEAN_1600_LOST  # 16 of 360 bins (4.4 %)
    # The scan starts on 0 deg and ends at 359.1 (0.9 from 360): no loss at the ends, so a
    # circular driver would lose the same bins.
    read_a, read_r = quanser_read(cfg.sample_angles_deg, np.full(1600, WALL_M))
    np.testing.assert_array_equal(filter_rplidar_data(read_a, read_r, wrap=True), out)


def test_deliver_uses_quanser_no_wrap_ends():
    # The first pick (0 deg) a no-return: the first valid pick is at 0.9 deg, round(0.9) = 1,
    # so bin 0 reads 0 on top of the 16, though 359.1 -> 360.9 holds no two whole degrees.
    cfg = DriverConfig()
    ranges = np.full(1600, WALL_M)
    ranges[0] = 0.0
    out = deliver(cfg.sample_angles_deg, ranges, cfg)
    assert np.flatnonzero(out == 0).tolist() == [0, *CLEAN_1600_LOST]
    read_a, read_r = quanser_read(cfg.sample_angles_deg, ranges)
    assert np.flatnonzero(filter_rplidar_data(read_a, read_r, wrap=True) == 0).tolist() == CLEAN_1600_LOST


# -- (e) dropped picks ------------------------------------------------------------------------------


def test_dropping_every_other_pick_keeps_only_the_last_bin_of_each_gap():
    angles = np.arange(384) * 0.9375  # the 384 picks, evenly spread
    ranges = np.full(384, WALL_M)
    np.testing.assert_array_equal(filter_rplidar_data(angles, ranges), np.full(360, WALL_M))
    ranges[1::2] = 0.0  # every other pick is a no-return: the valid ones are 1.875 deg apart
    # Every gap a -> b = a + 1.875 is too wide and zeroes ceil(a) <= k < floor(b). What is left
    # is bin floor(b) where b is not whole: b = 1.875, 3.75, 5.625, 7.5, 9.375, 11.25, 13.125
    # keep bins 1, 3, ..., 13; b = 15 is whole, and bin 15 lies on a sample with a wide gap
    # after it, so it is zeroed. The pattern repeats every 15 deg; the last sample, 358.125,
    # rounds to 358, so bin 359 is beyond the end (and zeroed by 358.125 -> 360 with wrap).
    kept = [15 * i + j for i in range(24) for j in (1, 3, 5, 7, 9, 11, 13)]
    for wrap in (False, True):
        out = filter_rplidar_data(angles, ranges, wrap=wrap)
        np.testing.assert_array_equal(out, _scan(dict.fromkeys(kept, WALL_M)))


# -- (f) a thin pole in the A2M12's 1600 samples ----------------------------------------------------


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


@pytest.mark.parametrize("samples_per_rev, mean_pole_m", [(1600, 0.9611), (1536, 0.9)])
def test_thin_pole_seen_exactly_where_a_pick_lands_on_it(samples_per_rev, mean_pole_m):
    seen, picked, mean_nearest = _pole_survival(samples_per_rev)
    # Seen if and only if read: every pick has a bin less than a pick spacing away that the
    # half-open slice leaves alone, so 384 of the positions (24 % of 1600, 25 % of 1536).
    assert set(np.flatnonzero(seen).tolist()) == picked
    assert int(seen.sum()) == 384
    # When seen, the pole mostly reads as a mixed range, about 0.9 to 1 m against its true 0.5 m.
    assert mean_nearest == pytest.approx(mean_pole_m, abs=5e-4)


# -- edge cases ---------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "ranges", [[], [0.0, 0.0, 0.0], [np.nan, -1.0, np.inf]], ids=["empty", "zeros", "nan-negative-inf"]
)
@pytest.mark.parametrize("wrap", [False, True])
def test_no_valid_sample_gives_all_zeros(ranges, wrap):
    angles = np.arange(len(ranges), dtype=float)
    out = filter_rplidar_data(angles, np.array(ranges, dtype=float), wrap=wrap)
    np.testing.assert_array_equal(out, np.zeros(360))


@pytest.mark.parametrize(
    "angle, wrap, expected",
    [
        (42.0, False, {42: 1.5}),  # round(42) = 42: the rounded ends coincide on it
        (42.5, False, {42: 1.5}),  # round(42.5) = 42 (half to even)
        (43.5, False, {44: 1.5}),  # round(43.5) = 44: the bin past it
        (42.7, False, {43: 1.5}),
        (42.0, True, {}),  # the whole-circle gap after it is too wide and zeroes 42 .. 401
        (42.5, True, {42: 1.5}),  # 42.5 -> 402.5 zeroes 43 .. 401; 42 (= 402) is half a bin below 402.5
        (42.7, True, {42: 1.5}),
    ],
)
def test_one_valid_sample(angle, wrap, expected):
    out = filter_rplidar_data(np.array([angle]), np.array([1.5]), wrap=wrap)
    np.testing.assert_array_equal(out, _scan(expected))
    # Other samples being no-returns changes nothing.
    out = filter_rplidar_data(np.array([41.5, angle, 42.5]), np.array([0.0, 1.5, np.nan]), wrap=wrap)
    np.testing.assert_array_equal(out, _scan(expected))


@pytest.mark.parametrize("bad", [0.0, -1.0, np.nan, np.inf, -np.inf])
def test_bad_ranges_are_no_return(bad):
    out = filter_rplidar_data(np.array([9.5, 10.0, 10.5]), np.array([1.0, bad, 2.0]))
    # The middle sample is dropped; 9.5 -> 10.5 is 1 deg; round(9.5) = round(10.5) = 10.
    np.testing.assert_array_equal(out, _scan({10: 1.5}))


def test_non_finite_angle_is_no_return():
    out = filter_rplidar_data(np.array([9.5, np.nan, 10.5]), np.array([1.0, 0.2, 2.0]))
    np.testing.assert_array_equal(out, _scan({10: 1.5}))


def test_repeated_angle_keeps_the_first_given():
    np.testing.assert_array_equal(filter_rplidar_data(np.array([360.0, 0.0]), np.array([1.0, 2.0])), _scan({0: 1.0}))
    np.testing.assert_array_equal(filter_rplidar_data(np.array([0.0, 360.0]), np.array([2.0, 1.0])), _scan({0: 2.0}))


def test_length_mismatch_names_both_lengths():
    with pytest.raises(ValueError, match=r"angles_deg has 3 .* ranges_m has 2"):
        filter_rplidar_data(np.zeros(3), np.zeros(2))
    with pytest.raises(ValueError, match=r"angles_deg has 5 .* ranges_m has 4"):
        quanser_read(np.zeros(5), np.zeros(4), read_per_rev=2)


@pytest.mark.parametrize("wrap", [1, 0, None, "yes"])
def test_wrap_must_be_a_bool(wrap):
    with pytest.raises(ValueError, match="wrap must be a bool"):
        filter_rplidar_data(np.zeros(3), np.ones(3), wrap=wrap)


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


# -- (g) properties: Quanser's code, written out literally, as the oracle --------------------------

_bad_range = st.sampled_from([0.0, -1.0, math.nan, math.inf])
_range = st.one_of(st.floats(0.05, 20.0), _bad_range)
# Angles on a 1/16 deg lattice (exact in binary, wrapped from [-360, 720)), so the oracle's
# ceil, floor, round and "gap > max_gap" are exact and cannot disagree with the module by rounding.
_angle16 = st.integers(-5760, 11519).map(lambda k: k / 16)


def _quanser_oracle(angles, ranges, n_bins, max_gap, wrap):
    """Quanser's ``filter_rplidar_data`` line by line, in bins (bin k at k) instead of radians.

    The grid is ``arange(n_bins)`` (the real one is a linspace that ends on 360 deg; the module
    does not model that). With ``wrap`` the first sample is appended one circle on, so the gap
    round the circle goes through the same slice, and the ends are not zeroed.
    """
    a = np.asarray(angles, float)
    r = np.asarray(ranges, float)
    ok = np.isfinite(a) & np.isfinite(r) & (r > 0)  # Quanser's own test is only r == 0
    phi_meas = np.mod(a[ok], 360.0) * (n_bins / 360.0)
    r_meas = r[ok]
    if phi_meas.size == 0:
        return np.zeros(n_bins)
    phi_meas, ids = np.unique(phi_meas, return_index=True)
    r_meas = r_meas[ids]
    r_filtered = np.interp(np.arange(n_bins), phi_meas, r_meas, period=n_bins)
    if wrap:
        phi_meas = np.append(phi_meas, phi_meas[0] + n_bins)
    ids = np.diff(phi_meas) > max_gap * n_bins / 360.0
    ids_lb = np.append(ids, False)
    ids_ub = np.append(False, ids)
    lb = np.ceil(phi_meas[ids_lb]).astype(int)
    ub = np.floor(phi_meas[ids_ub]).astype(int)
    for lo, hi in zip(lb, ub, strict=True):
        r_filtered[np.arange(lo, hi) % n_bins] = 0
    if not wrap:
        r_filtered[0 : int(np.round(phi_meas[0]))] = 0
        r_filtered[int(np.round(phi_meas[-1])) + 1 :] = 0
    return r_filtered


# Sparse scans: a few samples anywhere.
_sparse = st.lists(st.tuples(_angle16, _range), max_size=40)


@st.composite
def _dense(draw) -> list[tuple[float, float]]:
    """A run of 1/16 .. 2 deg steps from a lattice start, mostly valid: narrow and wide gaps,
    near-full circles (up to 400 samples, past 360 deg too) and narrow gaps across 0 all come up.
    Whole-degree starts and steps of 1/2, 1, 1.125 and 1.5 deg make the edge cases (a sample on
    a bin, a gap of exactly max_gap, two whole degrees in a 1.125 gap) common."""
    start = draw(st.one_of(_angle16, st.integers(-360, 719).map(float)))
    steps = draw(st.lists(st.one_of(st.integers(1, 32), st.sampled_from([8, 16, 18, 24])), min_size=1, max_size=400))
    ranges = draw(st.lists(st.one_of(st.just(WALL_M), _range), min_size=len(steps), max_size=len(steps)))
    return [(start + c / 16, r) for c, r in zip(np.cumsum(steps).tolist(), ranges, strict=True)]


_scans = st.one_of(_sparse, _dense())


@settings(max_examples=300, deadline=None)
@given(
    samples=_scans,
    n_bins=st.sampled_from([360, 720]),
    max_gap=st.sampled_from([0.5, 1.0, 1.1, 3.0]),
    wrap=st.booleans(),
)
def test_property_matches_quanser_code(samples, n_bins, max_gap, wrap):
    angles = np.array([s[0] for s in samples], float)
    ranges = np.array([s[1] for s in samples], float)
    out = filter_rplidar_data(angles, ranges, n_bins=n_bins, max_gap_deg=max_gap, wrap=wrap)
    expected = _quanser_oracle(angles, ranges, n_bins, max_gap, wrap)
    valid = ranges[np.isfinite(ranges) & (ranges > 0)]
    if valid.size:
        nz = out[out != 0]
        assert np.all((nz >= valid.min()) & (nz <= valid.max()))
    np.testing.assert_array_equal(out == 0, expected == 0)
    np.testing.assert_allclose(out, expected, rtol=1e-12, atol=0)


@settings(max_examples=150, deadline=None)
@given(samples=_scans, shift=st.integers(-400, 400))
def test_property_wrap_true_turns_with_the_scan(samples, shift):
    # Circular: turning every angle by whole degrees turns the scan by as many bins. (Not so
    # without wrap: there the ends at 0 deg are fixed.)
    angles = np.array([s[0] for s in samples], float)
    ranges = np.array([s[1] for s in samples], float)
    out = filter_rplidar_data(angles, ranges, wrap=True)
    np.testing.assert_array_equal(filter_rplidar_data(angles + shift, ranges, wrap=True), np.roll(out, shift))


@settings(max_examples=150, deadline=None)
@given(samples=_scans)
def test_property_wrap_only_changes_bins_between_the_last_and_first_sample(samples):
    angles = np.array([s[0] for s in samples], float)
    ranges = np.array([s[1] for s in samples], float)
    no_wrap = filter_rplidar_data(angles, ranges)
    circular = filter_rplidar_data(angles, ranges, wrap=True)
    ok = np.isfinite(ranges) & (ranges > 0)
    if not ok.any():
        return
    phi = np.mod(angles[ok], 360.0)
    inside = (np.arange(360) >= phi.min()) & (np.arange(360) < phi.max())
    np.testing.assert_array_equal(no_wrap[inside], circular[inside])
    # Beyond the rounded ends, no wrap reads 0.
    k = np.arange(360)
    assert not no_wrap[(k < np.round(phi.min())) | (k > np.round(phi.max()))].any()


@settings(max_examples=100, deadline=None)
@given(
    samples=st.lists(
        st.tuples(st.floats(-720.0, 720.0), st.one_of(st.floats(0.01, 30.0), _bad_range)), min_size=1, max_size=60
    ),
    wrap=st.booleans(),
)
def test_property_any_float_angles_stay_between_valid_ranges(samples, wrap):
    angles = np.array([s[0] for s in samples], float)
    ranges = np.array([s[1] for s in samples], float)
    out = filter_rplidar_data(angles, ranges, wrap=wrap)
    assert out.shape == (360,) and np.all(np.isfinite(out))
    valid = ranges[np.isfinite(ranges) & (ranges > 0)]
    nz = out[out != 0]
    if valid.size == 0:
        assert nz.size == 0
    else:
        assert np.all((nz >= valid.min()) & (nz <= valid.max()))
