"""The leaderboard at a glance, as HTML (inside the site's Markdown page, or a scorecard's own page):
per battery, one line per defence with its headline (sortable by any column: ``assets/board.js``),
then a heatmap of the battery's rows against the defences, each cell coloured by its rate with its
interval beneath, a row's N beside its title and everything on hover. A defence's name leads to its
card page (``href``: ``cards/<battery>-<defence>.md``, which GitHub follows; the site's build turns
these links of the board's HTML into its ``.html`` pages, as mkdocs does for Markdown's: docs/hooks.py).

The colour says how good a value is (green good, red bad), whichever way its measure points; the
numbers stay in the cell, so the colour is never the only carrier (and the heatmap reads in grey).
"""

from __future__ import annotations

import html
from pathlib import Path
from typing import Callable

from racf.experiments.scorecard.headline import HEADLINE_COLUMNS, Rate, headline, row_rates

__all__ = ["board_html", "card_page_name", "heat_colour", "column_heads", "best_rows", "BOARD_JS"]


def card_page_name(battery: str, defence: str) -> str:
    """The card page of a defence on a battery, relative to ``docs/results/``."""
    return f"cards/{battery}-{defence}.md"


def heat_colour(value: float, higher_is_better: bool) -> str:
    """A background from red (bad) through amber to green (good) for a rate in [0, 1]."""
    good = min(max(value if higher_is_better else 1.0 - value, 0.0), 1.0)
    return f"hsl({round(120 * good)}, 70%, {round(88 - 10 * good)}%)"


def _interval(rate: Rate, digits: int = 2) -> str:
    return f"[{rate.ci[0]:.{digits}f}, {rate.ci[1]:.{digits}f}]" if rate.ci else ""


def _rate_cell(rate: Rate | None, higher_is_better: bool, what: str, note: str = "", show_n: bool = True) -> str:
    """A rate's cell: coloured, the value, its interval beneath (and N, unless the table says it
    elsewhere), all of it on hover."""
    if rate is None:
        return '<td data-sort="">-</td>'
    hover = html.escape(f"{what}: {rate.value:.3f} {_interval(rate, 3)}, N {rate.n}", quote=True)
    extra = f"<br><small>{html.escape(note)}</small>" if note else ""
    n = f" N {rate.n}" if show_n else ""
    return (f'<td data-sort="{rate.value:.6f}" title="{hover}" style="background:{heat_colour(rate.value, higher_is_better)}">'
            f'<b>{rate.value:.2f}</b><br><small>{_interval(rate)}{n}</small>{extra}</td>')


#: How a measure reads in a column's head.
_MEASURE_WORDS = {"SCR": "stop compliance", "needless stop": "needless stops"}


def column_heads(cards: list[dict]) -> dict[str, str]:
    """What each headline column holds on this battery, for its head: the measures its rows give
    (stop compliance, collision-free, ...) and which way is better."""
    kinds: dict[str, list[str]] = {"worst": [], "attacked": [], "clean": [], "needless": []}
    for card in cards:
        for _, _, measure, _, higher, attacked in row_rates(card):
            where = ("worst", "attacked") if higher and attacked else ("clean",) if higher else ("needless",)
            for key in where:
                word = _MEASURE_WORDS.get(measure, measure)
                if word not in kinds[key]:
                    kinds[key].append(word)
    heads = {key: ", ".join(words) for key, words in kinds.items() if words}
    heads["driving"] = "mean over the rows the criteria judge, by N"
    heads["trainable"] = "the defence's own, frozen ones aside"
    return heads


def best_rows(heads: list, columns) -> dict[str, str]:
    """Per column, the defence with the best value (the higher or lower, as the column reads; a tie goes
    to the tighter side of the interval, then to the larger N): one mark a column that two or more
    defences fill."""
    best = {}
    for key, _, hib in columns:
        def rank(h):
            v = h.get(key)
            if key == "trainable":
                return (-v if not hib else v,) if v is not None else None
            if v is None:
                return None
            edge = (v.ci[0] if hib else -v.ci[1]) if v.ci else 0.0
            return ((v.value if hib else -v.value), edge, v.n)
        ranked = [(rank(h), h.defence) for h in heads if rank(h) is not None]
        if len(ranked) > 1:  # a lone value is no one's best
            best[key] = max(ranked)[1]
    return best


def _head(label: str, what: str | None, hib: bool) -> str:
    arrow = "higher is better &uarr;" if hib else "lower is better &darr;"
    sub = f"{html.escape(what)}; {arrow}" if what else arrow
    return f'<th title="click to sort">{html.escape(label)}<br><small class="racf-measure">{sub}</small></th>'


