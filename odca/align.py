"""Cross-sensor alignment l -> D = alpha * l + beta, robust regression over a calibration window."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Alignment", "fit_alignment"]


@dataclass(frozen=True)
class Alignment:
    """Affine map from LiDAR range to the depth-distance domain, fixed within a run."""

    alpha: float = 1.0
    beta: float = 0.0

    def __call__(self, lidar: np.ndarray | float) -> np.ndarray:
        return self.alpha * np.asarray(lidar, float) + self.beta


def fit_alignment(depth: np.ndarray, lidar: np.ndarray, confidence: np.ndarray | None = None,
                  min_confidence: float = 0.5, min_samples: int = 20) -> Alignment:
    """Huber regression of depth on LiDAR over paired, finite, high-confidence samples.

    Args:
        depth, lidar: (N,) paired distances, metres (NaN/inf/<= 0 are dropped).
        confidence: (N,) depth confidence; samples below ``min_confidence`` are dropped.
    Raises:
        ValueError: fewer than ``min_samples`` usable pairs, or mismatched shapes.
    """
    d, l = np.asarray(depth, float), np.asarray(lidar, float)
    if d.shape != l.shape or d.ndim != 1:
        raise ValueError(f"depth and lidar must be 1-D arrays of the same length, got {d.shape} and {l.shape}")
    ok = np.isfinite(d) & np.isfinite(l) & (d > 0) & (l > 0)
    if confidence is not None:
        c = np.asarray(confidence, float)
        if c.shape != d.shape:
            raise ValueError(f"confidence must match depth's shape {d.shape}, got {c.shape}")
        ok &= np.nan_to_num(c) >= min_confidence
    if ok.sum() < min_samples:
        raise ValueError(f"need >= {min_samples} paired high-confidence samples to fit the alignment, got {int(ok.sum())}")
    from sklearn.linear_model import HuberRegressor  # here: scikit-learn takes a second to import

    model = HuberRegressor(epsilon=1.35, alpha=0.0).fit(l[ok, None], d[ok])
    return Alignment(float(model.coef_[0]), float(model.intercept_))
