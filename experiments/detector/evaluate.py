"""How well a detector finds stop signs in rendered views (recall and false-positive frames).

- A view is *positive* when a stop sign's face is resolvable in it: its visible pixels number
  at least 12 and span at least 3 px each way (a sign seen edge-on is a 1-2 px sliver no
  detector resolves). It is a hit when the detection overlaps the faces' mask (grown by 2 px).
- A *false-positive frame* has a detection that overlaps no stop sign's face (grown by 2 px).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import cv2
import numpy as np

from racf.experiments.sweeps.detection_bands import DISTANCE_BANDS_M, band_label
from racf.stats import wilson_interval

__all__ = ["DetectionCounts", "SplitCounts", "evaluate_split", "resolvable", "score_frame", "MIN_SHARE",
           "DISTANCE_BANDS_M", "VIEW_BANDS_M", "VIEW_KINDS", "band_label"]

MIN_GT_PX, MIN_GT_SPAN_PX = 12, 3
#: What a rendered view is, as a split's ``kind`` column numbers it (``racf.experiments.detector.views``).
VIEW_KINDS = ("sign", "approach", "map")
#: The bands of a rendered split's recall: the loop's, and the far views' (first sight).
VIEW_BANDS_M = (*DISTANCE_BANDS_M, (4.0, 6.0))

_GROW = np.ones((5, 5), np.uint8)


def resolvable(mask: np.ndarray) -> bool:
    """Whether a face mask is large enough to count as a positive."""
    if mask.sum() < MIN_GT_PX:
        return False
    rows, cols = np.nonzero(mask)
    return np.ptp(rows) + 1 >= MIN_GT_SPAN_PX and np.ptp(cols) + 1 >= MIN_GT_SPAN_PX


def grow(mask: np.ndarray) -> np.ndarray:
    return cv2.dilate(mask.view(np.uint8), _GROW).astype(bool)


@dataclass
class DetectionCounts:
    """Running counts of positives, hits, frames and false-positive frames."""

    n_frames: int = 0
    n_positive: int = 0
    n_hit: int = 0
    n_fp: int = 0

    def add(self, hit: bool | None, false_positive: bool) -> None:
        """One frame: ``hit`` None when the frame is not a positive."""
        self.n_frames += 1
        self.n_fp += bool(false_positive)
        if hit is not None:
            self.n_positive += 1
            self.n_hit += bool(hit)

    @property
    def recall(self) -> float | None:
        return self.n_hit / self.n_positive if self.n_positive else None

    @property
    def fp_rate(self) -> float | None:
        return self.n_fp / self.n_frames if self.n_frames else None

    def to_dict(self) -> dict:
        return {**asdict(self), "recall": self.recall, "recall_ci": wilson_interval(self.n_hit, self.n_positive),
                "fp_rate": self.fp_rate, "fp_rate_ci": wilson_interval(self.n_fp, self.n_frames)}


#: The least share of its face a positive view must show.
MIN_SHARE = 0.5


def score_frame(detection, target: np.ndarray, faces: np.ndarray, share: float = 1.0) -> tuple[bool | None, bool]:
    """(hit or None when ``target`` is not a positive, false positive) of one frame's detection.

    Args:
        detection: the detector's output (with a ``mask``) or None.
        target: (H, W) bool, the face(s) that should be found.
        faces: (H, W) bool, every stop sign's face in the frame (a detection on any is no false positive).
        share: the share of the target's face that ``target`` shows (``View.target_share``).
    """
    hit = None
    if resolvable(target) and share >= MIN_SHARE:
        hit = detection is not None and bool((detection.mask & grow(target)).any())
    fp = detection is not None and not bool((detection.mask & grow(faces)).any())
    return hit, fp


@dataclass
class SplitCounts:
    """A detector over a split of rendered views: overall, per kind of view and per distance band."""

    overall: DetectionCounts
    by_kind: dict[str, DetectionCounts]
    by_band: dict[str, DetectionCounts]

    def to_dict(self) -> dict:
        """The overall counts' dict, with ``by_kind`` and ``by_band`` beside them."""
        return {**self.overall.to_dict(), "by_kind": {k: c.to_dict() for k, c in self.by_kind.items()},
                "by_band": {b: c.to_dict() for b, c in self.by_band.items()}}


def evaluate_split(detector, data: dict[str, np.ndarray], progress: bool = False) -> SplitCounts:
    """Recall and false-positive frames of ``detector`` over a split's views
    (``racf.experiments.detector.dataset.load_split``)."""
    from tqdm import tqdm

    overall = DetectionCounts()
    by_kind = {k: DetectionCounts() for k in VIEW_KINDS}
    by_band = {band_label(lo, hi): DetectionCounts() for lo, hi in VIEW_BANDS_M}
    for i in tqdm(range(len(data["rgb"])), desc="evaluate", unit="view", disable=not progress):
        outcome = score_frame(detector.detect(data["rgb"][i]), data["mask"][i], data["mask"][i],
                              data["faces_share"][i])
        overall.add(*outcome)
        if "kind" in data:
            by_kind[VIEW_KINDS[int(data["kind"][i])]].add(*outcome)
        d = float(data["d_true"][i])
        for lo, hi in VIEW_BANDS_M:
            if lo <= d < hi:
                by_band[band_label(lo, hi)].add(*outcome)
    return SplitCounts(overall, by_kind, by_band)
