"""The stop-sign detectors by name: what a trial's ``detector`` field and ``--detector`` choose.

- ``classical``: colour and shape (:class:`~controllers.detector.StopSignDetector`, OpenCV).
- ``learned``: the learned segmenter (:class:`~controllers.learned_detector.LearnedSignDetector`,
  the project's own checkpoint), as the paper's YOLOv8-seg stands to its stack.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import lru_cache

from controllers.detector import BlobDetector, StopSignDetector

__all__ = ["DETECTORS", "make_detector"]


@lru_cache(maxsize=1)
def _learned() -> BlobDetector:
    """One per process: the detector keeps no state between frames, and loading its weights
    for every episode would cost more than the episode's frames."""
    from controllers.learned_detector import LearnedSignDetector  # torch: loaded only when chosen

    return LearnedSignDetector()


#: Every stop-sign detector by name, with what it is.
DETECTORS: dict[str, tuple[Callable[[], BlobDetector], str]] = {
    "classical": (StopSignDetector, "red octagon in a light ring: colour and shape tests (OpenCV)"),
    "learned": (_learned, "small convolutional segmenter trained on the simulator's frames (racf train-detector)"),
}


def make_detector(name: str) -> BlobDetector:
    """A detector of that name (the learned one is shared within a process: it is stateless);
    ValueError names the choices."""
    if name not in DETECTORS:
        raise ValueError(f"unknown detector {name!r}; choose from {tuple(DETECTORS)}")
    return DETECTORS[name][0]()
