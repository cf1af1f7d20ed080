"""segment_scan gives exactly scikit-learn's DBSCAN(min_samples=1) partition."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from scipy.spatial.distance import pdist
from sklearn.cluster import DBSCAN

from racf.controllers.lidar_segmentation import bench_segmentation, scan_points, segment_scan

SCANS = Path(__file__).resolve().parents[1] / "data" / "lidar_scans.npz"


def _first_appearance(labels: np.ndarray) -> np.ndarray:
    names: dict[int, int] = {}
    return np.array([names.setdefault(int(v), len(names)) for v in labels], np.int64)


def _dbscan(points: np.ndarray, eps: float) -> np.ndarray:
    return _first_appearance(DBSCAN(eps=eps, min_samples=1).fit_predict(points))


def _no_ties(points: np.ndarray, eps: float) -> bool:
    """No pair at distance eps to within rounding (where float evaluation order decides)."""
    return len(points) < 2 or bool(np.all(np.abs(pdist(points) - eps) > 1e-9 * max(1.0, eps)))


def _beams(n: int, ranges: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return scan_points(ranges, 2 * np.pi * np.arange(n) / n)


@st.composite
def _scans(draw):
    """A random scan: walls (random walks in range), small objects, isolated returns, gaps."""
    n = draw(st.integers(8, 360))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    eps = draw(st.sampled_from([0.01, 0.03, 0.06, 0.1, 0.3, 1.0]))
    style = draw(st.sampled_from(["walk", "uniform", "near"]))
    if style == "walk":
        ranges = np.abs(1.5 + np.cumsum(rng.normal(0.0, 0.05, n)) + rng.normal(0, 0.01, n)) + 0.05
        jumps = rng.random(n) < 0.05
        ranges[jumps] *= rng.uniform(0.3, 0.9, jumps.sum())
    elif style == "uniform":
        ranges = rng.uniform(0.05, 5.0, n)
    else:
        ranges = rng.uniform(0.0, 0.3, n)
    ranges[rng.random(n) < draw(st.sampled_from([0.0, 0.2, 0.6]))] = np.inf
    return n, ranges, eps


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_scans())
def test_random_scans_match_dbscan(scan):
    n, ranges, eps = scan
    points, _, _ = _beams(n, ranges)
    assume(_no_ties(points, eps))
    expected = _dbscan(points, eps) if len(points) else np.zeros(0, np.int64)
    np.testing.assert_array_equal(segment_scan(points, eps), expected)
    np.testing.assert_array_equal(segment_scan(points, eps, beam_step_rad=2 * np.pi / n), expected)


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 60), st.integers(0, 2**32 - 1), st.sampled_from([0.05, 0.2, 0.5, 3.0]),
       st.sampled_from([0.0, 0.01, 1.0]))
def test_points_in_any_order_match_dbscan(n, seed, eps, grid):
    rng = np.random.default_rng(seed)
    points = rng.uniform(-2, 2, (n, 2))
    if grid:  # snapped points: duplicates and equal angles
        points = np.round(points / grid) * grid
    assume(_no_ties(points, eps))
    expected = _dbscan(points, eps) if len(points) else np.zeros(0, np.int64)
    np.testing.assert_array_equal(segment_scan(points, eps), expected)


@pytest.mark.parametrize("eps", [0.03, 0.06, 0.1, 0.25])
def test_recorded_scans_match_dbscan(eps):
    data = np.load(SCANS)
    scans = data["ranges"]
    assert scans.shape == (30, 360) and scans.dtype == np.float32
    n = scans.shape[1]
    forward = np.r_[np.arange(n - 70, n), np.arange(0, 71)]  # +-70 deg, rolled into scan order
    for ranges in scans:
        points, _, _ = _beams(n, ranges)
        np.testing.assert_array_equal(segment_scan(points, eps), _dbscan(points, eps))
        np.testing.assert_array_equal(segment_scan(points, eps, beam_step_rad=2 * np.pi / n), _dbscan(points, eps))
        sector, _, _ = scan_points(ranges[forward], 2 * np.pi * forward / n, 4.0)
        np.testing.assert_array_equal(segment_scan(sector, eps, beam_step_rad=2 * np.pi / n), _dbscan(sector, eps))


def test_labels_are_numbered_by_first_appearance_and_the_scan_wraps():
    # Beams 0, 1 and 358, 359 see one wall straight ahead: one cluster across the wrap.
    ranges = np.full(360, np.inf)
    ranges[[0, 1, 358, 359]] = 2.0
    ranges[[90, 91]] = 1.0
    ranges[[180]] = 3.0
    points, _, _ = _beams(360, ranges)
    np.testing.assert_array_equal(segment_scan(points, 0.06), [0, 0, 1, 1, 2, 0, 0])


def test_small_cases_and_points_at_the_scanner():
    assert segment_scan(np.zeros((0, 2)), 0.1).shape == (0,)
    np.testing.assert_array_equal(segment_scan(np.array([[1.0, 2.0]]), 0.1), [0])
    # A point at the origin has no angle bound: everything within eps of it is linked.
    points = np.array([[0.0, 0.0], [0.05, 0.0], [-0.04, 0.0], [1.0, 1.0], [1.0, 1.0]])
    np.testing.assert_array_equal(segment_scan(points, 0.06), _dbscan(points, 0.06))
    np.testing.assert_array_equal(segment_scan(points, 0.06), [0, 0, 0, 1, 1])


def test_unsorted_points_with_a_single_descent_are_sorted_first():
    # Angles -45, 90, 153, 90 deg: one descent but not a wrapped scan (found by hypothesis).
    points = np.array([[1.0, -1.0], [0.0, 1.0], [-2.0, 1.0], [0.0, 1.0]])
    np.testing.assert_array_equal(segment_scan(points, 0.05), [0, 1, 2, 1])


def test_eps_larger_than_the_nearest_range_compares_everything():
    rng = np.random.default_rng(3)
    points = rng.normal(size=(80, 2)) * 0.3
    for eps in (0.1, 0.4, 2.0):
        np.testing.assert_array_equal(segment_scan(points, eps), _dbscan(points, eps))


def test_many_links_between_runs_use_the_sparse_path():
    # Two interleaved combs: every scan neighbour is far, every second one is near, so the
    # components come from many links at offset 2 (more than the union-find handles).
    n = 360
    ranges = np.where(np.arange(n) % 2 == 0, 1.0, 1.5)
    points, _, _ = _beams(n, ranges)
    labels = segment_scan(points, 0.06)
    np.testing.assert_array_equal(labels, _dbscan(points, 0.06))
    np.testing.assert_array_equal(labels[:4], [0, 1, 0, 1])


def test_bad_inputs_raise():
    with pytest.raises(ValueError, match="shape"):
        segment_scan(np.zeros((4, 3)), 0.1)
    with pytest.raises(ValueError, match="eps_m"):
        segment_scan(np.zeros((4, 2)), 0.0)
    with pytest.raises(ValueError, match="finite"):
        segment_scan(np.array([[1.0, 0.0], [np.nan, 1.0]]), 0.1)
    with pytest.raises(ValueError, match="beam_step_rad"):
        segment_scan(np.ones((3, 2)), 0.1, beam_step_rad=0.0)


def test_scan_points_keeps_valid_returns_in_beam_order():
    ranges = np.array([1.0, np.inf, np.nan, -1.0, 0.0, 2.0, 5.0, 3.0])
    angles = np.linspace(0, 2 * np.pi, 8, endpoint=False)
    points, r, a = scan_points(ranges, angles, max_range_m=4.0)
    np.testing.assert_array_equal(r, [1.0, 2.0, 3.0])
    np.testing.assert_array_equal(a, angles[[0, 5, 7]])
    np.testing.assert_allclose(points, np.column_stack([r * np.cos(a), r * np.sin(a)]))
    with pytest.raises(ValueError):
        scan_points(ranges, angles[:4])


def test_bench_runs_on_the_recorded_scans():
    res = bench_segmentation(np.load(SCANS)["ranges"][:3], repeats=1)
    assert res["ours_us"] > 0 and res["sklearn_us"] > 0 and math.isfinite(res["mean_points"])
