"""Exact single-linkage segmentation of one 2D LiDAR scan in scan order.

:func:`segment_scan` returns the clusters of ``sklearn.cluster.DBSCAN(eps, min_samples=1)``
(with ``min_samples=1`` every point is a core point, so DBSCAN's clusters are the connected
components of the graph that links two points at distance <= eps: single linkage), about
twenty times faster than scikit-learn on a 360-beam scan (see :func:`bench_segmentation`),
by comparing each point only with its next few neighbours in scan order.

Why that is exact. Take two returns p, q at ranges r_p, r_q >= r_min and angular separation
Delta in [0, pi]. Then

    |p - q|^2 = (r_p - r_q)^2 + 4 r_p r_q sin^2(Delta / 2) >= 4 r_min^2 sin^2(Delta / 2),

so |p - q| <= eps forces sin(Delta / 2) <= eps / (2 r_min), i.e.
Delta <= alpha = 2 asin(eps / (2 r_min)) (alpha = pi, "compare everything", when
eps >= 2 r_min). With the points sorted by angle around the circle, the points within
alpha counter-clockwise of point i are the next m_i points in circular order, and a pair
within alpha of each other is within alpha counter-clockwise of one of its two members. So
comparing every point with its next K = max_i m_i points (circularly; K is computed from
the actual angles, never from a nominal beam count) finds every link of the eps-graph, and
the pairs it also compares that are farther than eps are simply not linked. r_min is the
smallest range among the points, so the bound holds for every pair. Angles are computed
with ``arctan2`` and alpha gets a relative slack of 1e-9, so rounding in the angles cannot
drop a link. Points in any other order are sorted by angle first (same partition, labels
still numbered in the input order). With ``beam_step_rad`` (returns of distinct beams of
one scan, in scan order) no angle is computed: points k places apart in circular order are
at least k beam steps apart in angle both ways round, so K = floor(alpha / step) suffices.

Links are distances with ``dx^2 + dy^2 <= eps^2``, the test scikit-learn's KD-tree makes;
only a pair whose distance equals eps to within float rounding can be decided differently
by scikit-learn's brute-force path (which it takes for a dozen points or fewer, with the
|a|^2 + |b|^2 - 2 a.b expansion).

Components: links between scan neighbours (offset 1) form runs, found with a cumulative
sum; the few remaining links between different runs are merged with a small union-find (or
``scipy.sparse.csgraph.connected_components`` when there are many, e.g. for random points).

Run ``python controllers/lidar_segmentation.py [scans.npz]`` for a timing against
scikit-learn on the recorded scans.
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components

__all__ = ["segment_scan", "scan_points", "bench_segmentation"]

#: Above this many links between runs, components come from scipy instead of a Python loop.
_UNION_FIND_MAX_LINKS = 48
#: Relative slack on the angular bound (rounding of arctan2 and asin).
_ANGLE_SLACK = 1e-9


def scan_points(ranges: np.ndarray, angles: np.ndarray, max_range_m: float = np.inf
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Valid returns of a scan as points in the scan's frame.

    Args:
        ranges: (N,) beam ranges, metres; inf, NaN or <= 0 mean no return.
        angles: (N,) beam angles, radians, counter-clockwise from the scanner's +x.
        max_range_m: returns farther than this are dropped, metres.

    Returns:
        ``(points_xy, ranges, angles)`` of the kept returns, in beam order: (M, 2) float
        x, y in metres (x forward, y left), (M,) ranges in metres and (M,) angles in radians.
    """
    ranges = np.asarray(ranges, dtype=np.float64)
    angles = np.asarray(angles, dtype=np.float64)
    if ranges.ndim != 1 or ranges.shape != angles.shape:
        raise ValueError(f"ranges and angles must be 1-D of the same length, got {ranges.shape} and {angles.shape}")
    with np.errstate(invalid="ignore"):
        ok = np.isfinite(ranges) & (ranges > 0) & (ranges <= max_range_m)
    r, a = ranges[ok], angles[ok]
    points = np.empty((r.size, 2))
    points[:, 0] = r * np.cos(a)
    points[:, 1] = r * np.sin(a)
    return points, r, a


