"""The one summary of a batch of episodes (``docs/protocol.md``), for trials, tables, studies and sweeps.

Per setting: N; SCR with its 95 % Wilson interval; under an attack, ASR = 1 - SCR and the
SCR over the episodes whose attack began before t* (only those can test a defence: where the
sign comes into view inside the braking distance, braking starts before the protocol lets an
attack begin); the trigger delay and the paper's dt_brake over successful stops; failures by
cause; the largest step change of the acted-on distance beyond the car's motion over all
episodes (the no-jump bound); under an attack, the stealth measures (``scoring.stealth``):
the undetected error's median with a 95 % bootstrap interval (seeded: the same rows give the
same interval) and its largest value, the share of episodes whose attack the defence flagged
(Wilson interval) and the median detection delay; the stop rule's STL robustness
(``episode.robustness``): its median with a bootstrap interval, 5th percentile and lowest value,
and the share of episodes that broke the rule (robustness < 0, Wilson interval); with
cross-traffic (``episode.conflict``), the collision rate (Wilson interval; under an attack also
over the episodes whose attack began before t*), the conflict outcomes and the smallest
time-to-collision. Strict JSON: None, never NaN.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from racf.stats import median_ci, wilson_interval
from racf.experiments.episode.conflict import CONFLICT_OUTCOMES
from racf.experiments.episode.scoring import FAILURES
from racf.experiments.episode.spec import parse_setting

__all__ = ["summarize", "summarize_settings", "stealth_summary", "robustness_summary", "conflict_summary",
           "setting_key"]


def _mean_std(values: pd.Series) -> tuple[float | None, float | None]:
    values = pd.to_numeric(values, errors="coerce").dropna()
    return (float(values.mean()) if len(values) else None,
            float(values.std(ddof=1)) if len(values) > 1 else None)


def summarize(results: pd.DataFrame, attack: bool | None = None) -> dict:
    """The summary of one setting's result rows.

    Args:
        results: result rows (``TrialResult.to_dict()`` and the store's extra columns).
        attack: whether the setting attacks; None reads it from the first row's setting.
    """
    n = int(len(results))
    if attack is None:
        attack = bool(n) and bool(parse_setting(str(results["setting"].iloc[0]))[0])
    success = results["success"].astype(bool) if n else pd.Series(dtype=bool)
    k = int(success.sum())
    scr = k / n if n else None
    ok = results[success] if n else results
    summary = {"n": n, "scr": scr, "scr_ci": list(wilson_interval(k, n)), "asr": (1.0 - scr) if attack and n else None}
    summary["trigger_delay_mean"], summary["trigger_delay_std"] = _mean_std(ok["trigger_delay_s"]) if n else (None,
                                                                                                              None)
    summary["dt_brake_mean"], summary["dt_brake_std"] = _mean_std(ok["dt_brake_s"]) if n else (None, None)
    summary["n_latency"] = int(pd.to_numeric(ok["dt_brake_s"], errors="coerce").notna().sum()) if n else 0
    summary["failures"] = {f: int((results["failure"] == f).sum()) for f in FAILURES} if n else {}
    jumps = pd.to_numeric(results["fused_jump_m"], errors="coerce").dropna() if "fused_jump_m" in results else []
    summary["max_fused_jump_m"] = float(jumps.max()) if len(jumps) else None
    summary.update(robustness_summary(results))
    summary.update(conflict_summary(results))
    if attack:
        summary["asr_ci"] = [1.0 - summary["scr_ci"][1], 1.0 - summary["scr_ci"][0]]
        early = results[pd.to_numeric(results["attack_start_s"], errors="coerce")
                        < pd.to_numeric(results["t_star_s"], errors="coerce")] if n else results
        k_early = int(early["success"].astype(bool).sum()) if len(early) else 0
        summary["n_attack_before_t_star"] = int(len(early))
        summary["scr_attack_before_t_star"] = k_early / len(early) if len(early) else None
        summary["scr_attack_before_t_star_ci"] = list(wilson_interval(k_early, len(early)))
        summary["lost_frames_mean"] = float(results["lost_frames"].mean()) if n else None
        summary["attacked_share"] = float(results["attack_start_s"].notna().mean()) if n else None
        summary.update(stealth_summary(results))
        if summary.get("n_traffic"):
            early = early[pd.to_numeric(early["traffic_cars"], errors="coerce").fillna(0) > 0]
            k_hit = int(early["collision"].fillna(False).astype(bool).sum())
            summary["n_traffic_attack_before_t_star"] = int(len(early))
            summary["collision_rate_attack_before_t_star"] = k_hit / len(early) if len(early) else None
            summary["collision_rate_attack_before_t_star_ci"] = list(wilson_interval(k_hit, len(early)))
    return summary


def robustness_summary(results: pd.DataFrame) -> dict:
    """The distribution of the stop rule's robustness over the episodes that have one (none for
    results stored before it was logged)."""
    values = pd.to_numeric(results["robustness_m"], errors="coerce").dropna() if "robustness_m" in results else []
    if not len(values):
        return {}
    median, ci = median_ci(values)
    broken = int((values < 0).sum())
    return {"n_robustness": int(len(values)), "robustness_median_m": median, "robustness_ci": ci,
            "robustness_p5_m": float(np.quantile(values, 0.05)), "robustness_min_m": float(values.min()),
            "violation_share": broken / len(values), "violation_share_ci": list(wilson_interval(broken, len(values)))}


def stealth_summary(results: pd.DataFrame) -> dict:
    """The stealth measures over the episodes whose attack began (``scoring.stealth``)."""
    if "undetected_error_m" not in results or not len(results):
        return {}
    began = results[results["attack_start_s"].notna()]
    err = pd.to_numeric(began["undetected_error_m"], errors="coerce").dropna()
    median, ci = median_ci(err)
    detected = began["detected"].fillna(False).astype(bool)
    delays = pd.to_numeric(began.loc[detected, "detection_delay_s"], errors="coerce").dropna()
    return {"n_attacked": int(len(began)), "undetected_error_median": median, "undetected_error_ci": ci,
            "undetected_error_max": float(err.max()) if len(err) else None,
            "detected_share": float(detected.mean()) if len(began) else None,
            "detected_share_ci": list(wilson_interval(int(detected.sum()), int(len(began)))),
            "detection_delay_median": float(delays.median()) if len(delays) else None}


def conflict_summary(results: pd.DataFrame) -> dict:
    """Collisions and conflicts over the episodes that drove with other cars (none without)."""
    if "traffic_cars" not in results or not len(results):
        return {}
    with_traffic = results[pd.to_numeric(results["traffic_cars"], errors="coerce").fillna(0) > 0]
    if not len(with_traffic):
        return {}
    n = int(len(with_traffic))
    hit = int(with_traffic["collision"].fillna(False).astype(bool).sum())
    ttc = pd.to_numeric(with_traffic["min_ttc_s"], errors="coerce").dropna()
    return {"n_traffic": n, "collision_rate": hit / n, "collision_rate_ci": list(wilson_interval(hit, n)),
            "conflicts": {c: int((with_traffic["conflict"] == c).sum()) for c in CONFLICT_OUTCOMES},
            "min_ttc_median_s": float(ttc.median()) if len(ttc) else None}


def setting_key(setting: str, traffic_cars: int = 0) -> str:
    """How summaries name a setting: with other cars, ``SETTING@trafficN``."""
    return f"{setting}@traffic{int(traffic_cars)}" if traffic_cars else str(setting)


def summarize_settings(frame: pd.DataFrame) -> dict[str, dict]:
    """:func:`summarize` per setting (and per traffic, ``setting_key``), in sorted order."""
    if frame.empty:
        return {}
    cars = pd.to_numeric(frame["traffic_cars"], errors="coerce").fillna(0).astype(int) if "traffic_cars" in frame \
        else pd.Series(0, index=frame.index)
    keys = [setting_key(s, c) for s, c in zip(frame["setting"], cars)]
    return {key: summarize(rows) for key, rows in frame.groupby(pd.Series(keys, index=frame.index), sort=True)}
