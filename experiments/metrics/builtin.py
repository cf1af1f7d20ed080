"""racf's own metrics, registered the way a user's are (``racf.metrics`` entry points): what the
attack did, the stop's outcome and timing, the acted-on distance's largest jump, the stealth
measures, the stop rule's STL robustness and whether the car touched anything. A scenario's own
metrics live with it (cross-traffic's ``conflict``: ``racf.experiments.scenarios.cross_traffic``).

Each wraps a pure scorer of the per-step log (``racf.experiments.episode.scoring``,
``.robustness``), so a stored log can be rescored without running anything. Where the stop rule
does not apply (no target stands: ``racf.experiments.episode.criteria``), the outcome and the
robustness say nothing (None, NaN) instead of a broken rule.
"""

from __future__ import annotations

import math
from dataclasses import asdict

import numpy as np
import pandas as pd

from racf.experiments.episode.criteria import StopRule, standing_outcomes
from racf.experiments.episode.robustness import robustness
from racf.experiments.episode.scoring import FAILURES, largest_jump, stealth
from racf.experiments.metrics.base import Episode, Field, Metric
from racf.sim.attacks import PatchOcclusion
from racf.sim.attacks.base import attack_wrappers, find_wrapper
from racf.stats import median_ci, wilson_interval

__all__ = ["AttackMeasures", "Outcome", "Jump", "StealthMeasures", "Robustness", "Collision",
           "stealth_summary", "robustness_summary", "attack_before_t_star"]

_NAN = math.nan


class AttackMeasures(Metric):
    """When and how hard the attack acted: the first window of the attack that began first (the patch
    on a tie), the patch's coverage, and the frames the detector lost to it."""

    name = "attack"
    meaning = "when the attack that began first acted, the patch's coverage and the frames it cost the detector"
    always, order = True, 10
    fields = (
        Field("rho", _NAN, "", "the patch's coverage share (NaN: no patch)"),
        Field("t_atk_s", _NAN, "s", "the first attack window's length"),
        Field("attack_start_s", _NAN, "s", "when the first attack window began (NaN: no attack began)"),
        Field("lost_frames", 0, "frames", "steps the sign was in view and attacked but not detected, of those the "
                                          "car's detector finds on the unattacked frame (a sign it cannot see "
                                          "clean is not the attack's loss)"),
    )

    def score(self, episode: Episode) -> dict:
        patch = find_wrapper(episode.env, PatchOcclusion)
        windows = _first_attack_windows(episode.env)
        log = episode.log
        return {"rho": patch.rho if patch is not None else _NAN,
                "t_atk_s": windows[0][1] - windows[0][0] if windows else _NAN,
                "attack_start_s": windows[0][0] if windows else _NAN,
                "lost_frames": int((log["attack_active"] & log["clean_detected"] & ~log["detected"]).sum())}

    def summarize(self, results: pd.DataFrame, attacked: bool) -> dict:
        if not attacked:
            return {}
        n = len(results)
        if "success" not in results:  # no stop rule judged these episodes: no SCR before t*
            return {"lost_frames_mean": float(results["lost_frames"].mean()) if n else None,
                    "attacked_share": float(results["attack_start_s"].notna().mean()) if n else None}
        early = attack_before_t_star(results)
        k_early = int(early["success"].astype(bool).sum()) if len(early) else 0
        return {"n_attack_before_t_star": int(len(early)),
                "scr_attack_before_t_star": k_early / len(early) if len(early) else None,
                "scr_attack_before_t_star_ci": list(wilson_interval(k_early, len(early))),
                "lost_frames_mean": float(results["lost_frames"].mean()) if n else None,
                "attacked_share": float(results["attack_start_s"].notna().mean()) if n else None}