def _headline_table(cards: list[dict], battery: str, href) -> list[str]:
    heads = [headline(c) for c in cards]
    submitted = {c["defence"]: bool(c.get("submitted")) for c in cards}
    columns = [(key, label, hib) for key, label, hib in HEADLINE_COLUMNS
               if any(h.get(key) is not None for h in heads)]
    what = column_heads(cards)
    best = best_rows(heads, columns)
    out = ['<table class="racf-board racf-sortable">', "<thead><tr><th>defence</th>"
           + "".join(_head(label, what.get(key), hib) for key, label, hib in columns) + "</tr></thead>",
           "<tbody>"]
    for h in sorted(heads, key=lambda h: -(h.worst.value if h.worst else -1)):
        name = html.escape(h.defence)
        mark = " <small>submitted</small>" if submitted.get(h.defence) else ""
        cells = [f'<td data-sort="{name}">{_name(h.defence, battery, href)}{mark}</td>']
        for key, label, hib in columns:
            value = h.get(key)
            if key == "trainable":
                cells.append(f'<td data-sort="{value if value is not None else ""}">'
                             f'{"-" if value is None else f"{value:,}"}</td>')
            elif key == "worst" and value is not None:
                cells.append(_rate_cell(value, hib, f"{label} ({value.row})", note=str(value.row)))
            else:
                cells.append(_rate_cell(value, hib, label))
            if best.get(key) == h.defence:
                cells[-1] = cells[-1].replace("<td ", '<td class="racf-best" ', 1).replace(
                    "</td>", ' <span class="racf-star" title="best in this column">&#9733;</span></td>', 1)
        out.append("<tr>" + "".join(cells) + "</tr>")
    return out + ["</tbody></table>"]


def _heatmap(cards: list[dict], battery: str, href) -> list[str]:
    names = [c["defence"] for c in cards]
    grid: dict[tuple[str, str], dict[str, tuple[Rate, bool]]] = {}
    titles: dict[str, str] = {}
    for card in cards:
        for key, title, measure, rate, hib, _ in row_rates(card):
            grid.setdefault((key, measure), {})[card["defence"]] = (rate, hib)
            titles[key] = title
    head = "".join(f"<th>{_name(n, battery, href)}</th>" for n in names)
    out = ['<table class="racf-heatmap">', f"<thead><tr><th>row</th><th>N</th><th>measure</th>{head}</tr></thead>",
           "<tbody>"]
    spans: dict[str, int] = {}  # a row's title stands once, across its measures
    for key, _ in grid:
        spans[key] = spans.get(key, 0) + 1
    shown = set()
    for (key, measure), cells in grid.items():
        counts = sorted({rate.n for rate, _ in cells.values()})
        row = [] if key in shown else [
            f'<td class="racf-row" rowspan="{spans[key]}" title="{html.escape(key, quote=True)}">'
            f"{html.escape(titles[key])}</td>",
            f'<td rowspan="{spans[key]}">{"/".join(map(str, counts))}</td>']
        shown.add(key)
        row.append(f"<td>{html.escape(measure)}</td>")
        for name in names:  # N stands once a row, beside its title (every defence runs the same episodes)
            rate, hib = cells.get(name, (None, True))
            row.append(_rate_cell(rate, hib, f"{name}, {measure}", show_n=False))
        out.append("<tr>" + "".join(row) + "</tr>")
    return out + ["</tbody></table>"]


def _name(defence: str, battery: str, href) -> str:
    code = f"<code>{html.escape(defence)}</code>"
    link = None if href is None else href(battery, defence)
    return code if link is None else f'<a href="{html.escape(link, quote=True)}">{code}</a>'


def board_html(cards: list[dict], battery: str,
               href: Callable[[str, str], str | None] | None = card_page_name) -> str:
    """A battery's board: the sortable headline table, then the heatmap (one HTML block each).
    ``href(battery, defence)`` gives the link of a defence's card (None: no links)."""
    from racf.experiments.scorecard.board_notes import coincidence_note, commit_note

    notes = [note for note in (_driving_note(cards), commit_note(cards),
                               coincidence_note(cards, battery, _cells)) if note]
    return "\n".join(["<div class=\"racf-board-wrap\" markdown=\"0\">", *_headline_table(cards, battery, href),
                      "</div>", "", *[f"{note}\n" for note in notes],
                      "<div class=\"racf-heatmap-wrap\" markdown=\"0\">", *_heatmap(cards, battery, href), "</div>"])


def _cells(card: dict) -> tuple:
    """Every number the board shows of a card (its headline and its rows), to find two that coincide."""
    h = headline(card)
    return (tuple(None if h.get(k) is None else getattr(h.get(k), "value", h.get(k)) for k, _, _ in HEADLINE_COLUMNS),
            tuple((key, measure, round(rate.value, 9), rate.n) for key, _, measure, rate, _, _ in row_rates(card)))


def _driving_note(cards: list[dict]) -> str:
    """Why a battery's board has no driving score, where it has none."""
    if any(headline(c).driving is not None for c in cards):
        return ""
    return ("**No driving score** on this battery: its cards were made before a card carried one for every row "
            "its criteria judge (a card made now has it: `racf scorecard` again).")


#: The board's sorting script (the site loads it as ``javascripts/board.js``; a scorecard's page inlines it).
BOARD_JS = Path(__file__).with_name("assets") / "board.js"
