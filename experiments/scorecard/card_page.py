"""One defence's card as a page worth sharing: its headline first, beside raw depth's and the best
on the board; then each section under its own heading, every rate drawn as a bar with its interval,
its N, raw's value and the best's. ``racf scorecard`` writes it as ``card-<defence>.html`` (with the
plots under their sections), and the results site shows each stored card the same way
(``docs/results/cards/``).

"The best" of a row is the other card, on the same battery, whose value is best in that row; a
row nobody else has shows a dash.
"""

from __future__ import annotations

import html

from racf.experiments.scorecard.headline import HEADLINE_COLUMNS, headline
from racf.experiments.scorecard.rows import card_rows

__all__ = ["card_fragment", "card_document", "CARD_CSS"]

#: Measures whose values are shares in [0, 1]: drawn as bars.
_SHARES = ("SCR", "collision-free", "needless", "TPR", "FPR", "AUROC", "driving score", "route completion",
           "unchanged share", "collision rate")

CARD_CSS = """
table.racf-card-table{border-collapse:collapse;margin:.4em 0 1.2em;width:100%;font-size:.9em}
table.racf-card-table th,table.racf-card-table td{border-bottom:1px solid #ddd;padding:3px 6px;text-align:left;
 vertical-align:top}
table.racf-card-table td:first-child{width:30%}
table.racf-card-table td.num{white-space:nowrap}
table.racf-card-table small{color:#444}
.racf-bar{position:relative;display:inline-block;width:80px;height:11px;background:#e6e6e6;vertical-align:middle;
 margin-right:6px;border-radius:2px}
.racf-bar>span{position:absolute;left:0;top:0;bottom:0;background:#4a7ebb;border-radius:2px}
.racf-bar>i{position:absolute;top:4.5px;height:2px;background:#111}
.racf-quick{background:#fff3cd;border:1px solid #e0b84c;padding:.5em .8em;border-radius:4px}
.racf-unplotted{color:#555;font-style:italic}
"""


def _is_share(measure: str, value, interval) -> bool:
    inside = value is not None and 0.0 <= value <= 1.0 and (not interval or interval[0] is None
                                                            or 0.0 <= interval[0] <= interval[1] <= 1.0)
    return inside and any(measure.startswith(s) or s in measure for s in _SHARES)


def _value(measure: str, value, interval, digits: int = 3) -> str:
    if value is None:
        return "-"
    text = f"{value:,.0f}" if measure == "trainable" else f"{value:.{digits}f}"
    bounds = (f"[{interval[0]:.{digits}f}, {interval[1]:.{digits}f}]"
              if interval and interval[0] is not None else "")
    shown = f"<b>{html.escape(text)}</b>" + (f" <small>{bounds}</small>" if bounds else "")
    if not _is_share(measure, value, interval):
        return shown
    whisker = ""
    if bounds:
        whisker = f'<i style="left:{100 * interval[0]:.1f}%;width:{100 * (interval[1] - interval[0]):.1f}%"></i>'
    return (f'<span class="racf-bar" role="img" aria-label="{html.escape(f"{text} {bounds}".strip(), quote=True)}">'
            f'<span style="width:{100 * value:.1f}%"></span>{whisker}</span>{shown}')


def _values(card: dict) -> dict[tuple[str, str, str], float]:
    """A card's values by (section, row, measure), the ones it has."""
    return {(s, r, m): v for s, r, m, v, _, _, _ in card_rows(card) if v is not None}


def _best(key, hib: bool, others: dict[str, dict]) -> tuple[str, float] | None:
    """The other card best in row ``key`` (``others``: each other defence's ``_values``)."""
    if key[2].startswith("undetected error"):  # no contest: raw's is small where the attack hides the depth
        return None
    found = [(defence, values[key]) for defence, values in others.items() if key in values]
    if not found:
        return None
    return max(found, key=lambda dv: dv[1] if hib else -dv[1])


def _headline_value(key: str, value) -> str:
    """One headline cell: a count as a number, a rate as a bar with its interval (and its row)."""
    if value is None:
        return "-"
    if key == "trainable":
        return f"{value:,}"
    return _value("SCR", value.value, value.ci, 2) + (f"<br><small>{html.escape(value.row)}</small>" if value.row else "")


def _score(value) -> float:
    return value if isinstance(value, int) else value.value


