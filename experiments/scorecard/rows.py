"""A card's rows, flat: (section, row, measure, value, interval, N, higher is better), in the
battery's order. The Markdown card, the comparison, the card page and the board read them."""

from __future__ import annotations

__all__ = ["card_rows"]


def card_rows(card: dict) -> list[tuple[str, str, str, float | None, list | None, int | None, bool]]:
    """Every row of a card as (section, row, measure, value, interval, N, higher_is_better)."""
    from racf.experiments.scorecard.battery import BATTERIES

    from racf.experiments.scorecard.card_format import current_card

    card = current_card(card)
    rows = []
    battery = BATTERIES.get(card["battery"].removesuffix("-quick"))
    order = [r.key for r in battery.rows()] if battery else []
    for key, r in sorted(card["closed_loop"].items(), key=lambda kv: order.index(kv[0]) if kv[0] in order else 99):
        if "scr" in r and (r["scr"] is not None or "n_needless" not in r):  # the stop rule judged the row
            rows.append(("closed loop", r["title"], "SCR", r["scr"], r["scr_ci"], r["n"], True))  # (no sign stood: none)
        for m in r.get("headline", []):  # what the row's criteria declare (Criterion.card)
            rows.append(("closed loop", r["title"], m["measure"], m["value"], m["ci"], m["n"], m["higher_is_better"]))
        if r.get("n_attack_before_t_star"):
            rows.append(("closed loop", r["title"], "SCR, attack before t*", r["scr_attack_before_t_star"],
                         r["scr_attack_before_t_star_ci"], r["n_attack_before_t_star"], True))
        if r.get("undetected_error_median") is not None:
            rows.append(("closed loop", r["title"], "undetected error m, median", r["undetected_error_median"],
                         r["undetected_error_ci"], r["n"], False))
        if r.get("robustness_median_m") is not None:  # the stop rule's STL robustness
            rows.append(("closed loop", r["title"], "STL robustness m, median", r["robustness_median_m"],
                         r["robustness_ci"], r["n"], True))
        if r.get("n_traffic"):  # other cars crossing: what a missed stop cost
            rows.append(("closed loop", r["title"], "collision rate", r["collision_rate"], r["collision_rate_ci"],
                         r["n_traffic"], False))
            if r.get("n_traffic_attack_before_t_star"):
                rows.append(("closed loop", r["title"], "collision rate, attack before t*",
                             r["collision_rate_attack_before_t_star"], r["collision_rate_attack_before_t_star_ci"],
                             r["n_traffic_attack_before_t_star"], False))
        if r.get("driving_score") is not None:
            rows.append(("closed loop", r["title"], "driving score", r["driving_score"], r["driving_score_ci"], r["n"],
                         True))
        for m in r.get("measures", []):  # the plug-in metrics' declared fields (card.plugin_measures)
            rows.append(("closed loop", r["title"], m["measure"], m["value"], m["ci"], m["n"], m["higher_is_better"]))
    for key, r in card["drives"].items():
        rows.append(("drives", r["title"], "driving score", r["driving_score"], r["driving_score_ci"], r["n"], True))
        rows.append(("drives", r["title"], "route completion", r["route_completion"], None, r["n"], True))
    d = card.get("detection")
    if d:
        rows += [("detection", "all closed-loop steps", "TPR", d["tpr"], d["tpr_ci"], d["n_positive_steps"], True),
                 ("detection", "all closed-loop steps", "FPR", d["fpr"], d["fpr_ci"], d["n_negative_steps"], False),
                 ("detection", "all closed-loop steps", f"AUROC (from the {d['auroc_from']})", d["auroc"], None,
                  d["n_positive_steps"] + d["n_negative_steps"], True),
                 ("detection", "attacked episodes", "median time to detect, s", d["time_to_detect_median_s"],
                  d["time_to_detect_ci"], d["n_attacked_episodes"], False),
                 ("detection", "attacked episodes", f"undetected error m, median, at {d['undetected_error_at']}",
                  d["undetected_error_median_m"], d["undetected_error_ci"], d["n_attacked_episodes"], False)]
    off = card.get("offline")
    if off:
        for preset in ("weak", "mid", "strong"):
            if preset in off:
                r = off[preset]
                rows.append(("offline", f"{preset} preset ({off.get('split', 'by_series')}, {r['n_draws']} draws)",
                             "RMSE m", r["rmse"], r["rmse_ci"], r["n"], False))
        if off.get("strong_ratio_to_chronos") is not None:
            rows.append(("offline", "strong preset", "RMSE / Chronos-only's", off["strong_ratio_to_chronos"], None,
                         off["strong"]["n"], False))
        p = off["clean_pass_through"]
        rows.append(("offline", "clean input", "unchanged share", p["unchanged_share"], None, p["n_depth"], True))
    params = card["cost"]["parameters"]
    rows.append(("cost", f"parameters ({params['from']})", "trainable", params["trainable"], None, None, False))
    step = card.get("timing", {}).get("step_time")
    if step:
        rows.append(("cost", "per step, one thread", "p99 ms (a timing: varies run to run)", step["p99_ms"], None,
                     step["n_steps"], False))
    return rows