def segment_scan(points_xy: np.ndarray, eps_m: float, *, beam_step_rad: float | None = None) -> np.ndarray:
    """Clusters of DBSCAN(eps, min_samples=1) (single linkage) of scan points.

    Args:
        points_xy: (N, 2) points in metres in the scanner's frame, normally in scan order
            (increasing angle around the scanner, wrapping at most once); any order gives
            the same partition, scan order is just faster.
        eps_m: link distance, metres: two points at most this far apart share a cluster.
        beam_step_rad: optional promise that the points are returns of distinct beams of a
            scanner whose beam angles are whole multiples of this step, given in scan order.
            Then no angle is computed: a link between points k beams apart needs
            k * beam_step_rad <= alpha. Wrong promises give wrong clusters.

    Returns:
        (N,) int64 labels 0..K-1, numbered in order of first appearance in ``points_xy``.
        The partition equals ``DBSCAN(eps=eps_m, min_samples=1)``'s (labels up to renaming).

    Raises:
        ValueError: for a bad shape, a non-finite coordinate or a non-positive eps.
    """
    p = np.asarray(points_xy, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 2:
        raise ValueError(f"points_xy must have shape (N, 2), got {p.shape}")
    if not (math.isfinite(eps_m) and eps_m > 0):
        raise ValueError(f"eps_m must be a finite number > 0 m, got {eps_m}")
    n = p.shape[0]
    if n <= 1:
        return np.zeros(n, np.int64)
    x, y = p[:, 0], p[:, 1]
    r2 = x * x + y * y
    r2_min = float(r2.min())
    if not math.isfinite(float(r2.max())) or not math.isfinite(r2_min):
        raise ValueError("points_xy must be finite (and below 1e154 m)")
    eps_m = float(eps_m)
    alpha = _max_link_angle(math.sqrt(r2_min), eps_m)
    order = None
    if beam_step_rad is not None:
        if not (math.isfinite(beam_step_rad) and beam_step_rad > 0):
            raise ValueError(f"beam_step_rad must be a finite number > 0 rad, got {beam_step_rad}")
        k_max = n - 1 if alpha >= math.pi else min(n - 1, int(alpha / beam_step_rad))
    else:
        theta = np.arctan2(y, x)
        descents = np.flatnonzero(theta[1:] < theta[:-1])
        if descents.size == 1 and theta[-1] <= theta[0]:
            # Circular scan order (one wrap through +-pi): unwrap so the angles increase.
            theta[int(descents[0]) + 1:] += 2.0 * math.pi
        elif descents.size:
            order = np.argsort(theta, kind="stable")
            x, y, theta = x[order], y[order], theta[order]
        if alpha >= math.pi:
            k_max = n - 1
        else:
            ext = np.concatenate([theta, theta + 2.0 * math.pi])
            reach = np.searchsorted(ext, theta + alpha, side="right") - np.arange(1, n + 1)
            k_max = int(min(n - 1, reach.max()))

    roots, dense = _components(p if order is None else p[order], k_max, eps_m * eps_m)
    if order is None:
        if dense:
            return roots
        # Roots are the smallest run id of each component and run ids grow in input order,
        # so ranking the roots numbers the clusters by first appearance.
        present = np.zeros(n, bool)
        present[roots] = True
        return (np.cumsum(present) - 1)[roots]
    unsorted = np.empty(n, np.int64)
    unsorted[order] = roots
    _, first, inverse = np.unique(unsorted, return_index=True, return_inverse=True)
    rank = np.empty(first.size, np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(first.size)
    return rank[inverse.ravel()]


def _max_link_angle(r_min: float, eps_m: float) -> float:
    """Largest angle between two linked points at ranges >= r_min (pi: unbounded), rad."""
    if 2.0 * r_min <= eps_m:
        return math.pi
    return min(math.pi, 2.0 * math.asin(eps_m / (2.0 * r_min)) * (1.0 + _ANGLE_SLACK) + _ANGLE_SLACK)


def _windows(values: np.ndarray, k_max: int, first: int = 1) -> np.ndarray:
    """(k_max - first + 1, n) read-only view with [k - first, i] = values[(i + k) mod n].

    ``values`` must be the contiguous (n + k_max,) array ``concat(v, v[:k_max])``.
    """
    n = values.size - k_max
    item = values.itemsize
    return np.ndarray((k_max - first + 1, n), values.dtype, values, first * item, (item, item))


def _components(p: np.ndarray, k_max: int, eps2: float) -> tuple[np.ndarray, bool]:
    """Components of the eps-graph of the (n, 2) points ``p``, comparing each point with its
    next ``k_max`` points (circularly).

    Returns:
        ``(roots, dense)``: (n,) the smallest run id in each point's component (runs are
        maximal chains linked at offset 1, numbered in order), and whether the roots are
        already 0..K-1 (no run was merged into another but through the wrap).
    """
    n = p.shape[0]
    if k_max == 0:
        return np.arange(n), True
    # links[k - 1, i]: point i and point (i + k) mod n are within eps (dx^2 + dy^2 <= eps^2).
    xy = np.empty((2, n + k_max))
    xy[:, :n] = p.T
    xy[:, n:] = xy[:, :k_max]
    d = np.ndarray((2, k_max, n), np.float64, xy, xy.itemsize, (xy.strides[0], xy.itemsize, xy.itemsize))
    d = d - xy[:, None, :n]
    d *= d
    links = d[0] + d[1] <= eps2
    # Runs of neighbours linked at offset 1; the last run wraps onto the first when linked.
    brk = ~links[0]
    run = np.cumsum(brk, dtype=np.intp)
    n_runs = int(run[-1]) + (0 if brk[-1] else 1)
    run -= brk  # run[i] = breaks before i
    if not brk[-1] and n_runs > 1:
        run[run == n_runs - 1] = 0
        n_runs -= 1
    if k_max == 1 or n_runs == 1:
        return run, True
    far = _windows(np.concatenate((run, run[:k_max])), k_max, first=2)
    ks, src = np.nonzero(links[1:] & (far != run))
    if src.size == 0:
        return run, True
    a, b = run[src], far[ks, src]
    if a.size <= _UNION_FIND_MAX_LINKS:
        return _union_find(n_runs, a.tolist(), b.tolist())[run], False
    graph = csr_matrix((np.ones(a.size, np.int8), (a, b)), shape=(n_runs, n_runs))
    _, comp = connected_components(graph, directed=True, connection="weak")
    # scipy numbers components in order of their smallest node: map back to that node.
    smallest = np.full(int(comp.max()) + 1, n_runs, np.int64)
    np.minimum.at(smallest, comp, np.arange(n_runs))
    return smallest[comp][run], False


def _union_find(n: int, a: list[int], b: list[int]) -> np.ndarray:
    """(n,) root of each node after linking the pairs ``a[i] - b[i]``; a root is the
    smallest node of its set."""
    parent = list(range(n))
    for u, v in zip(a, b):
        while parent[u] != u:
            parent[u] = parent[parent[u]]
            u = parent[u]
        while parent[v] != v:
            parent[v] = parent[parent[v]]
            v = parent[v]
        if u < v:
            parent[v] = u
        elif v < u:
            parent[u] = v
    out = np.asarray(parent, np.int64)
    while True:  # Pointer jumping until every node points at its root.
        nxt = out[out]
        if np.array_equal(nxt, out):
            return out
        out = nxt


def bench_segmentation(scans: np.ndarray | None = None, eps_m: float = 0.06, max_range_m: float = 4.0,
                       repeats: int = 20) -> dict[str, float]:
    """Mean time per call of :func:`segment_scan` and of scikit-learn's DBSCAN, microseconds.

    Args:
        scans: (S, N) ranges (beam i at 2 pi i / N); default: the recorded test scans in
            ``tests/data/lidar_scans.npz``.
        eps_m: link distance, metres.
        max_range_m: returns beyond this are dropped before clustering, metres.
        repeats: timed passes over all scans.

    Returns:
        ``{"ours_us": ..., "ours_beam_step_us": ..., "sklearn_us": ..., "mean_points": ...}``:
        microseconds per call of :func:`segment_scan` (plain, and told the beam step), of
        ``DBSCAN(eps, min_samples=1).fit_predict``, and the mean number of points per scan.
    """
    from sklearn.cluster import DBSCAN

    if scans is None:
        path = Path(__file__).resolve().parents[1] / "tests" / "data" / "lidar_scans.npz"
        scans = np.load(path)["ranges"]
    scans = np.asarray(scans, np.float64)
    angles = 2 * np.pi * np.arange(scans.shape[1]) / scans.shape[1]
    clouds = [scan_points(s, angles, max_range_m)[0] for s in scans]
    clouds = [c for c in clouds if len(c) > 0]
    for c in clouds:  # warm-up
        segment_scan(c, eps_m)
    t0 = time.perf_counter()
    for _ in range(repeats):
        for c in clouds:
            segment_scan(c, eps_m)
    ours = (time.perf_counter() - t0) / (repeats * len(clouds))
    step = 2 * np.pi / scans.shape[1]
    t0 = time.perf_counter()
    for _ in range(repeats):
        for c in clouds:
            segment_scan(c, eps_m, beam_step_rad=step)
    ours_beams = (time.perf_counter() - t0) / (repeats * len(clouds))
    db = DBSCAN(eps=eps_m, min_samples=1)
    sk_repeats = max(1, repeats // 5)
    t0 = time.perf_counter()
    for _ in range(sk_repeats):
        for c in clouds:
            db.fit_predict(c)
    theirs = (time.perf_counter() - t0) / (sk_repeats * len(clouds))
    return {"ours_us": ours * 1e6, "ours_beam_step_us": ours_beams * 1e6, "sklearn_us": theirs * 1e6,
            "mean_points": float(np.mean([len(c) for c in clouds]))}


if __name__ == "__main__":
    import sys

    data = np.load(sys.argv[1])["ranges"] if len(sys.argv) > 1 else None
    for max_range in (4.0, 12.0):
        res = bench_segmentation(data, max_range_m=max_range)
        print(f"max range {max_range:4.1f} m, {res['mean_points']:.0f} points/scan: "
              f"segment_scan {res['ours_us']:.1f} us ({res['ours_beam_step_us']:.1f} us with beam_step_rad), "
              f"sklearn DBSCAN {res['sklearn_us']:.1f} us per call")