class Outcome(Metric):
    """The protocol's outcome of the first target (the timing fields) and of every target (success)."""

    name = "outcome"
    meaning = "stop compliance: whether the car stopped in the band, where, and how late it braked"
    always, order = True, 20
    needs_criterion = "stop_rule"
    higher_is_better = {"success": True}
    fields = (
        Field("success", None, "", "every target that stands served: at rest 0-0.60 m before its line (None: no "
                                   "target stands, the stop rule does not apply)", "rate"),
        Field("stopped", False, "", "the car came to rest for the first target"),
        Field("stop_distance_m", _NAN, "m", "front bumper to the first target's line at rest"),
        Field("t_star_s", _NAN, "s", "t*: when the reference controller first brakes"),
        Field("t_brake_s", _NAN, "s", "when the car first braked"),
        Field("trigger_delay_s", _NAN, "s", "t(brake) - t*, t* the reference braker's first brake (negative: the car "
                                            "braked before it would have, which is early, not wrong)"),
        Field("dt_brake_s", _NAN, "s", "the paper's latency: t* to braking within 0.60 m of the line"),
        Field("failure", None, "", f"where a failed first target went wrong: one of {', '.join(FAILURES)}"),
        Field("duration_s", _NAN, "s", "the episode's length"),
        Field("n_targets", 1, "targets", "targets on the route"),
        Field("targets_served", 0, "targets", "targets the car stopped for in the band"),
    )

    def score(self, episode: Episode) -> dict:
        n_targets, duration = len(episode.plan.mission.targets), float(episode.log["t"].iloc[-1])
        if not StopRule().applies(episode):  # no target stands: nothing to stop for, no SCR
            return {"success": None, "duration_s": duration, "n_targets": n_targets}
        outcomes = standing_outcomes(episode.log)
        first = outcomes[0]
        served = sum(o.success for o in outcomes)
        return {"success": bool(served == len(outcomes)), "stopped": not math.isnan(first.rest_distance_m),
                "stop_distance_m": first.rest_distance_m, "t_star_s": first.t_star_s, "t_brake_s": first.t_brake_s,
                "trigger_delay_s": first.trigger_delay_s, "dt_brake_s": first.dt_brake_s, "failure": first.failure,
                "duration_s": duration, "n_targets": n_targets, "targets_served": served}

    def summarize(self, results: pd.DataFrame, attacked: bool) -> dict:
        results = results[results["success"].notna()] if len(results) else results  # where the stop rule applies
        n = int(len(results))
        success = results["success"].astype(bool) if n else pd.Series(dtype=bool)
        k = int(success.sum())
        scr = k / n if n else None
        ok = results[success] if n else results
        summary = {"n_scr": n, "scr": scr, "scr_ci": list(wilson_interval(k, n)),
                   "asr": (1.0 - scr) if attacked and n else None}
        summary["trigger_delay_mean"], summary["trigger_delay_std"] = _mean_std(ok["trigger_delay_s"]) if n else (
            None, None)
        summary["dt_brake_mean"], summary["dt_brake_std"] = _mean_std(ok["dt_brake_s"]) if n else (None, None)
        summary["n_latency"] = int(pd.to_numeric(ok["dt_brake_s"], errors="coerce").notna().sum()) if n else 0
        summary["failures"] = {f: int((results["failure"] == f).sum()) for f in FAILURES} if n else {}
        if attacked:
            summary["asr_ci"] = [1.0 - summary["scr_ci"][1], 1.0 - summary["scr_ci"][0]]
        return summary


class Jump(Metric):
    """The largest step change of the distance the car acted on beyond its own motion (the no-jump bound)."""

    name = "jump"
    meaning = "the largest step change of the acted-on distance beyond the car's own motion"
    always, order = True, 30
    needs_criterion = "stop_rule"
    fields = (Field("fused_jump_m", _NAN, "m", "the largest step change of d_fused beyond the car's motion"),)

    def score(self, episode: Episode) -> dict:
        return {"fused_jump_m": largest_jump(episode.log)}

    def summarize(self, results: pd.DataFrame, attacked: bool) -> dict:
        jumps = pd.to_numeric(results["fused_jump_m"], errors="coerce").dropna() if "fused_jump_m" in results else []
        return {"max_fused_jump_m": float(jumps.max()) if len(jumps) else None}


class StealthMeasures(Metric):
    """How far the attack pushed the acted-on distance before the defence flagged it, and when it did."""

    name = "stealth"
    meaning = "the undetected error and the detection delay of the defence's flag"
    always, order = True, 40
    needs_criterion = "stop_rule"
    higher_is_better = {"undetected_error_m": False, "detected": True}
    fields = (
        Field("undetected_error_m", _NAN, "m", "the largest |d_fused - d_true| before the defence's first flag (over "
                                               "the whole attack where it never flagged)"),
        Field("detection_delay_s", _NAN, "s", "the attack's start to the defence's first flag"),
        Field("detected", False, "", "the defence flagged the attack (False: it never flagged it, whatever the car "
                                     "did: an attack can fail unflagged)"),
    )

    def score(self, episode: Episode) -> dict:
        return asdict(stealth(episode.log))

    def summarize(self, results: pd.DataFrame, attacked: bool) -> dict:
        return stealth_summary(results) if attacked else {}