def _headline_rows(card: dict, raw: dict | None, others: list[dict]) -> list[str]:
    mine = headline(card)
    theirs = {c["defence"]: headline(c) for c in others}
    raw_h = headline(raw) if raw is not None else None
    beside = raw_h is not None and card["defence"] != "raw"
    out = ['<table class="racf-card-table racf-headline"><thead><tr><th>headline</th><th><code>'
           + html.escape(card["defence"]) + "</code></th>" + ("<th><code>raw</code></th>" if beside else "")
           + "<th>best other</th></tr></thead><tbody>"]
    for key, label, hib in HEADLINE_COLUMNS:
        value = mine.get(key)
        if value is None:
            continue
        ranked = [(name, h.get(key)) for name, h in theirs.items() if h.get(key) is not None]
        best = max(ranked, key=lambda nv: _score(nv[1]) if hib else -_score(nv[1]), default=None)
        best_text = "-" if best is None else f"<code>{html.escape(best[0])}</code> {_headline_value(key, best[1])}"
        raw_cell = f"<td>{_headline_value(key, raw_h.get(key))}</td>" if beside else ""
        out.append(f"<tr><td>{html.escape(label)}</td><td>{_headline_value(key, value)}</td>{raw_cell}"
                   f"<td>{best_text}</td></tr>")
    return out + ["</tbody></table>"]


def card_fragment(card: dict, others: list[dict] = (), plots: dict[str, list[str]] | None = None) -> str:
    """The card as HTML (no page around it): ``others`` are other defences' cards on the same
    battery (raw's among them, if any); ``plots`` are HTML snippets to put under a section."""
    others = [c for c in others if c["defence"] != card["defence"] and c["battery"] == card["battery"]]
    raw = next((c for c in others if c["defence"] == "raw"), None)
    out = ['<div class="racf-card" markdown="0">']
    if card["quick"]:
        out.append('<p class="racf-quick"><b>Quick battery</b>: a few episodes a row, for development; its '
                   "intervals are wide, and it is not for reporting.</p>")
    out.append(f"<p>Battery <code>{html.escape(card['battery'])}</code>, version <code>{html.escape(card['version'])}"
               f"</code>, sensor profile <code>{html.escape(card['sensor_profile'])}</code>. Intervals are 95 % "
               "(Wilson for rates, bootstrap otherwise); a bar is the value, its black line the interval.</p>")
    out += _headline_rows(card, raw, others)
    sections: dict[str, list] = {}
    for row in card_rows(card):
        sections.setdefault(row[0], []).append(row)
    beside = raw is not None
    raw_rows = _values(raw) if beside else {}
    other_rows = {c["defence"]: _values(c) for c in others}  # each other card's rows, read once
    for section, rows in sections.items():
        out.append(f"<h2>{html.escape(section.capitalize())}</h2>")
        out.append('<table class="racf-card-table"><thead><tr><th>row</th><th>measure</th><th>value [95 % CI]</th>'
                   "<th>N</th>" + ("<th><code>raw</code></th>" if beside else "") + "<th>best other</th></tr></thead><tbody>")
        for s, r, m, v, interval, n, hib in rows:
            key = (s, r, m)
            raw_cell = (f'<td class="num">{_value(m, raw_rows[key], None) if key in raw_rows else "-"}</td>'
                        if beside else "")
            best = _best(key, hib, other_rows)
            best_cell = "-" if best is None else f"<code>{html.escape(best[0])}</code> {_value(m, best[1], None)}"
            out.append(f"<tr><td>{html.escape(r)}</td><td>{html.escape(m)}</td><td class=\"num\">{_value(m, v, interval)}</td>"
                       f"<td>{n if n is not None else '-'}</td>{raw_cell}<td class=\"num\">{best_cell}</td></tr>")
        out.append("</tbody></table>")
        out += (plots or {}).get(section, [])
    penalties = ", ".join(f"{k.replace('_', ' ')} x {v}" for k, v in card["penalties"].items())
    out.append(f"<p>Driving-score penalties: {html.escape(penalties)}.</p></div>")
    return "\n".join(out)


def card_document(card: dict, others: list[dict] = (), plots: dict[str, list[str]] | None = None) -> str:
    """The card as a page of its own (``racf scorecard``'s ``card-<defence>.html``)."""
    title = f"{card['defence']} on {card['battery']}"
    return ("<!doctype html><html lang='en'><head><meta charset='utf-8'>"
            "<meta name='viewport' content='width=device-width, initial-scale=1'>"
            f"<title>racf card: {html.escape(title)}</title><style>body{{font-family:system-ui,sans-serif;"
            "max-width:1100px;margin:1em auto;padding:0 1em;line-height:1.4}img{max-width:100%}" + CARD_CSS
            + f"</style></head><body><h1>racf card: <code>{html.escape(card['defence'])}</code> on "
            f"<code>{html.escape(card['battery'])}</code></h1>\n" + card_fragment(card, others, plots)
            + "\n</body></html>\n")
