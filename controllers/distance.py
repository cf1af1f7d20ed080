"""Distance to a detected stop sign from the depth image and from the 2D LiDAR.

- :class:`DepthDistance`: median valid depth inside the detection's mask, the paper's
  d~(t), with a confidence c~(t) = detection confidence x share of valid depth pixels.
- :class:`LidarReference`: the paper's l(t), the range of the nearest DBSCAN cluster
  (scikit-learn) of LiDAR returns inside the camera's horizontal field of view and near
  the detection's bearing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from sklearn.cluster import DBSCAN

from controllers.detector import Detection

__all__ = ["CameraModel", "DepthDistance", "LidarReferenceConfig", "LidarReference"]


@dataclass(frozen=True)
class CameraModel:
    """What perception needs of the camera: horizontal pinhole intrinsics.

    Attributes:
        width: image width, pixels.
        fx: horizontal focal length, pixels.
        cx: principal point column, pixels.
    """

    width: int
    fx: float
    cx: float

    def __post_init__(self) -> None:
        if not (self.width > 0 and self.fx > 0 and 0 <= self.cx <= self.width):
            raise ValueError(f"need width > 0, fx > 0 and 0 <= cx <= width, got {self}")

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


@dataclass(frozen=True)
class LidarReferenceConfig:
    """Geometry and clustering of the LiDAR reference.

    Attributes:
        camera_offset_m: (x, y) of the camera in the LiDAR's frame (x forward, y left), m.
            The QCar 2's D435 sits 0.107 m ahead of and 0.032 m left of the RPLIDAR.
        eps_m: DBSCAN neighbourhood radius.
        min_samples: DBSCAN core-point size; 1 keeps a sign 2 m away that only two or
            three beams hit.
        bearing_margin_rad: how far outside the detection's box a cluster may lie.
        max_range_m: returns beyond this are ignored.
    """

    camera_offset_m: tuple[float, float] = (0.107, 0.032)
    eps_m: float = 0.06
    min_samples: int = 1
    bearing_margin_rad: float = math.radians(4.0)
    max_range_m: float = 6.0

    def __post_init__(self) -> None:
        if not 0.005 <= self.eps_m <= 1.0:
            raise ValueError(f"eps_m must be in [0.005, 1] m, got {self.eps_m}")
        if not (isinstance(self.min_samples, int) and 1 <= self.min_samples <= 50):
            raise ValueError(f"min_samples must be an int in [1, 50], got {self.min_samples!r}")
        if not 0.0 <= self.bearing_margin_rad <= 0.5:
            raise ValueError(f"bearing_margin_rad must be in [0, 0.5] rad, got {self.bearing_margin_rad}")
        if not 0.2 <= self.max_range_m <= 50:
            raise ValueError(f"max_range_m must be in [0.2, 50] m, got {self.max_range_m}")


class LidarReference:
    """l(t): the nearest LiDAR cluster in the camera's view (near the detection, if any).

    Args:
        camera: the camera whose field of view bounds the search.
        config: geometry and clustering.
    """

    def __init__(self, camera: CameraModel, config: LidarReferenceConfig | None = None) -> None:
        self.camera = camera
        self.config = config or LidarReferenceConfig()
        self._angles: np.ndarray | None = None

    def estimate(self, ranges: np.ndarray, detection: Detection | None = None) -> float:
        """Range (m, from the LiDAR) of the selected cluster, NaN when there is none.

        Args:
            ranges: (N,) beam ranges, beam i at 2 pi i / N counter-clockwise from forward;
                inf, NaN or <= 0 = no return.
            detection: when given, only clusters within its box's bearing span (plus the
                margin) count.
        """
        ranges = np.asarray(ranges, float)
        if ranges.ndim != 1 or ranges.size < 8:
            raise ValueError(f"ranges must be a 1-D scan of >= 8 beams, got shape {ranges.shape}")
        if self._angles is None or self._angles.size != ranges.size:
            self._angles = 2 * np.pi * np.arange(ranges.size) / ranges.size
        c = self.config
        ok = np.isfinite(ranges) & (ranges > 0) & (ranges <= c.max_range_m)
        r, a = ranges[ok], self._angles[ok]
        # Points in the camera's frame (x forward, y left).
        px = r * np.cos(a) - c.camera_offset_m[0]
        py = r * np.sin(a) - c.camera_offset_m[1]
        bearing = np.arctan2(py, px)
        keep = (px > 0) & (np.abs(bearing) <= self.camera.half_hfov_rad)
        if detection is not None:
            x0, _, x1, _ = detection.box
            left, right = self.camera.bearing(x0 - 0.5), self.camera.bearing(x1 - 0.5)
            keep &= (bearing <= left + c.bearing_margin_rad) & (bearing >= right - c.bearing_margin_rad)
        if not keep.any():
            return float("nan")
        points, r = np.column_stack([px[keep], py[keep]]), r[keep]
        labels = DBSCAN(eps=c.eps_m, min_samples=c.min_samples).fit_predict(points)
        best = float("nan")
        for label in np.unique(labels[labels >= 0]):
            best = float(np.nanmin([best, np.median(r[labels == label])]))
        return best
