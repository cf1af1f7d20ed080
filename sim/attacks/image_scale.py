"""Scaling one object's pixels in a frame about its centre: a camera-injection attacker making a
sign look farther (smaller) or nearer (larger) than it is."""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["scale_region"]


def scale_region(rgb: np.ndarray, mask: np.ndarray, factor: float,
                 centre: tuple[float, float] | None = None) -> np.ndarray:
    """A copy of ``rgb`` with the pixels under ``mask`` scaled by ``factor`` about ``centre`` (u, v),
    by default their centroid.

    The object's old pixels are filled from around them (``cv2.inpaint``: what the background
    behind would plausibly show), then the scaled object is drawn over. ``factor`` < 1 makes it
    smaller, as if farther away; 1 (or an empty mask) changes nothing. About the principal point,
    the scaled object is the same object moved along the camera's rays. ``rgb`` may also be a
    float32 plane (a depth image).
    """
    if not mask.any() or factor == 1.0:
        return rgb.copy()
    rows, cols = np.nonzero(mask)
    cu, cv = (float(cols.mean()), float(rows.mean())) if centre is None else centre
    warp = np.array([[factor, 0.0, (1.0 - factor) * cu], [0.0, factor, (1.0 - factor) * cv]])
    size = (rgb.shape[1], rgb.shape[0])
    grown = cv2.dilate(mask.astype(np.uint8), np.ones((3, 3), np.uint8))  # the edge's blended pixels too
    out = cv2.inpaint(rgb, grown, 3, cv2.INPAINT_TELEA)
    scaled = cv2.warpAffine(rgb, warp, size, flags=cv2.INTER_LINEAR)
    scaled_mask = cv2.warpAffine(mask.astype(np.uint8), warp, size, flags=cv2.INTER_NEAREST).astype(bool)
    out[scaled_mask] = scaled[scaled_mask]
    return out
