"""The monocular size witness: a distance from how big the sign looks, d_size = f * H / h.

The stop sign's face has a known size (the map says so: ``H`` across flats, the same
vertically and horizontally for an octagon), so the height ``h`` of its box in pixels gives
its depth along the optical axis, whatever the depth camera and the LiDAR say. What it is worth:

- the box's edges are whole pixels, so its height is known to about half a pixel: the
  relative error grows as the box shrinks (``edge_px / h``), on top of a floor for what the
  pinhole model leaves out (``floor``, a share of the distance);
- yaw narrows a sign but never makes it wider than tall, so a box clearly wider than tall
  (by ``wider_than_tall`` and ``width_slack_px``: an octagon's slanted edges render a pixel or
  two wider) has lost rows to an occluder: its width speaks instead;
- a box on the image's edge (within ``edge_margin_px``) may be cut: no witness;
- the detector's confidence falls as more of the face is hidden (a ring broken, a shape
  off): the std is divided by it, and below ``min_confidence`` there is no witness.

An occluder or a sticker can only hide rows of the face, never add any, so the box can
only shrink: d_size errs long, not short. ODCA uses it that way (:mod:`racf.odca.gate`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from racf.controllers.detector import Detection
from racf.controllers.distance import CameraModel

__all__ = ["SizeDistance"]


@dataclass(frozen=True)
class SizeDistance:
    """d_size and its std from a detection's box.

    Attributes:
        camera: the camera's intrinsics (fx for widths, fy for heights).
        face_m: the detected face's size across flats, m (a map fact: for the stop signs, the
            red octagon inside the white border).
        edge_px: the std of the box's height from its edges' quantisation, pixels.
        floor: the std's floor, a share of the distance.
        wider_than_tall: a box wider than ``this x`` its height (plus ``width_slack_px``) has lost
            rows: its width is used.
        width_slack_px: pixels a whole octagon's box may be wider than tall.
        edge_margin_px: a box this close to the image's edge may be cut: no witness.
        min_confidence: a detection below this confidence is too broken to measure.
    """

    camera: CameraModel
    face_m: float
    edge_px: float = 0.5
    floor: float = 0.02
    wider_than_tall: float = 1.1
    width_slack_px: float = 2.0
    edge_margin_px: int = 2
    min_confidence: float = 0.5

    def __post_init__(self) -> None:
        if not (math.isfinite(self.face_m) and 0.0 < self.face_m <= 5.0):
            raise ValueError(f"face_m must be a size in (0, 5] m, got {self.face_m!r}")
        for name, lo, hi in (("edge_px", 0.0, 10.0), ("floor", 0.0, 1.0), ("wider_than_tall", 1.0, 5.0),
                             ("width_slack_px", 0.0, 50.0), ("min_confidence", 0.0, 1.0)):
            value = getattr(self, name)
            if not (math.isfinite(value) and lo <= value <= hi):
                raise ValueError(f"{name} must be in [{lo}, {hi}], got {value!r}")

    def estimate(self, detection: Detection | None) -> tuple[float, float]:
        """(d_size m, its std m); (NaN, NaN) without a detection, with one too broken to measure
        or one on the image's edge."""
        if detection is None or detection.confidence < self.min_confidence:
            return math.nan, math.nan
        rows, cols = detection.mask.shape
        x0, y0, x1, y1 = detection.box
        m = self.edge_margin_px
        if x0 < m or y0 < m or x1 > cols - m or y1 > rows - m:
            return math.nan, math.nan
        fy = self.camera.fy if self.camera.fy is not None else self.camera.fx
        height = float(y1 - y0)
        width_as_rows = float(x1 - x0) * fy / self.camera.fx  # the width in the height's pixels
        extent = width_as_rows if width_as_rows > self.wider_than_tall * height + self.width_slack_px else height
        if extent < 1.0:
            return math.nan, math.nan
        d = fy * self.face_m / extent
        relative = math.hypot(self.edge_px / extent, self.floor) / detection.confidence
        return d, d * relative
