"""A scorecard's outputs: ``scorecard.json`` (strict), ``scorecard.md`` (one card per defence,
row by row, the quick battery said once at the top), ``scorecard.html`` (the cards at a glance)
and ``card-<defence>.html`` (each card's page: ``card_page``, with its plots under their
sections: the detection ROC, or why there is none, and the undetected error against the stealth
ramp's rate); and two cards side by side."""

from __future__ import annotations

import base64
import html
import io
import json
from pathlib import Path

from racf.experiments.scorecard.rows import card_rows
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


def card_markdown(card: dict) -> str:
    lines = [f"## `{card['defence']}` on battery `{card['battery']}`", "",
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


def _img(fig, alt: str) -> str:
    return f'<img alt="{html.escape(alt, quote=True)}" src="data:image/png;base64,{_png(fig)}">'


def card_plots(card: dict) -> dict[str, list[str]]:
    """The plots of one card, by the section they belong under: the detection ROC (or why there is
    none) and the undetected error against the stealth ramp's rate (where the battery runs it)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out: dict[str, list[str]] = {}
    d = card.get("detection")
    if d:
        roc = d.get("roc") or {}
        if roc.get("fpr") and max(roc.get("tpr", [0.0])) > 0.0:
            fig, ax = plt.subplots(figsize=(5.2, 4.2))
            ax.plot(roc["fpr"], roc["tpr"], label=f"{card['defence']} (AUROC {d['auroc']:.2f})")
            ax.plot([0, 1], [0, 1], color="grey", lw=0.8, ls="--", label="chance")
            ax.set(xlabel="false-positive rate (clean steps flagged)", ylabel="true-positive rate (attacked steps flagged)",
                   title=f"Detection ROC of {card['defence']} over the closed-loop steps")
            ax.legend(fontsize=8, loc="lower right")
            fig.tight_layout()
            out["detection"] = [_img(fig, f"detection ROC of {card['defence']}")]
            plt.close(fig)
        else:
            out["detection"] = [f'<p class="racf-unplotted">No ROC to draw: <code>{html.escape(card["defence"])}'
                                "</code> never flags an attacked step, so there is no trade-off between catching "
                                "attacks and false alarms to show.</p>"]
    rates = {}
    for key in RAMP_ROWS:  # the stealth ramp at every rate the battery runs
        rates.update(card["closed_loop"].get(key, {}).get("by_rate", {}))
    points = sorted((float(r), v) for r, v in rates.items() if v.get("undetected_error_median") is not None)
    if points:
        fig, ax = plt.subplots(figsize=(5.2, 4.2))
        xs = [p[0] for p in points]
        line, = ax.plot(xs, [p[1]["undetected_error_median"] for p in points], marker="o", label=card["defence"])
        ax.fill_between(xs, [p[1]["undetected_error_ci"][0] for p in points],
                        [p[1]["undetected_error_ci"][1] for p in points], color=line.get_color(), alpha=0.15,
                        label="95 % bootstrap interval")
        ax.set(xscale="log", xlabel="stealth_ramp rate r (m/s)", ylabel="undetected error, m (median)",
               title="Undetected error against the attack's rate")
        ax.legend(fontsize=8)
        fig.tight_layout()
        out["closed loop"] = [_img(fig, "undetected error against the stealth ramp's rate")]
        plt.close(fig)
    return out


def _index_html(cards: list[dict], others: list[dict], quick: bool) -> str:
    """``scorecard.html``: the run's cards at a glance (the board), each name leading to its page."""
    from racf.experiments.scorecard.board import BOARD_JS, board_html
    from racf.experiments.scorecard.card_page import CARD_CSS

    battery = cards[0]["battery"]
    shown = cards + [c for c in others if c["battery"] == battery and c["defence"] not in {x["defence"] for x in cards}]
    mine = {c["defence"] for c in cards}  # only this run's cards have a page here
    board = board_html(shown, battery, href=lambda _, defence: f"card-{defence}.html" if defence in mine else None)
    note = ('<p class="racf-quick"><b>Quick battery</b>: a few episodes a row, for development; not for '
            "reporting.</p>") if quick else ""
    return ("<!doctype html><html lang='en'><head><meta charset='utf-8'>"
            "<meta name='viewport' content='width=device-width, initial-scale=1'><title>racf scorecard</title><style>"
            "body{font-family:system-ui,sans-serif;max-width:1200px;margin:1em auto;padding:0 1em}"
            "table{border-collapse:collapse;width:100%;font-size:.85em}th,td{padding:3px 6px;text-align:left;"
            "vertical-align:top}th{background:#f3f3f3}" + CARD_CSS + "</style></head><body>"
            f"<h1>racf scorecard: battery <code>{html.escape(battery)}</code></h1>{note}"
            "<p>Each defence's headline; its name opens its card. Green is good, red bad, whichever way a measure "
            "points; intervals are 95 % (Wilson); click a column's head to sort.</p>" + board
            + f"<script>{BOARD_JS.read_text()}</script></body></html>\n")


def write_scorecard(cards: list[dict], out: Path, others: list[dict] = ()) -> dict[str, Path]:
    """Writes ``scorecard.json``, ``scorecard.md``, ``scorecard.html`` (the cards at a glance) and
    ``card-<defence>.html`` for each card (its page, beside ``others``: raw's and other defences'
    cards on the same battery) under ``out``."""
    from racf.experiments.scorecard.card_page import card_document

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    quick = any(c["quick"] for c in cards)
    head = ["# racf scorecard" + (" (QUICK battery: small N, not for reporting)" if quick else ""), ""]
    markdown = "\n".join(head + [card_markdown(c) for c in cards])
    peers = list(cards) + [c for c in others if c["defence"] not in {x["defence"] for x in cards}]
    paths = {"json": atomic_write(out / "scorecard.json", strict_json({"cards": cards})),
             "md": atomic_write(out / "scorecard.md", markdown),
             "html": atomic_write(out / "scorecard.html", _index_html(cards, others, quick))}
    for card in cards:
        paths[f"card {card['defence']}"] = atomic_write(out / f"card-{card['defence']}.html",
                                                         card_document(card, peers, card_plots(card)))
    return paths
