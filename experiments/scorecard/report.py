"""A scorecard's outputs: ``scorecard.json`` (strict), ``scorecard.md`` (one card per defence,
row by row) and ``scorecard.html`` (the same tables with the plots: the detection ROC, SCR per
attack with Wilson bands, and the undetected error against the stealth ramp's rate); and two
cards side by side."""

from __future__ import annotations

import base64
import html
import io
import json
from pathlib import Path

from racf.provenance import atomic_write
from racf.stats import ci

#: The closed-loop rows that run the stealth ramp, whose undetected error is plotted against its rate.
RAMP_ROWS = ("ramp_rates", "stealth_ramp")

__all__ = ["card_markdown", "compare_markdown", "write_scorecard", "strict_json", "card_rows"]


def strict_json(data) -> str:
    """JSON with null for every non-finite number (never NaN)."""
    def clean(x):
        if hasattr(x, "item") and not isinstance(x, (list, dict)):  # numpy scalars
            x = x.item()
        if isinstance(x, float) and x != x or x in (float("inf"), float("-inf")):
            return None
        if isinstance(x, dict):
            return {str(k): clean(v) for k, v in x.items()}
        if isinstance(x, (list, tuple)):
            return [clean(v) for v in x]
        return x
    return json.dumps(clean(data), indent=1, allow_nan=False, sort_keys=True) + "\n"


def _f(x, digits: int = 2) -> str:
    return "-" if x is None else f"{x:.{digits}f}"


def _ci(pair, digits: int = 2) -> str:
    text = ci(pair, digits)
    return f" {text}" if text else ""


def card_rows(card: dict) -> list[tuple[str, str, str, float | None, list | None, int | None, bool]]:
    """Every row of a card as (section, row, measure, value, interval, N, higher_is_better)."""
    from racf.experiments.scorecard.battery import BATTERIES

    rows = []
    battery = BATTERIES.get(card["battery"].removesuffix("-quick"))
    order = [r.key for r in battery.rows()] if battery else []
    for key, r in sorted(card["closed_loop"].items(), key=lambda kv: order.index(kv[0]) if kv[0] in order else 99):
        if r.get("scr") is not None or not ("n_needless" in r or "n_following" in r):  # no SCR where no sign
            rows.append(("closed loop", r["title"], "SCR", r["scr"], r["scr_ci"], r["n"], True))  # is the target
        if r.get("n_following"):  # the car ahead: collisions and needless hard brakes
            rows.append(("closed loop", r["title"], "collision-free", r["collision_free"], r["collision_free_ci"],
                         r["n_following"], True))
            rows.append(("closed loop", r["title"], "needless hard brake", r["needless_hard_brake"],
                         r["needless_hard_brake_ci"], r["n_following"], False))
        following = bool(r.get("n_following"))  # the stop rule's measures say nothing of following a car
        if r.get("n_attack_before_t_star") and not following:
            rows.append(("closed loop", r["title"], "SCR, attack before t*", r["scr_attack_before_t_star"],
                         r["scr_attack_before_t_star_ci"], r["n_attack_before_t_star"], True))
        if r.get("undetected_error_median") is not None:
            rows.append(("closed loop", r["title"], "undetected error m, median", r["undetected_error_median"],
                         r["undetected_error_ci"], r["n"], False))
        if r.get("robustness_median_m") is not None and not following:  # the stop rule's STL robustness
            rows.append(("closed loop", r["title"], "STL robustness m, median", r["robustness_median_m"],
                         r["robustness_ci"], r["n"], True))
        if r.get("n_traffic"):  # cross-traffic: what a missed stop cost
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


def card_markdown(card: dict) -> str:
    quick = " **(quick battery: small N, for development only)**" if card["quick"] else ""
    lines = [f"## `{card['defence']}` on battery `{card['battery']}`{quick}", "",
             f"Version `{card['version']}`, sensor profile `{card['sensor_profile']}`; "
             f"wall time {card['timing']['wall_s']:.0f} s. Intervals are 95 % (Wilson for rates, bootstrap otherwise).",
             "", "| section | row | measure | value [95% CI] | N |", "|---|---|---|---|---|"]
    for section, row, measure, value, interval, n, _ in card_rows(card):
        digits = 0 if measure == "trainable" else 3
        lines.append(f"| {section} | {row} | {measure} | {_f(value, digits)}{_ci(interval, digits)} | {n if n is not None else '-'} |")
    lines += ["", "Driving-score penalties: " + ", ".join(f"{k.replace('_', ' ')} x {v}" for k, v in card["penalties"].items())
              + ".", ""]
    if card["quick"] and card["defence"] != "raw":  # a quick card alone says little: set it beside no defence
        lines += [f"To compare: `racf scorecard --defence raw --quick` into the same `--out`, then "
                  f"`racf scorecard --compare {card['defence']} raw --quick` (the same episodes, paired).", ""]
    return "\n".join(lines)


def _disjoint(a, b) -> bool:
    return bool(a and b and a[0] is not None and b[0] is not None and (a[1] < b[0] or b[1] < a[0]))


