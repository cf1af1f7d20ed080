"""The leaderboard page: the defences' scorecards at a glance, one board a battery (the newest
first; :mod:`racf.experiments.scorecard.board`), and a page per card (:func:`card_pages`), written from
the stored cards (``docs/results/data/scorecard-<battery>.json``) and the cold run's time
(``scorecard-timing.json``) by :mod:`racf.experiments.pages.results_pages`."""

from __future__ import annotations

from functools import partial
from typing import Callable

from racf.experiments.pages.results_format import page_head as _page_head
from racf.experiments.pages.results_format import FRONT_MATTER
from racf.experiments.pages.results_format import meta_lines as _meta
from racf.experiments.pages.results_format import missing as _missing

__all__ = ["leaderboard_markdown", "card_pages", "BATTERY_TITLES"]

#: Where a battery's rows are from, for its heading.
BATTERY_TITLES = {"racf-6": "following the car ahead", "racf-5": "whether the car stops where a sign stands, and only there",
                  "racf-link": "the defence served over the link, and attacks on the link",
                  "racf-4": "stop signs, with cross-traffic", "racf-3": "stop signs, a placed sticker",
                  "racf-2": "stop signs, white-box attacks", "racf-1": "stop signs, the paper's protocol"}


def leaderboard_markdown(d) -> str:
    """The leaderboard page from the stored cards (``scorecard-<battery>``, newest battery first)
    and the cold run's time: per battery, the board at a glance (``board_html``)."""
    from racf.experiments.scorecard.board import board_html
    from racf.experiments.scorecard.battery import BATTERIES, DEFAULT_BATTERY

    lines = [*_page_head("Leaderboard: which defence holds, and where each fails"),
             "`racf scorecard --defence NAME` rates a defence, built-in or plug-in, on a fixed battery "
             "([the tutorial](../tutorials/scorecard.md) says what is in it; [submit yours](../tutorials/submit-a-card.md)). "
             "Per battery: one line per defence, its worst attacked row first (click a column's head to sort by it; "
             "a name opens the defence's card), then every row of the battery, coloured from red (bad) to green "
             "(good) whichever way its measure points, with its interval and N beneath (and on hover). "
             "A battery never changes: a new row makes a new battery, and its board stands above the older ones.", ""]
    boards = _boards(d)
    if not boards:
        return "\n".join(lines + _missing(f"scorecard-{DEFAULT_BATTERY}",
                                          "racf scorecard --defence raw ekf chronos odca chi2 cusum"))
    for name in [b for b in reversed(list(BATTERIES)) if b in boards]:
        metas, cards, submitted = boards[name]
        title = BATTERY_TITLES.get(name)
        lines += [f"## `{name}`" + (f": {title}" if title else ""), ""]
        for meta in metas:
            lines += _meta(meta)
        if submitted:
            lines += ["Submitted, each measured by its own command (its card page names it and where its code is): "
                      + ", ".join(f"`{c['defence']}`" for c in submitted) + ".", ""]
        lines += [board_html(cards + submitted, name), "", _penalties(cards + submitted), ""]
    if "scorecard-timing" in d:
        cold = d["scorecard-timing"]
        walls = ", ".join(f"`{name}` {t['wall_s'] / 60:.1f} min" for name, t in cold["cold_run"]["cards"].items())
        lines += ["", f"**Time**, from a cold run of `racf-1` with nothing stored (`{cold['meta']['command']}`, commit "
                      f"`{cold['meta']['commit']}`, {cold['meta']['machine']}): {cold['cold_run']['total_s'] / 60:.1f} "
                      f"min in all, {cold['cold_run']['includes']}; per card {walls}. The first card also computes "
                      "the offline reference (Chronos-only), which the others reuse. The cards above were then "
                      "written again from the stored episodes, which is why their own timings are short.", ""]
    return "\n".join(lines)


def _penalties(cards: list[dict]) -> str:
    penalties = cards[0]["penalties"]
    return ("Pooled rates are successes over episodes across the rows of that kind, with their Wilson interval. "
            "Driving-score penalties: " + ", ".join(f"{k.replace('_', ' ')} x {v}" for k, v in penalties.items()) + ".")


def _boards(d) -> dict[str, tuple[list[dict], list[dict], list[dict]]]:
    """Per battery: the provenance of each stored result that holds its cards, racf's own cards
    (each with its result's provenance under ``_meta``), and the submitted cards
    (``docs/results/submissions/``, beside the data folder), each marked ``submitted``."""
    from racf.experiments.scorecard.submission import load_submissions

    boards: dict = {}
    for path in sorted(d.root.glob("scorecard-*.json")):
        data = d[path.stem]
        for card in data.get("cards", []):  # a battery's cards may come from several stored results
            metas, cards, _ = boards.setdefault(card["battery"], ([], [], []))
            if not metas or metas[-1] is not data["meta"]:
                metas.append(data["meta"])
            cards.append({**card, "_meta": data["meta"]})
    for sub in load_submissions(d.root.parent / "submissions"):
        battery = sub.card["battery"]
        boards.setdefault(battery, ([], [], []))[2].append({**sub.card, "submitted": sub.submitted})
    return boards


def card_pages(root) -> dict[str, Callable[[], str]]:
    """Every stored or submitted card's page, by its path under ``docs/results/``
    (``cards/<battery>-<defence>.md``), each written when asked (the stored results read once)."""
    from racf.experiments.pages.results_format import StoredResults
    from racf.experiments.scorecard.board import card_page_name
    from racf.experiments.scorecard.submission import load_submissions

    d = StoredResults(root)
    submissions = {(s.card["battery"], s.card["defence"]): s for s in load_submissions(d.root.parent / "submissions")}
    pages = {}
    for battery, (_, cards, submitted) in _boards(d).items():
        for card in cards + submitted:
            pages[card_page_name(battery, card["defence"])] = partial(
                _card_page, card, cards + submitted, submissions.get((battery, card["defence"])))
    return pages


def _card_page(card: dict, peers: list[dict], submission) -> str:
    """One card's page: its provenance (or its submission's command and code), then the card beside ``peers``."""
    from racf.experiments.scorecard.card_page import card_fragment

    defence, battery = card["defence"], card["battery"]
    lines = [*FRONT_MATTER, f"# `{defence}` on battery `{battery}`", "",
             f"One defence's card, beside raw depth's and the best of the other defences carded on `{battery}` "
             "([the leaderboard](../leaderboard.md) sets them all side by side).", ""]
    if submission is not None:
        lines += [f"*Submitted* {submission.submitted}: measured by `{submission.command}` on racf commit "
                  f"`{card['commit']}`; its code: `{submission.code}`.", ""]
    elif card.get("_meta"):
        lines += _meta(card["_meta"])
    return "\n".join(lines + [card_fragment(card, peers), ""])
