"""Naturalistic patch textures: smooth multi-scale noise over a palette of natural colours.

The result looks like a weathered sticker or foliage rather than a flat block: blotches at
two scales, fine grain, and colours drawn from moss, bark, sand, slate and paper tones
(never a saturated red, which would be a stop sign's own colour).
"""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["natural_texture"]

_PALETTE = np.array([
    (84, 107, 47),    # moss
    (128, 128, 72),   # olive
    (101, 67, 33),    # bark
    (194, 178, 128),  # sand
    (112, 128, 144),  # slate
    (225, 220, 205),  # paper
    (60, 62, 58),     # soot
    (70, 110, 140),   # faded blue
], np.float32)


def natural_texture(rng: np.random.Generator, size: int = 64) -> np.ndarray:
    """(size, size, 3) uint8 texture drawn from ``rng``."""
    if not 8 <= size <= 1024:
        raise ValueError(f"size must be in [8, 1024] px, got {size}")
    colours = _PALETTE[rng.choice(len(_PALETTE), size=3, replace=False)]

    def blotches(cells: int) -> np.ndarray:
        grid = rng.random((cells, cells)).astype(np.float32)
        return cv2.resize(grid, (size, size), interpolation=cv2.INTER_CUBIC)

    a = np.clip(0.65 * blotches(4) + 0.35 * blotches(9), 0, 1)
    b = np.clip(blotches(6), 0, 1)
    # Blend three colours by two noise fields, then add grain.
    tex = (colours[0] * (1 - a)[..., None] + colours[1] * a[..., None]) * (1 - 0.6 * b)[..., None] \
        + colours[2] * (0.6 * b)[..., None]
    tex += rng.normal(0.0, 9.0, size=tex.shape).astype(np.float32)
    return np.clip(tex, 0, 255).astype(np.uint8)
