"""The leaderboard page: the built-in defences' scorecards, one column a defence and one table a
battery (the newest first), written from the stored cards (``docs/results/data/scorecard-<battery>.json``)
and the cold run's time (``scorecard-timing.json``) by :mod:`racf.experiments.pages.results_pages`."""

from __future__ import annotations

from racf.experiments.pages.results_format import page_head as _page_head
from racf.experiments.pages.results_format import ci as _ci
from racf.experiments.pages.results_format import meta_lines as _meta
from racf.experiments.pages.results_format import missing as _missing

__all__ = ["leaderboard_markdown"]

def leaderboard_markdown(d) -> str:
    """The leaderboard page from the stored cards (``scorecard-<battery>``, newest battery first)
    and the cold run's time."""
    from racf.experiments.scorecard.battery import BATTERIES, DEFAULT_BATTERY

    lines = [*_page_head("Leaderboard: the defences on the scorecard's batteries"),
             "`racf scorecard --defence NAME` rates a defence, built-in or plug-in, on the same fixed battery "
             "([the tutorial](../tutorials/scorecard.md) says what is in it). Each column is one defence's card; "
             "its version names the code it ran (a plug-in's source included). Bold: the best value of a row "
             "where its interval does not overlap the runner-up's. A battery never changes: a new row makes a "
             "new battery, and its table stands above the older ones.", ""]
    stored = [name for name in reversed(list(BATTERIES)) if f"scorecard-{name}" in d]
    if not stored:
        return "\n".join(lines + _missing(f"scorecard-{DEFAULT_BATTERY}",
                                          "racf scorecard --defence raw ekf chronos odca chi2 cusum"))
    for name in stored:
        lines += [f"## `{name}`", ""] + _battery_table(d[f"scorecard-{name}"])
    if "scorecard-timing" in d:
        cold = d["scorecard-timing"]
        walls = ", ".join(f"`{name}` {t['wall_s'] / 60:.1f} min" for name, t in cold["cold_run"]["cards"].items())
        lines += ["", f"**Time**, from a cold run of `racf-1` with nothing stored (`{cold['meta']['command']}`, commit "
                      f"`{cold['meta']['commit']}`, {cold['meta']['machine']}): {cold['cold_run']['total_s'] / 60:.1f} "
                      f"min in all, {cold['cold_run']['includes']}; per card {walls}. The first card also computes "
                      "the offline reference (Chronos-only), which the others reuse. The cards above were then "
                      "written again from the stored episodes, which is why their own timings are short.", ""]
    return "\n".join(lines)


def _battery_table(data: dict) -> list[str]:
    """One battery's stored cards as one table."""
    from racf.experiments.scorecard.report import card_rows

    lines = []
    cards = data["cards"]
    lines += _meta(data["meta"])
    names = [c["defence"] for c in cards]
    table: dict = {}
    for card in cards:
        for section, row, measure, value, ci, n, hib in card_rows(card):
            table.setdefault((section, row, measure), {})[card["defence"]] = (value, ci, n, hib)
    lines += ["| section | row | measure | " + " | ".join(f"`{n}`" for n in names) + " |",
              "|---|---|---|" + "---|" * len(names),
              "| | | version | " + " | ".join(f"`{c['version'].rsplit('_', 1)[-1]}`" for c in cards) + " |"]
    for (section, row, measure), cells in table.items():
        # an undetected error is no contest: raw depth's is small where the attack hides the depth
        best = None if measure.startswith("undetected error m, median") and section == "closed loop" else _best(cells)
        digits = 0 if measure == "trainable" else 3
        out = []
        for name in names:
            if name not in cells or cells[name][0] is None:
                out.append("-")
                continue
            value, ci, n, _ = cells[name]
            text = f"{value:.{digits}f}{(' ' + _ci(ci, digits)) if ci and ci[0] is not None else ''}" + (
                f" ({n})" if n is not None else "")
            out.append(f"**{text}**" if name == best else text)
        lines.append(f"| {section} | {row} | {measure} | " + " | ".join(out) + " |")
    penalties = cards[0]["penalties"]
    lines += ["", "N in brackets. Driving-score penalties: " + ", ".join(f"{k.replace('_', ' ')} x {v}"
                                                                  for k, v in penalties.items()) + ".", ""]
    return lines


def _best(cells: dict) -> str | None:
    """The defence whose value beats every other's with non-overlapping intervals (None: no clear best)."""
    scored = [(name, v, ci, hib) for name, (v, ci, _, hib) in cells.items() if v is not None and ci and ci[0] is not None]
    if len(scored) < 2:
        return None
    scored.sort(key=lambda x: x[1], reverse=scored[0][3])
    (name, _, ci, hib), (_, _, ci2, _) = scored[0], scored[1]
    apart = ci[0] > ci2[1] if hib else ci[1] < ci2[0]
    return name if apart else None
