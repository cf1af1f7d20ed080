"""Obstacle detection from the RGB image: the map's blue crates, by colour and shape.

The crates are a stand-in for any obstacle on the lane; what matters downstream is a mask
whose depth gives the distance, as for a stop sign. Same interface as the stop-sign
detector (``detect`` / ``candidates`` returning :class:`~racf.controllers.detector.Detection`).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from racf.controllers.components import sparse_components
from racf.controllers.detector import BlobDetector, Detection, check_rgb

__all__ = ["ObstacleDetectorConfig", "ObstacleDetector"]


@dataclass(frozen=True)
class ObstacleDetectorConfig:
    """Colour and shape thresholds (OpenCV HSV: H 0-179, S and V 0-255).

    Attributes:
        hue_range: (low, high) hue of the crate's blue.
        min_saturation, min_value: minimum saturation and brightness.
        min_area_px: smallest component considered.
        full_extent: area / box area at and above which the confidence is 1 (a box face is ~1).
        min_confidence: detections below this are not reported.
    """

    hue_range: tuple[int, int] = (98, 128)
    min_saturation: int = 120
    min_value: int = 50
    min_area_px: int = 20
    full_extent: float = 0.85
    min_confidence: float = 0.5

    def __post_init__(self) -> None:
        lo, hi = self.hue_range
        if not 0 <= lo <= hi <= 179:
            raise ValueError(f"hue_range must satisfy 0 <= low <= high <= 179, got {self.hue_range}")
        if not (0 <= self.min_saturation <= 255 and 0 <= self.min_value <= 255 and self.min_area_px >= 1):
            raise ValueError("min_saturation and min_value must be in [0, 255] and min_area_px >= 1")
        for name in ("full_extent", "min_confidence"):
            if not 0.0 < getattr(self, name) <= 1.0:
                raise ValueError(f"{name} must be in (0, 1], got {getattr(self, name)}")


class ObstacleDetector(BlobDetector):
    """Finds the largest blue crate in an RGB frame."""

    def __init__(self, config: ObstacleDetectorConfig | None = None) -> None:
        self.config = config or ObstacleDetectorConfig()

    def candidates(self, rgb: np.ndarray) -> list[Detection]:
        rgb = check_rgb(rgb)
        c = self.config
        hsv = cv2.cvtColor(rgb, cv2.COLOR_RGB2HSV)
        blue = ((hsv[..., 0] >= c.hue_range[0]) & (hsv[..., 0] <= c.hue_range[1])
                & (hsv[..., 1] >= c.min_saturation) & (hsv[..., 2] >= c.min_value))
        n, labels, stats, centroids = sparse_components(blue.view(np.uint8))
        out = []
        for i in range(1, n):
            x, y, w, h, area = (int(q) for q in stats[i])
            if area < c.min_area_px:
                continue
            confidence = float(min(1.0, area / (w * h) / c.full_extent))
            out.append(Detection(labels == i, (x, y, x + w, y + h), confidence, area,
                                 (float(centroids[i][0]), float(centroids[i][1]))))
        return out
