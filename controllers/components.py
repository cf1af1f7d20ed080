"""Connected components of a sparse mask, labelled only where it has pixels.

The detectors label a colour mask that is almost empty: a sign is a few hundred of a frame's
76,800 pixels. OpenCV's ``connectedComponentsWithStats`` still walks the whole frame: about
0.45 ms on a 320 x 240 approach frame, against 0.06 ms for this function on the same mask
(one core). ``sparse_components`` labels that box and gives back what the whole frame's
call gives, to the bit, for every component (``tests/controllers/test_components.py`` checks
it against the full call).

Why it is the same: OpenCV's 8-connectivity labeller scans 2 x 2 blocks in raster order and
numbers components in the order it meets them, so the box starts on even rows and columns
(the full frame's block grid); every component lies inside the box, so its pixels, area and
extent are the same; the centroid is OpenCV's integer coordinate sum over the area, and the
box's sum is recovered exactly and shifted before that division.
"""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["sparse_components"]


def sparse_components(mask: np.ndarray) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
    """``cv2.connectedComponentsWithStats(mask, connectivity=8)`` for components 1..n-1.

    Args:
        mask: (H, W) uint8, non-zero = set.
    Returns:
        (n, labels (H, W) int32, stats (n, 5) int32, centroids (n, 2) float64). Rows 1.. are the
        components, as the full call gives them; row 0 (the background) is left out of the
        promise: it describes the labelled box, not the frame.
    """
    rows = np.flatnonzero(mask.any(axis=1))
    labels = np.zeros(mask.shape, np.int32)
    if rows.size == 0:
        return 1, labels, np.zeros((1, 5), np.int32), np.zeros((1, 2))
    cols = np.flatnonzero(mask.any(axis=0))
    y0, x0 = int(rows[0]) & ~1, int(cols[0]) & ~1  # on the labeller's 2 x 2 block grid
    y1, x1 = int(rows[-1]) + 1, int(cols[-1]) + 1
    n, box_labels, stats, centroids = cv2.connectedComponentsWithStats(mask[y0:y1, x0:x1], connectivity=8)
    labels[y0:y1, x0:x1] = box_labels
    area = stats[1:, cv2.CC_STAT_AREA].astype(np.int64)
    # The box's integer coordinate sums, exact (an area times a coordinate is far below 2**52),
    # shifted to the frame and divided as OpenCV divides them.
    for axis, offset in ((0, x0), (1, y0)):
        total = np.rint(centroids[1:, axis] * area).astype(np.int64) + offset * area
        centroids[1:, axis] = total / area
    stats[1:, cv2.CC_STAT_LEFT] += x0
    stats[1:, cv2.CC_STAT_TOP] += y0
    return n, labels, stats, centroids
