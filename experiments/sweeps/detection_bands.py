"""The detector's recall in the loop, by the target's distance: what an attack on the camera leaves.

From a sweep's per-step logs (kept with ``--log-steps``): over the control steps with a new
camera frame and the target in view, the share on which the detector reported it, per
distance band of the true depth and per attack, its settings and estimator. For an attacked
setting only the steps the attack acted on count (a sticker up from the start: all of them).
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from racf.stats import wilson_interval

__all__ = ["BANDS_M", "DISTANCE_BANDS_M", "recall_rows", "band_labels", "band_label"]

#: The distance bands recall is reported in (the sign's true depth, m): in the loop here, per
#: rendered view in the detector's study (``racf.experiments.detector.evaluate``).
DISTANCE_BANDS_M = ((0.3, 1.0), (1.0, 2.0), (2.0, 4.0))
BANDS_M = DISTANCE_BANDS_M


def band_label(lo: float, hi: float) -> str:
    """A band's name in tables and JSON, e.g. ``0.3-1 m``."""
    return f"{lo:g}-{hi:g} m"
_COLUMNS = ["frame_new", "control", "sign_in_view", "d_true", "detected", "attack_active"]


def recall_rows(frame: pd.DataFrame, logs: Path) -> list[dict]:
    """One row per (attack, settings, estimator) with logs: recall and its Wilson interval per band
    (``n`` frames); empty when no episode kept its log."""
    logs = Path(logs)
    if frame.empty or not logs.is_dir():
        return []
    frame = frame.assign(attack_params=frame.get("attack_params", pd.Series("", index=frame.index)).fillna(""))
    rows = []
    for (attack, params, estimator), group in frame.groupby(["attack", "attack_params", "estimator"], sort=True):
        hits = {band: [0, 0] for band in BANDS_M}
        for trial_id in group["trial_id"]:
            path = logs / f"{trial_id}.parquet"
            if not path.exists():
                continue
            log = pd.read_parquet(path, columns=_COLUMNS)
            seen = log["frame_new"].astype(bool) & log["control"].astype(bool) & log["sign_in_view"].astype(bool)
            if attack != "none":
                seen &= log["attack_active"].astype(bool)
            d, detected = log["d_true"].to_numpy(float), log["detected"].astype(bool).to_numpy()
            for lo, hi in BANDS_M:
                in_band = seen.to_numpy() & (d >= lo) & (d < hi)
                hits[(lo, hi)][0] += int(detected[in_band].sum())
                hits[(lo, hi)][1] += int(in_band.sum())
        if not any(n for _, n in hits.values()):
            continue
        bands = {band_label(lo, hi): {"recall": k / n if n else None, "recall_ci": wilson_interval(k, n), "n": n}
                 for (lo, hi), (k, n) in hits.items()}
        rows.append({"attack": str(attack), "params": str(params), "estimator": str(estimator), "bands": bands})
    return rows


def band_labels() -> list[str]:
    """The bands' names, in order (the keys of a row's ``bands``)."""
    return [band_label(lo, hi) for lo, hi in BANDS_M]
