"""Scores of one method on one corrupted split: recovery, horizon, diagnostics, intervals."""

from __future__ import annotations

import numpy as np

from racf.experiments.offline.methods import SplitArrays
from racf.experiments.offline.metrics import auprc, auroc, mae, rmse
from racf.odca.train import MOVING_MPS  # the protocol's standstill bound, m/s

__all__ = ["MOVING_MPS", "recovery_scores", "horizon_scores", "diagnostic_scores", "bootstrap_rmse",
           "series_sse", "bootstrap_rmse_draws", "error_sources", "mean_over_draws"]



def recovery_scores(estimate: np.ndarray, a: SplitArrays) -> dict:
    """RMSE / MAE against d_clean and d_true, over all scored and over moving scored samples."""
    scored = a.scored
    moving = scored & (np.abs(a.v) > MOVING_MPS)
    out = {"n": int(scored.sum()), "n_moving": int(moving.sum())}
    for suffix, mask in (("", scored), ("_moving", moving)):
        out[f"rmse{suffix}"] = rmse(estimate, a.d_clean, mask)
        out[f"mae{suffix}"] = mae(estimate, a.d_clean, mask)
        out[f"rmse_true{suffix}"] = rmse(estimate, a.d_true, mask)
        out[f"mae_true{suffix}"] = mae(estimate, a.d_true, mask)
    out["n_true"] = int((scored & np.isfinite(a.d_true)).sum())
    return out


def horizon_scores(origins: np.ndarray, paths: np.ndarray, a: SplitArrays) -> dict:
    """The H-step score: errors of the forecasts from each origin over its next H steps (same series, scored)."""
    horizon = paths.shape[1]
    idx = origins[:, None] + np.arange(horizon)[None, :]
    inside = idx < len(a)
    idx_c = np.minimum(idx, len(a) - 1)
    same = inside & (a.series_id[idx_c] == a.series_id[origins][:, None]) & a.scored[idx_c]
    err = (paths - a.d_clean[idx_c])[same & np.isfinite(paths)]
    return {f"rmse_h{horizon}": float(np.sqrt(np.mean(err**2))) if err.size else None,
            f"mae_h{horizon}": float(np.mean(np.abs(err))) if err.size else None,
            f"n_h{horizon}": int(err.size)}


def diagnostic_scores(estimate: np.ndarray, a: SplitArrays) -> dict:
    """AUROC / AUPRC of XS = |estimate - aligned LiDAR| and Chg = |estimate - d~| as detectors of attacked steps.

    For raw depth XS is the paper's r_XS = |d~ - l|; for a repairing method it is what is
    left of the disagreement after repair. d~ is the held raw depth (a blackout has none).
    Steps without a LiDAR value have no XS and are left out of its score.
    """
    scored = a.scored
    xs = np.abs(estimate - a.l_al)[scored]
    chg = np.abs(estimate - a.raw)[scored]
    label = a.label[scored]
    return {"auroc_xs": auroc(xs, label), "auprc_xs": auprc(xs, label),
            "auroc_chg": auroc(chg, label), "auprc_chg": auprc(chg, label),
            "attacked_share": float(label.mean()) if label.size else None}


def bootstrap_rmse(estimate: np.ndarray, a: SplitArrays, n_boot: int, seed: int, level: float = 0.95
                   ) -> list[float] | None:
    """Percentile interval of the RMSE against d_clean, resampling whole test series (they are the units)."""
    scored = a.scored
    if not scored.any() or n_boot < 1:
        return None
    sq = (estimate - a.d_clean) ** 2
    ids, inverse = np.unique(a.series_id[scored], return_inverse=True)
    sse = np.bincount(inverse, weights=sq[scored], minlength=len(ids))
    count = np.bincount(inverse, minlength=len(ids)).astype(float)
    rng = np.random.default_rng(seed)
    draws = rng.integers(0, len(ids), size=(n_boot, len(ids)))
    values = np.sqrt(sse[draws].sum(1) / np.maximum(count[draws].sum(1), 1.0))
    tail = (1 - level) / 2 * 100
    return [float(np.percentile(values, tail)), float(np.percentile(values, 100 - tail))]


def series_sse(estimate: np.ndarray, a: SplitArrays, series: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """Sum of squared errors against d_clean and scored-step count per test series (in ``series`` order)."""
    scored = a.scored
    index = {sid: k for k, sid in enumerate(series)}
    rows = np.array([index[sid] for sid in a.series_id[scored]], int)
    sq = ((estimate - a.d_clean) ** 2)[scored]
    return (np.bincount(rows, weights=sq, minlength=len(series)),
            np.bincount(rows, minlength=len(series)).astype(float))


def bootstrap_rmse_draws(sse: np.ndarray, count: np.ndarray, n_boot: int, seed: int, level: float = 0.95
                         ) -> list[float] | None:
    """Percentile interval of the mean-over-draws RMSE, resampling test drives and corruption draws together.

    ``sse`` and ``count`` are (series, draws). Each resample picks the series and the draws
    with replacement; its value is the mean over the picked draws of the RMSE over the picked
    series, as the reported RMSE is the mean over draws.
    """
    n_series, n_draws = sse.shape
    if n_boot < 1 or not count.sum():
        return None
    rng = np.random.default_rng(seed)
    rows = rng.integers(0, n_series, size=(n_boot, n_series))
    cols = rng.integers(0, n_draws, size=(n_boot, n_draws))
    # (boot, draws): the picked series' totals in each picked draw.
    sse_sum = np.stack([sse[rows[b]][:, cols[b]].sum(0) for b in range(n_boot)])
    cnt_sum = np.stack([count[rows[b]][:, cols[b]].sum(0) for b in range(n_boot)])
    values = np.sqrt(sse_sum / np.maximum(cnt_sum, 1.0)).mean(1)
    tail = (1 - level) / 2 * 100
    return [float(np.percentile(values, tail)), float(np.percentile(values, 100 - tail))]


def mean_over_draws(rows: list[dict]) -> dict:
    """One score dict from one per draw: numbers averaged (None where a draw has none), counts summed."""
    out = {}
    for key in rows[0]:
        values = [r[key] for r in rows]
        if key.startswith("n"):
            out[key] = int(sum(values))
        elif all(isinstance(v, (int, float)) and v is not None for v in values):
            out[key] = float(np.mean(values))
        else:
            numbers = [v for v in values if isinstance(v, (int, float))]
            out[key] = float(np.mean(numbers)) if numbers else None
    return out


def error_sources(estimate: np.ndarray, a: SplitArrays) -> dict:
    """Where the error comes from: RMSE and sum of squared errors per (segment kind, LiDAR present)."""
    from racf.experiments.data.corruption import SEGMENT_KINDS

    scored = a.scored
    sq = (estimate - a.d_clean) ** 2
    lidar = np.isfinite(a.l_al)
    out = {}
    for k, kind in enumerate(SEGMENT_KINDS):
        for has, name in ((True, "lidar"), (False, "no_lidar")):
            mask = scored & (a.kind == k) & (lidar == has)
            out[f"{kind}|{name}"] = {"n": int(mask.sum()), "sse": float(sq[mask].sum()),
                                     "rmse": float(np.sqrt(sq[mask].mean())) if mask.any() else None}
    return out
