"""Scoring rules of the offline benchmark (``docs/protocol.md``), pure numpy + scikit-learn.

Every function takes aligned per-step arrays and returns plain floats, or ``None`` where the
metric is undefined (no samples, one class only), so results serialise as strict JSON.
"""

from __future__ import annotations

import numpy as np

__all__ = ["rmse", "mae", "auroc", "auprc", "bounded_degradation", "resilience_gain", "hold_last"]


def _errors(estimate, reference, mask=None) -> np.ndarray:
    est, ref = np.asarray(estimate, float), np.asarray(reference, float)
    if est.shape != ref.shape:
        raise ValueError(f"estimate and reference must have the same shape, got {est.shape} and {ref.shape}")
    ok = np.isfinite(est) & np.isfinite(ref)
    if mask is not None:
        ok &= np.asarray(mask, bool)
    return (est - ref)[ok]


def rmse(estimate, reference, mask=None) -> float | None:
    """Root-mean-square error over the steps where both are finite (and ``mask`` holds)."""
    err = _errors(estimate, reference, mask)
    return float(np.sqrt(np.mean(err**2))) if err.size else None


def mae(estimate, reference, mask=None) -> float | None:
    """Mean absolute error over the steps where both are finite (and ``mask`` holds)."""
    err = _errors(estimate, reference, mask)
    return float(np.mean(np.abs(err))) if err.size else None


def _scored(score, label) -> tuple[np.ndarray, np.ndarray] | None:
    s, y = np.asarray(score, float), np.asarray(label)
    if s.shape != y.shape:
        raise ValueError(f"score and label must have the same shape, got {s.shape} and {y.shape}")
    # A NaN score carries no evidence either way (e.g. the residual when the LiDAR is
    # silent): the step is left out rather than guessed.
    ok = np.isfinite(s)
    s, y = s[ok], y[ok].astype(int)
    if not set(np.unique(y)) <= {0, 1}:
        raise ValueError(f"labels must be 0 or 1, got {sorted(set(np.unique(y)))}")
    return (s, y) if len(np.unique(y)) == 2 else None


def auroc(score, label) -> float | None:
    """Area under the ROC curve of ``score`` as a detector of ``label == 1``; NaN scores left out."""
    from sklearn.metrics import roc_auc_score

    scored = _scored(score, label)
    return float(roc_auc_score(scored[1], scored[0])) if scored else None


def auprc(score, label) -> float | None:
    """Average precision (area under the precision-recall curve); NaN scores left out."""
    from sklearn.metrics import average_precision_score

    scored = _scored(score, label)
    return float(average_precision_score(scored[1], scored[0])) if scored else None


def bounded_degradation(rmse_weak: float | None, rmse_strong: float | None) -> float | None:
    """BD = (RMSE_strong - RMSE_weak) / RMSE_weak (lower is better)."""
    if rmse_weak is None or rmse_strong is None or not rmse_weak > 0:
        return None
    return float((rmse_strong - rmse_weak) / rmse_weak)


def resilience_gain(rmse_method: dict[str, float | None], rmse_chronos: dict[str, float | None]) -> float | None:
    """RGR = mean over presets of 1 - RMSE_method(s) / RMSE_Chronos(s) (higher is better)."""
    gains = [1.0 - rmse_method[s] / rmse_chronos[s] for s in rmse_chronos
             if rmse_method.get(s) is not None and rmse_chronos[s] is not None and rmse_chronos[s] > 0]
    return float(np.mean(gains)) if gains else None


def hold_last(values, first=None) -> np.ndarray:
    """Each NaN replaced by the last finite value before it (within a series; ``first`` marks series starts)."""
    import pandas as pd

    v = np.asarray(values, float)
    v = np.where(np.isfinite(v), v, np.nan)
    starts = np.zeros(len(v), bool) if first is None else np.asarray(first, bool)
    return pd.Series(v).groupby(np.cumsum(starts)).ffill().to_numpy()
