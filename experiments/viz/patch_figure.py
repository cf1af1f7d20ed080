"""The README's picture of the patched sign: near views, clean and with the sticker, each with
the learned detector's mask drawn over it."""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["patched_sign_figure"]


def patched_sign_figure(examples: list[tuple[np.ndarray, np.ndarray, np.ndarray]], path: Path) -> Path:
    """Writes a grid: a row per example, (clean, patched) frames cropped around the sign, the
    learned detector's mask in green."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from racf.controllers.detectors import make_detector
    from racf.experiments.viz.figures import save_figure

    if not examples:
        raise ValueError("no example views to draw (none came near enough)")
    det = make_detector("learned")
    fig, axes = plt.subplots(len(examples), 2, figsize=(6, 3 * len(examples)), squeeze=False)
    for row, (clean, patched, target) in zip(axes, examples):
        rows, cols = np.nonzero(target)
        pad = 25
        y0, y1 = max(rows.min() - pad, 0), min(rows.max() + pad, clean.shape[0])
        x0, x1 = max(cols.min() - pad, 0), min(cols.max() + pad, clean.shape[1])
        for ax, rgb, title in zip(row, (clean, patched), ("clean", "sticker on the sign")):
            d = det.detect(rgb)
            shown = rgb.copy()
            if d is not None:
                shown[d.mask] = (0.5 * shown[d.mask] + np.array([0, 120, 0])).astype(np.uint8)
            ax.imshow(shown[y0:y1, x0:x1])
            ax.set_title(f"{title}: {'found' if d is not None else 'missed'}", fontsize=9)
            ax.axis("off")
    fig.suptitle("Learned detector (green: its mask), sticker printed in the scene", fontsize=10)
    return save_figure(fig, path, dpi=110)
