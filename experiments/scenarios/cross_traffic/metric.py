"""Cross-traffic's metric (``conflict``): what an episode came to with the other cars, scored from
the step log by :func:`~racf.experiments.scenarios.cross_traffic.conflict.score_conflict`."""

from __future__ import annotations

import math

import pandas as pd

from racf.experiments.metrics.base import Episode, Field, Metric
from racf.experiments.metrics.builtin import attack_before_t_star
from racf.experiments.scenarios.cross_traffic.conflict import CONFLICT_OUTCOMES, score_conflict
from racf.stats import wilson_interval

__all__ = ["Conflict", "conflict_summary"]

_NAN = math.nan


class Conflict(Metric):
    """What the episode came to with the other cars: the conflict outcome, the smallest time-to-collision
    and the post-encroachment time (a contact with anything counts)."""

    name = "conflict"
    meaning = "collisions, conflicts and time-to-collision with other cars"
    order = 61
    fields = (
        Field("conflict", None, "", f"with other cars, one of {', '.join(CONFLICT_OUTCOMES)}"),
        Field("min_ttc_s", _NAN, "s", "the smallest time-to-collision with another car"),
        Field("pet_s", _NAN, "s", "the post-encroachment time at the conflict point"),
        Field("traffic_cars", 0, "cars", "how many other cars drove"),
    )

    def score(self, episode: Episode) -> dict:
        outcome = score_conflict(episode.log)
        return {"conflict": outcome.conflict, "min_ttc_s": outcome.min_ttc_s, "pet_s": outcome.pet_s,
                "traffic_cars": len(episode.plan.extras.get("cars", ()))}

    def summarize(self, results: pd.DataFrame, attacked: bool) -> dict:
        summary = conflict_summary(results)
        if attacked and summary.get("n_traffic"):
            early = attack_before_t_star(results)
            early = early[pd.to_numeric(early["traffic_cars"], errors="coerce").fillna(0) > 0]
            k_hit = int(early["collision"].fillna(False).astype(bool).sum())
            summary["n_traffic_attack_before_t_star"] = int(len(early))
            summary["collision_rate_attack_before_t_star"] = k_hit / len(early) if len(early) else None
            summary["collision_rate_attack_before_t_star_ci"] = list(wilson_interval(k_hit, len(early)))
        return summary


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
