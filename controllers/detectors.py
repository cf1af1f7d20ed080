"""The stop-sign detectors by name: what a trial's ``detector`` field and ``--detector`` choose.

``DETECTORS`` is :data:`racf.plugins.DETECTORS`, filled from the ``racf.detectors`` entry points:

- ``classical``: colour and shape (:class:`~racf.controllers.detector.StopSignDetector`, OpenCV).
- ``learned``: the learned segmenter (:class:`~racf.controllers.learned_detector.LearnedSignDetector`,
  the project's own checkpoint), as the paper's YOLOv8-seg stands to its stack.

A user's detector is a class (or factory) whose objects answer ``detect(rgb) -> Detection | None``.
"""

from __future__ import annotations

from functools import lru_cache

from racf.controllers.detector import BlobDetector
from racf.plugins import DETECTORS

__all__ = ["DETECTORS", "make_detector", "shared_learned_detector"]


@lru_cache(maxsize=1)
def shared_learned_detector() -> BlobDetector:
    """The learned segmenter: a small convolutional net trained on the simulator's frames.

    One per process: it keeps no state between frames, and loading its weights for every
    episode would cost more than the episode's frames."""
    from racf.controllers.learned_detector import LearnedSignDetector  # torch: loaded only when chosen

    return LearnedSignDetector()


def make_detector(name: str) -> BlobDetector:
    """A detector of that name; ValueError (a PluginError) names the choices."""
    return DETECTORS.plugin(name).obj()
