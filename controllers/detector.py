"""Stop-sign detection from the RGB image alone: a red octagon inside a light border.

Classical colour-and-shape detection (OpenCV): red pixels -> connected components ->
shape tests -> a confidence. The confidence is what a learned detector's score is to the
rest of the pipeline, and like one it falls as more of the sign is hidden:

- ``ring``: share of the pixels just outside the red region that look like the sign's
  white border or the light room behind it (an occluder breaks the ring);
- ``aspect``: a sign is never seen wider than tall (yaw only narrows it), and a very thin
  sliver is not a sign seen obliquely but what is left of an occluded one;
- ``solidity``: an octagon is convex; the yield signs' red triangular rings are not;
- ``symmetry``: an octagon has as many pixels above its middle row as below; a yield sign
  (a triangle pointing down, solid red when too far to resolve its white inside) has
  three times as many.

Yield signs (red rings, triangular) and the traffic lights' red lamps (small discs on a
black housing) are rejected by solidity, extent and the ring test.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from racf.controllers.components import sparse_components

__all__ = ["DetectorConfig", "Detection", "BlobDetector", "StopSignDetector", "check_rgb"]


@dataclass(frozen=True)
class DetectorConfig:
    """Thresholds of the colour-and-shape detector (OpenCV HSV: H 0-179, S and V 0-255).

    Attributes:
        red_hue_max: hues <= this or >= 180 - this count as red.
        red_min_saturation: minimum saturation of a red pixel.
        red_min_value: minimum brightness of a red pixel.
        min_area_px: smallest red component considered (a 0.10 m sign 2.5 m away at
            320x240 covers ~40 px even when seen 55 deg off its normal).
        min_solidity: area / convex-hull area; an octagon is ~1, a triangular ring ~0.5.
        min_extent: area / bounding-box area; an octagon is 0.83, a triangle 0.5.
        ring_px: width of the ring inspected around a component, pixels.
        light_max_saturation: ring pixels at most this saturated ...
        light_min_value: ... and at least this bright count as border / background.
        full_aspect: height / width at and above which the aspect term is 1.
        thin_aspect: width / height at and above which the sliver term is 1 (it falls
            linearly to 0 below; a sign 55 deg off its normal has ~0.57).
        max_asymmetry: |above - below| / area at which the symmetry term reaches 0 (it is
            1 up to a third of this; a downward triangle has ~0.3-0.5).
        min_confidence: detections below this confidence are not reported.
    """

    red_hue_max: int = 10
    red_min_saturation: int = 120
    red_min_value: int = 50
    min_area_px: int = 12
    min_solidity: float = 0.80
    min_extent: float = 0.60
    ring_px: int = 2
    light_max_saturation: int = 60
    light_min_value: int = 110
    full_aspect: float = 0.9
    thin_aspect: float = 0.30
    max_asymmetry: float = 0.30
    min_confidence: float = 0.20

    def __post_init__(self) -> None:
        for name, lo, hi in (("red_hue_max", 1, 30), ("red_min_saturation", 0, 255), ("red_min_value", 0, 255),
                             ("min_area_px", 1, 10_000), ("ring_px", 1, 10), ("light_max_saturation", 0, 255),
                             ("light_min_value", 0, 255)):
            value = getattr(self, name)
            if not (isinstance(value, int) and lo <= value <= hi):
                raise ValueError(f"{name} must be an int in [{lo}, {hi}], got {value!r}")
        for name in ("min_solidity", "min_extent", "full_aspect", "thin_aspect", "max_asymmetry", "min_confidence"):
            value = getattr(self, name)
            if not 0.0 <= value <= 1.0:
                raise ValueError(f"{name} must be in [0, 1], got {value!r}")


@dataclass(frozen=True)
class Detection:
    """One stop-sign detection.

    Attributes:
        mask: (H, W) bool, the sign's red pixels.
        box: (x0, y0, x1, y1) pixel bounds, x1 and y1 exclusive.
        confidence: in [0, 1].
        area_px: number of mask pixels.
        centroid: (u, v) centre of the mask, pixels.
    """

    mask: np.ndarray
    box: tuple[int, int, int, int]
    confidence: float
    area_px: int
    centroid: tuple[float, float]


def check_rgb(rgb: np.ndarray) -> np.ndarray:
    """``rgb`` as an array; ValueError unless it is an (H, W, 3) uint8 image."""
    rgb = np.asarray(rgb)
    if rgb.ndim != 3 or rgb.shape[2] != 3 or rgb.dtype != np.uint8:
        raise ValueError(f"rgb must be an (H, W, 3) uint8 image, got shape {rgb.shape} dtype {rgb.dtype}")
    return rgb


class BlobDetector:
    """Shared by the colour detectors: subclasses list ``candidates``; ``detect`` keeps the
    largest one at or above ``config.min_confidence``."""

    config: DetectorConfig  # or any config with min_confidence
    #: What a detection's mask outlines, for the size witness (``racf.controllers.size_distance``),
    #: which measures the mask's box against the map's size of that part: ``red_face``, the red
    #: octagon inside the white border (the colour detector's red pixels), or ``face``, the whole
    #: face, border included (what the learned segmenter was trained to mark).
    outline: str = "red_face"

    def candidates(self, rgb: np.ndarray) -> list[Detection]:
        raise NotImplementedError

    def passing(self, rgb: np.ndarray) -> list[Detection]:
        """The candidates with confidence >= ``min_confidence``."""
        return [d for d in self.candidates(rgb) if d.confidence >= self.config.min_confidence]

    @staticmethod
    def largest(detections: list[Detection]) -> Detection | None:
        """The detector's pick among ``detections``: the largest, or None."""
        return max(detections, key=lambda d: d.area_px) if detections else None

    def detect(self, rgb: np.ndarray) -> Detection | None:
        """The largest candidate with confidence >= ``min_confidence``, or None."""
        return self.largest(self.passing(rgb))


