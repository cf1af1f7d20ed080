"""Cards written by an older racf, read as the current form.

Before a scenario's criteria declared their card measures (``Criterion.card``), a row whose episodes
kept behind a car ahead held them under keys of their own (``n_following``, ``collision_free``,
``needless_hard_brake``) beside the stop rule's summaries, which did not apply to it (``asr``,
``failures``, ``dt_brake``, the STL robustness, the stealth measures). :func:`current_row` turns such a
row into the current form: the same numbers as a ``headline`` list, and the measures that do not apply
left out. The board, the card pages and the results pages read every card through it, so a card
submitted before the change reads as one made after it.
"""

from __future__ import annotations

__all__ = ["current_row", "current_card", "NOT_APPLYING"]

#: The stop rule's summaries, which a row its criteria judged otherwise does not carry.
NOT_APPLYING = ("scr", "scr_ci", "asr", "asr_ci", "failures", "dt_brake_mean", "dt_brake_std", "n_latency",
                "n_attack_before_t_star", "scr_attack_before_t_star", "scr_attack_before_t_star_ci",
                "robustness_median_m", "robustness_ci", "robustness_p5_m", "robustness_min_m", "violation_share",
                "violation_share_ci", "undetected_error_median", "undetected_error_ci", "detected_share",
                "detected_share_ci")
_OLD = (("collision_free", "collision-free", True), ("needless_hard_brake", "needless hard brake", False))


def current_row(row: dict) -> dict:
    """One closed-loop row in the current form (a row already in it is returned as it is)."""
    if not row.get("n_following"):
        return row
    n = row["n_following"]
    headline = [{"measure": measure, "value": row[key], "ci": row[f"{key}_ci"], "n": n, "higher_is_better": higher}
                for key, measure, higher in _OLD if key in row]
    dropped = {"n_following", *NOT_APPLYING, *(k for key, _, _ in _OLD for k in (key, f"{key}_ci"))}
    return {k: v for k, v in row.items() if k not in dropped} | {"headline": headline}


def current_card(card: dict) -> dict:
    """A card with every closed-loop row in the current form."""
    return {**card, "closed_loop": {key: current_row(r) for key, r in card.get("closed_loop", {}).items()}}
