"""A defence rated as a detector, from its per-step ``flag`` (and ``score``, if it reports one)
against the steps an attack was active.

Which steps count (``docs/protocol.md``, the scorecard's detection rows):

- positives: the steps with the attack active (``attack_active``);
- negatives: every step of a clean episode, and an attacked episode's steps before its attack
  began; an attacked episode's steps after its attack ended are neither (the defence may
  still be recovering);
- only steps with a depth to judge (``d_meas`` finite) and where the defence reported (``flag``
  not NaN) count: a missing depth (an occluded sign, a blackout) is plain to any defence and
  is not a detection, and a defence with no detector has no detection rows.

TPR and FPR are shares of those steps with Wilson intervals. The AUROC is over ``score``
(higher: more suspicious) where the defence reports one, else over the binary flag (one
operating point; said so in ``auroc_from``). The time to detect is per attacked episode, from
the attack's start to the first flag at or after it (median over the episodes the defence
flagged). The **undetected error at 1 % false alarms** sets the threshold on ``score`` that
flags 1 % of the negative steps, and takes, per attacked episode, the largest |d_fused - d_true|
over the active steps before the first step above it; the output is read as logged, so for a
defence whose repair depends on its own threshold this is the error of the logged run seen
through the new threshold. With no score it falls back to the flag (and says so).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from racf.stats import median_ci, wilson_interval

__all__ = ["FALSE_ALARM_RATE", "label_steps", "detection_rows", "roc_points"]

#: The false-alarm rate at which the undetected error is read: 1 % of clean steps flagged.
FALSE_ALARM_RATE = 0.01


def label_steps(log: pd.DataFrame) -> pd.Series:
    """Per step: 1 (attack active), 0 (clean: no attack yet, or none at all), NaN (after the
    attack ended, no depth to judge, or the defence did not report)."""
    n = len(log)
    active = log["attack_active"].to_numpy(bool) if "attack_active" in log else np.zeros(n, bool)
    label = np.zeros(n)
    if active.any():
        label[int(np.argmax(active)):] = np.nan
        label[active] = 1.0
    flag = log["flag"].to_numpy(float) if "flag" in log else np.full(n, np.nan)
    label[~np.isfinite(flag)] = np.nan
    if "d_meas" in log:
        label[~np.isfinite(log["d_meas"].to_numpy(float))] = np.nan
    return pd.Series(label, index=log.index)


def _score(log: pd.DataFrame) -> np.ndarray:
    if "score" in log and np.isfinite(log["score"].to_numpy(float)).any():
        return log["score"].to_numpy(float)
    return log["flag"].to_numpy(float)


def _episode_measures(log: pd.DataFrame, threshold: float | None) -> dict | None:
    """Time to detect and the undetected error at ``threshold`` (None: the flag) of one attacked episode."""
    active = log["attack_active"].to_numpy(bool) if "attack_active" in log else np.zeros(len(log), bool)
    if not active.any():
        return None
    start = int(np.argmax(active))
    t = log["t"].to_numpy(float)
    idx = np.arange(len(log))
    flag = log["flag"].to_numpy(float)
    flagged = np.flatnonzero((flag == 1.0) & (idx >= start))
    alarm = flagged if threshold is None else np.flatnonzero((_score(log) > threshold) & (idx >= start))
    until = int(alarm[0]) if alarm.size else len(log)
    quiet = active & (idx < until)
    err = np.abs(log["d_fused"].to_numpy(float) - log["d_true"].to_numpy(float))[quiet]
    err = err[np.isfinite(err)]
    return {"time_to_detect_s": float(t[flagged[0]] - t[start]) if flagged.size else math.nan,
            "undetected_error_m": float(err.max()) if err.size else math.nan}


def roc_points(labels: np.ndarray, scores: np.ndarray) -> dict:
    """The ROC curve (false- and true-positive rates) and its area."""
    from sklearn.metrics import roc_auc_score, roc_curve

    fpr, tpr, _ = roc_curve(labels, scores)
    return {"fpr": fpr.tolist(), "tpr": tpr.tolist(), "auroc": float(roc_auc_score(labels, scores))}


def detection_rows(logs: list[pd.DataFrame]) -> dict | None:
    """The detection rows of one defence over its episodes' step logs (None: it reported no
    flag on any step, i.e. it has no detector)."""
    logs = [log for log in logs if "flag" in log and np.isfinite(log["flag"].to_numpy(float)).any()]
    if not logs:
        return None
    labels = np.concatenate([label_steps(log).to_numpy() for log in logs])
    flags = np.concatenate([log["flag"].to_numpy(float) for log in logs])
    scores = np.concatenate([_score(log) for log in logs])
    has_score = any("score" in log and np.isfinite(log["score"].to_numpy(float)).any() for log in logs)
    keep = np.isfinite(labels) & np.isfinite(scores)
    labels, flags, scores = labels[keep], flags[keep], scores[keep]
    pos, neg = labels == 1.0, labels == 0.0
    tp, fp = int((flags[pos] == 1.0).sum()), int((flags[neg] == 1.0).sum())
    row = {"n_positive_steps": int(pos.sum()), "n_negative_steps": int(neg.sum()),
           "tpr": tp / pos.sum() if pos.any() else None, "tpr_ci": list(wilson_interval(tp, int(pos.sum()))),
           "fpr": fp / neg.sum() if neg.any() else None, "fpr_ci": list(wilson_interval(fp, int(neg.sum()))),
           "auroc": None, "auroc_from": "score" if has_score else "flag", "roc": None}
    if pos.any() and neg.any():
        roc = roc_points(labels, scores)
        row["auroc"], row["roc"] = roc["auroc"], {"fpr": roc["fpr"], "tpr": roc["tpr"]}
    threshold = float(np.quantile(scores[neg], 1.0 - FALSE_ALARM_RATE)) if has_score and neg.any() else None
    episodes = [m for log in logs if (m := _episode_measures(log, threshold)) is not None]
    delays = np.array([m["time_to_detect_s"] for m in episodes])
    errors = np.array([m["undetected_error_m"] for m in episodes])
    detected = np.isfinite(delays)
    row["n_attacked_episodes"] = len(episodes)
    row["detected_share"] = float(detected.mean()) if episodes else None
    row["detected_share_ci"] = list(wilson_interval(int(detected.sum()), len(episodes)))
    row["time_to_detect_median_s"], row["time_to_detect_ci"] = median_ci(delays[detected])
    row["undetected_error_at"] = "1 % false alarms (score threshold)" if threshold is not None else "the flag"
    row["threshold"] = threshold
    row["undetected_error_median_m"], row["undetected_error_ci"] = median_ci(errors[np.isfinite(errors)])
    return row