class StopSignDetector(BlobDetector):
    """The classical detector: the most prominent red octagon in a light ring, by colour and shape (OpenCV).

    Example:
        >>> import numpy as np
        >>> StopSignDetector().detect(np.full((240, 320, 3), 128, np.uint8)) is None
        True
    """

    def __init__(self, config: DetectorConfig | None = None) -> None:
        self.config = config or DetectorConfig()
        k = 2 * self.config.ring_px + 1
        self._ring_kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (k, k))

    def candidates(self, rgb: np.ndarray) -> list[Detection]:
        """Every red component that passes the shape tests, with its confidence.

        Args:
            rgb: (H, W, 3) uint8 image.
        """
        rgb = check_rgb(rgb)
        c = self.config
        hsv = cv2.cvtColor(rgb, cv2.COLOR_RGB2HSV)
        # Red wraps around hue 0: two inclusive HSV boxes (OpenCV's inRange is one pass each).
        red = cv2.bitwise_or(
            cv2.inRange(hsv, (0, c.red_min_saturation, c.red_min_value), (c.red_hue_max, 255, 255)),
            cv2.inRange(hsv, (180 - c.red_hue_max, c.red_min_saturation, c.red_min_value), (255, 255, 255)))
        n, labels, stats, centroids = sparse_components(red)
        out = []
        for i in range(1, n):
            x, y, w, hgt, area = (int(q) for q in stats[i])
            if area < c.min_area_px or area < c.min_extent * w * hgt:
                continue
            # Work in a padded crop: components are small, the frame is not.
            pad = c.ring_px + 1
            x0, y0 = max(0, x - pad), max(0, y - pad)
            x1, y1 = min(rgb.shape[1], x + w + pad), min(rgb.shape[0], y + hgt + pad)
            comp = (labels[y0:y1, x0:x1] == i).astype(np.uint8)
            contours, _ = cv2.findContours(comp, cv2.RETR_EXTERNAL, cv2.CHAIN_APPROX_SIMPLE)
            hull = np.zeros_like(comp)
            cv2.fillPoly(hull, [cv2.convexHull(np.concatenate(contours))], 1)
            solidity = area / max(int(hull.sum()), area)  # pixel counts, like with like
            if solidity < c.min_solidity:
                continue
            ring = cv2.dilate(comp, self._ring_kernel).astype(bool) & ~comp.astype(bool)
            crop = hsv[y0:y1, x0:x1]
            light = (crop[..., 1] <= c.light_max_saturation) & (crop[..., 2] >= c.light_min_value)
            ring_score = float(light[ring].mean()) if ring.any() else 0.0
            aspect = min(1.0, (hgt / w) / c.full_aspect) * min(1.0, (w / hgt) / c.thin_aspect)
            rows = np.nonzero(comp)[0] + y0
            middle = y + (hgt - 1) / 2
            asymmetry = abs(int((rows < middle).sum()) - int((rows > middle).sum())) / area
            symmetry = float(np.clip(1.5 * (1 - asymmetry / c.max_asymmetry), 0, 1))
            confidence = float(np.clip(ring_score * aspect * symmetry, 0.0, 1.0))
            mask = labels == i
            out.append(Detection(mask, (x, y, x + w, y + hgt), confidence, area,
                                 (float(centroids[i][0]), float(centroids[i][1]))))
        return out