class Robustness(Metric):
    """The stop rule's signal-temporal-logic robustness, the lowest over the targets (negative: broken)."""

    name = "robustness"
    meaning = "the stop rule's STL robustness (negative: the rule was broken)"
    always, order = True, 50
    needs_criterion = "stop_rule"
    higher_is_better = {"robustness_m": True}
    fields = (Field("robustness_m", _NAN, "m", "the stop rule's STL robustness, lowest over the targets: how far the "
                                           "car stayed from breaking the rule (negative: it broke it, by that much)"),)

    def score(self, episode: Episode) -> dict:
        if not StopRule().applies(episode):  # no stop rule where no target stands
            return {}
        return {"robustness_m": robustness(episode.log)}

    def summarize(self, results: pd.DataFrame, attacked: bool) -> dict:
        return robustness_summary(results)


class Collision(Metric):
    """Whether the car touched anything, and what (the env's contact report, which ends the episode)."""

    name = "collision"
    meaning = "whether the car touched anything, and what it touched first"
    always, order = True, 60
    higher_is_better = {"collision": False}
    fields = (
        Field("collision", False, "", "the car touched anything"),
        Field("collision_with", None, "", "what it touched first (a world manager's name for its body, or a geom's)"),
    )

    def score(self, episode: Episode) -> dict:
        touched = episode.log["collision_with"].astype(str) if "collision_with" in episode.log else ()
        hits = [name for name in touched if name]
        return {"collision": bool(hits), "collision_with": hits[0] if hits else None}


def robustness_summary(results: pd.DataFrame) -> dict:
    """The distribution of the stop rule's robustness over the episodes that have one (none for
    results stored before it was logged)."""
    values = pd.to_numeric(results["robustness_m"], errors="coerce").dropna() if "robustness_m" in results else []
    if not len(values):
        return {}
    median, interval = median_ci(values)
    broken = int((values < 0).sum())
    return {"n_robustness": int(len(values)), "robustness_median_m": median, "robustness_ci": interval,
            "robustness_p5_m": float(np.quantile(values, 0.05)), "robustness_min_m": float(values.min()),
            "violation_share": broken / len(values), "violation_share_ci": list(wilson_interval(broken, len(values)))}


def stealth_summary(results: pd.DataFrame) -> dict:
    """The stealth measures over the episodes whose attack began (``scoring.stealth``)."""
    if "undetected_error_m" not in results or not len(results):
        return {}
    began = results[results["attack_start_s"].notna()]
    err = pd.to_numeric(began["undetected_error_m"], errors="coerce").dropna()
    median, interval = median_ci(err)
    detected = began["detected"].fillna(False).astype(bool)
    delays = pd.to_numeric(began.loc[detected, "detection_delay_s"], errors="coerce").dropna()
    return {"n_attacked": int(len(began)), "undetected_error_median": median, "undetected_error_ci": interval,
            "undetected_error_max": float(err.max()) if len(err) else None,
            "detected_share": float(detected.mean()) if len(began) else None,
            "detected_share_ci": list(wilson_interval(int(detected.sum()), int(len(began)))),
            "detection_delay_median": float(delays.median()) if len(delays) else None}


def attack_before_t_star(results: pd.DataFrame) -> pd.DataFrame:
    """The episodes whose attack began before t* (only those can test a defence)."""
    if not len(results):
        return results
    return results[pd.to_numeric(results["attack_start_s"], errors="coerce")
                   < pd.to_numeric(results["t_star_s"], errors="coerce")]


def _mean_std(values: pd.Series) -> tuple[float | None, float | None]:
    values = pd.to_numeric(values, errors="coerce").dropna()
    return (float(values.mean()) if len(values) else None,
            float(values.std(ddof=1)) if len(values) > 1 else None)


def _first_attack_windows(env) -> list[tuple[float, float]]:
    """The attack windows (start, end s) of the attack that began first (the patch on a tie)."""
    attacks = [a for a in attack_wrappers(env) if a.schedule.windows]
    if not attacks:
        return []
    return min(attacks, key=lambda a: (a.schedule.windows[0][0], not isinstance(a, PatchOcclusion))).schedule.windows