def compare_markdown(a: dict, b: dict) -> str:
    """Two cards side by side; rows whose intervals do not overlap are marked, with the better side."""
    left = {(s, r, m): (v, ci, n, hib) for s, r, m, v, ci, n, hib in card_rows(a)}
    right = {(s, r, m): (v, ci, n, hib) for s, r, m, v, ci, n, hib in card_rows(b)}
    lines = [f"# `{a['defence']}` vs `{b['defence']}` (battery `{a['battery']}` / `{b['battery']}`)", "",
             "**bold**: the intervals do not overlap; the better side is named.", "",
             f"| section | row | measure | {a['defence']} | {b['defence']} | differs |", "|---|---|---|---|---|---|"]
    for key in [k for k in left if k in right]:
        (va, ca, _, hib), (vb, cb, _, _) = left[key], right[key]
        differs = ""
        if _disjoint(ca, cb):
            better = a["defence"] if (va > vb) == hib else b["defence"]
            differs = f"**yes: {better}**"
        lines.append(f"| {key[0]} | {key[1]} | {key[2]} | {_f(va, 3)}{_ci(ca, 3)} | {_f(vb, 3)}{_ci(cb, 3)} | {differs} |")
    return "\n".join(lines) + "\n"


def _png(fig) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    return base64.b64encode(buf.getvalue()).decode()


def _plots(cards: list[dict]) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    images = []
    fig, ax = plt.subplots(figsize=(5.2, 4.2))
    for card in cards:
        d = card.get("detection")
        if d and d.get("roc"):
            ax.plot(d["roc"]["fpr"], d["roc"]["tpr"], label=f"{card['defence']} (AUROC {d['auroc']:.2f})")
    ax.plot([0, 1], [0, 1], color="grey", lw=0.8, ls="--")
    ax.set(xlabel="false-positive rate (clean steps flagged)", ylabel="true-positive rate (attacked steps flagged)",
           title="Detection ROC over the closed-loop steps")
    ax.legend(fontsize=8)
    fig.tight_layout()
    images.append(_png(fig))
    plt.close(fig)
    keys = [k for k, r in cards[0]["closed_loop"].items() if r.get("scr") is not None]  # rows where a sign stands
    fig, ax = plt.subplots(figsize=(8.5, 4.2))
    width = 0.8 / len(cards)
    for i, card in enumerate(cards):
        rows = [card["closed_loop"][k] for k in keys]
        x = [j + i * width for j in range(len(keys))]
        scr = [r["scr"] for r in rows]
        err = [[r["scr"] - r["scr_ci"][0] for r in rows], [r["scr_ci"][1] - r["scr"] for r in rows]]
        ax.bar(x, scr, width, yerr=err, capsize=2, label=card["defence"])
    ax.set_xticks([j + 0.4 - width / 2 for j in range(len(keys))], keys, rotation=30, ha="right", fontsize=8)
    ax.set(ylabel="SCR (95 % Wilson)", ylim=(0, 1.05), title="Stop compliance per closed-loop row")
    ax.legend(fontsize=8)
    fig.tight_layout()
    images.append(_png(fig))
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(5.2, 4.2))
    for card in cards:
        rates = {}
        for key in RAMP_ROWS:  # the stealth ramp at every rate the battery runs
            rates.update(card["closed_loop"].get(key, {}).get("by_rate", {}))
        points = sorted((float(r), v) for r, v in rates.items() if v.get("undetected_error_median") is not None)
        if points:
            xs = [p[0] for p in points]
            ys = [p[1]["undetected_error_median"] for p in points]
            lo = [p[1]["undetected_error_ci"][0] for p in points]
            hi = [p[1]["undetected_error_ci"][1] for p in points]
            line, = ax.plot(xs, ys, marker="o", label=card["defence"])
            ax.fill_between(xs, lo, hi, color=line.get_color(), alpha=0.15)
    ax.set(xscale="log", xlabel="stealth_ramp rate r (m/s)", ylabel="undetected error, m (median, 95 % bootstrap)",
           title="Undetected error against the attack's rate")
    ax.legend(fontsize=8)
    fig.tight_layout()
    images.append(_png(fig))
    plt.close(fig)
    return images


def _html(cards: list[dict], text: str) -> str:
    """The page: the plots, then the Markdown's tables rendered as HTML tables (Python-Markdown)."""
    import markdown

    images = "".join(f'<img alt="plot" src="data:image/png;base64,{png}">' for png in _plots(cards))
    body = markdown.markdown(html.escape(text, quote=False), extensions=["tables"])
    return ("<!doctype html><html><head><meta charset='utf-8'><title>racf scorecard</title>"
            "<style>body{font-family:sans-serif;max-width:1100px;margin:auto}img{max-width:48%}"
            "table{border-collapse:collapse;margin:1em 0}th,td{border:1px solid #ccc;padding:2px 8px;"
            "text-align:left}th{background:#f3f3f3}</style></head><body>" + images + body + "</body></html>\n")


def write_scorecard(cards: list[dict], out: Path) -> dict[str, Path]:
    """Writes ``scorecard.json``, ``scorecard.md`` and ``scorecard.html`` under ``out``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    quick = any(c["quick"] for c in cards)
    head = ["# racf scorecard" + (" (QUICK battery: small N, not for reporting)" if quick else ""), ""]
    markdown = "\n".join(head + [card_markdown(c) for c in cards])
    return {"json": atomic_write(out / "scorecard.json", strict_json({"cards": cards})),
            "md": atomic_write(out / "scorecard.md", markdown),
            "html": atomic_write(out / "scorecard.html", _html(cards, markdown))}
