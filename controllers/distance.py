"""Distance to a detected target from the depth image, and the camera model perception uses.

- :class:`DepthDistance`: median valid depth inside the detection's mask, the paper's
  d~(t), with a confidence c~(t) = detection confidence x share of valid depth pixels.

The LiDAR reference l(t) is :class:`racf.controllers.lidar_target.LidarTargetTracker`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from racf.controllers.detector import Detection

__all__ = ["CameraModel", "DepthDistance"]


@dataclass(frozen=True)
class CameraModel:
    """What perception needs of the camera: pinhole intrinsics.

    Attributes:
        width: image width, pixels.
        fx: horizontal focal length, pixels.
        cx: principal point column, pixels.
        fy: vertical focal length, pixels (None: square pixels, fx).
        cy: principal point row, pixels (None: not known; what needs it says so).
    """

    width: int
    fx: float
    cx: float
    fy: float | None = None
    cy: float | None = None

    def __post_init__(self) -> None:
        if not (self.width > 0 and self.fx > 0 and 0 <= self.cx <= self.width):
            raise ValueError(f"need width > 0, fx > 0 and 0 <= cx <= width, got {self}")
        if self.fy is not None and not self.fy > 0:
            raise ValueError(f"need fy > 0 (or None: square pixels), got {self.fy!r}")

    def height_per_metre(self, v0: float, v1: float) -> float:
        """The height an image extent from row ``v0`` to row ``v1`` (its edges) spans per metre of
        depth along the optical axis: (v1 - v0) / fy."""
        return abs(v1 - v0) / (self.fy if self.fy is not None else self.fx)

    @property
    def half_hfov_rad(self) -> float:
        """Half the horizontal field of view (the wider side of the principal point)."""
        return math.atan(max(self.cx, self.width - self.cx) / self.fx)

    def bearing(self, u: float) -> float:
        """Bearing of image column ``u`` from the optical axis, radians, left positive."""
        return math.atan2(self.cx - u, self.fx)


class DepthDistance:
    """d~ and c~ from a depth image and a detection."""

    def estimate(self, depth: np.ndarray, detection: Detection | None) -> tuple[float, float]:
        """(distance m, confidence in [0, 1]); (NaN, 0) with no detection or no valid depth.

        Args:
            depth: (H, W) float depth in metres, 0 (or non-finite) = no return.
            detection: the detector's output for the same frame.
        """
        if detection is None:
            return float("nan"), 0.0
        depth = np.asarray(depth)
        if depth.shape != detection.mask.shape:
            raise ValueError(f"depth shape {depth.shape} does not match the detection mask {detection.mask.shape}")
        values = depth[detection.mask]
        valid = values[np.isfinite(values) & (values > 0)]
        if valid.size == 0:
            return float("nan"), 0.0
        share = valid.size / values.size
        return float(np.median(valid)), float(detection.confidence * share)
