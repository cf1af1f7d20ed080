"""A CARLA-style driving score on seeded drives: route completion x one penalty factor per
infraction (``battery.PENALTIES``: a stop sign run x 0.80, a static object hit x 0.65, a
vehicle hit x 0.60).

Per drive, from its step log (``scoring.score_log``: one outcome per target met):
route completion is the share of the drive's targets the car served; a target whose failure
put the car past its line (``braked_late``, ``confirmed_lost``, ``never_confirmed``) is an
infraction: a stop sign run, or a crate hit. Stopping short (``braked_early``) costs no
penalty: CARLA scores it through route completion, and so does this score when the car never
goes on. A contact with another car (the log's ``collision_with``: ``traffic0``..) is a vehicle
hit, on top of the stop sign it ran. The card gives the mean over the drives with a bootstrap
interval; closed-loop rows with other cars get the same score.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from racf.experiments.episode.scoring import score_log

__all__ = ["drive_score", "driving_rows", "bootstrap_mean", "PASSED_THE_LINE"]

#: The failures that leave the car past its line.
PASSED_THE_LINE = ("braked_late", "confirmed_lost", "never_confirmed")


def drive_score(log: pd.DataFrame, n_targets: int, penalties: dict[str, float], vehicles=()) -> dict:
    """One drive's route completion, infractions and driving score. ``vehicles``: the names of the
    vehicles its world declares (``WorldTarget``, named as a contact with one is): touching one is a
    vehicle hit."""
    outcomes = score_log(log)
    targets = log.groupby("slot", sort=True)["target"].first().to_dict()
    infractions = {"ran_stop_sign": 0, "hit_static_object": 0, "hit_vehicle": 0}
    for outcome in outcomes:
        if outcome.failure in PASSED_THE_LINE:
            kind = "ran_stop_sign" if str(targets[outcome.slot]).startswith("sign") else "hit_static_object"
            infractions[kind] += 1
    if "collision_with" in log and log["collision_with"].astype(str).isin(set(vehicles)).any():
        infractions["hit_vehicle"] += 1  # the env ends an episode at its first contact
    completion = len(outcomes) / n_targets if n_targets else 0.0
    penalty = float(np.prod([penalties[k] ** v for k, v in infractions.items()]))
    return {"route_completion": completion, "infractions": infractions, "penalty": penalty,
            "driving_score": completion * penalty}


def bootstrap_mean(values: np.ndarray, resamples: int = 2000) -> list[float | None]:
    if not values.size:
        return [None, None]
    rng = np.random.default_rng(0)
    means = rng.choice(values, (resamples, values.size)).mean(axis=1)
    return [float(np.quantile(means, 0.025)), float(np.quantile(means, 0.975))]


def driving_rows(results: pd.DataFrame, logs: list[pd.DataFrame], penalties: dict[str, float], vehicles=()) -> dict:
    """The driving score over a batch of drives (``results`` rows and their logs, in order; ``vehicles``:
    the names of the vehicles their worlds declare)."""
    per = [drive_score(log, int(n), penalties, vehicles) for log, n in zip(logs, results["n_targets"])]
    scores = np.array([p["driving_score"] for p in per], float)
    completion = np.array([p["route_completion"] for p in per], float)
    infractions = {k: int(sum(p["infractions"][k] for p in per)) for k in ("ran_stop_sign", "hit_static_object",
                                                                           "hit_vehicle")}
    return {"n": len(per), "driving_score": float(scores.mean()) if per else None,
            "driving_score_ci": bootstrap_mean(scores), "route_completion": float(completion.mean()) if per else None,
            "infractions": infractions, "targets": int(results["n_targets"].sum()) if per else 0}
