"""The existence results page (``docs/results/existence.md``): every defence's ``racf-5`` card side by
side (SCR where a sign stands, the needless-stop rate where none does), the driving score those
rates give, and the issue's claims checked against the stored numbers."""

from __future__ import annotations

import json
from pathlib import Path

from racf.experiments.pages.results_format import meta_lines, missing, page_head, rate

__all__ = ["existence_markdown", "EXISTENCE_RESULT", "EXISTENCE_COMMAND"]

#: The stored result the page reads, and the command that makes it.
EXISTENCE_RESULT = "scorecard-racf-5"
EXISTENCE_COMMAND = "racf scorecard --defence vote odca detectors_or map_only raw ekf --battery racf-5 --json"
#: The defences in the order the page shows them (any other stored card follows).
_ORDER = ("vote", "odca", "detectors_or", "map_only", "raw", "ekf")
#: The driving score's factors (CARLA's coefficients; a needless stop: ``NEEDLESS_STOP_PENALTY``).
_RAN, _NEEDLESS = 0.80, 0.70


def _cell(row: dict) -> tuple[str, float | None, list | None, int]:
    """(measure, value, interval, N) of one card row: SCR, or the needless-stop rate where no sign stands."""
    if row.get("scr") is not None:
        return "SCR", row["scr"], row["scr_ci"], row["n"]
    needless = next((m for m in row.get("measures", []) if m["measure"].startswith("needless_stop")), None)
    if needless is None:
        return "needless", None, None, row["n"]
    return "needless", needless["value"], needless["ci"], needless["n"]


def _score(measure: str, value: float | None) -> str:
    """The mean driving score the rate implies (1, x 0.80 for a real sign run, x 0.70 for a needless stop)."""
    if value is None:
        return "-"
    return f"{value + (1 - value) * _RAN:.3f}" if measure == "SCR" else f"{1 - value * (1 - _NEEDLESS):.3f}"


def existence_markdown(root: Path) -> str:
    lines = page_head(
        "Existence: whether a sign stands, against a map that can be wrong",
        "Battery `racf-5` ([concepts](../concepts/existence.md)): stop-sign approaches in the `stale_map` "
        "scenario, N 60 a row, episode *i* at sign *i* mod 4 at a speed drawn in [1, 2] m/s from its index "
        "(paired across defences). `odca` is detector-only (what every defence did before); `detectors_or` and "
        "`map_only` are the declared baselines; `vote` is RACF's existence vote with ODCA's distance. Where a "
        "sign stands the cell is SCR; where none stands (a removed sign, a phantom) it is the needless-stop "
        "rate (lower is better).")
    path = root / f"{EXISTENCE_RESULT}.json"
    if not path.exists():
        return "\n".join(lines + missing(EXISTENCE_RESULT, EXISTENCE_COMMAND))
    data = json.loads(path.read_text())
    cards = {c["defence"]: c for c in data["cards"]}
    names = [n for n in _ORDER if n in cards] + sorted(set(cards) - set(_ORDER))
    lines += meta_lines(data["meta"])
    from racf.experiments.scorecard.battery import BATTERIES

    stored = list(cards[names[0]]["closed_loop"])
    order = [row.key for row in BATTERIES["racf-5"].loop]
    keys = sorted(stored, key=lambda k: order.index(k) if k in order else len(order))  # the battery's order
    lines += ["| row | measure | " + " | ".join(f"`{n}`" for n in names) + " |", "|---|---|" + "---|" * len(names)]
    scores = ["| row | " + " | ".join(f"`{n}`" for n in names) + " |", "|---|" + "---|" * len(names)]
    for key in keys:
        title = cards[names[0]]["closed_loop"][key]["title"]
        cells, score = [], []
        measure = "SCR"
        for name in names:
            row = cards[name]["closed_loop"].get(key)
            if row is None:
                cells.append("-")
                score.append("-")
                continue
            measure, value, interval, n = _cell(row)
            cells.append(f"{rate(value, interval)} ({n})" if value is not None else "-")
            score.append(_score(measure, value))
        label = "SCR" if measure == "SCR" else "needless stops"
        lines.append(f"| {title} (`{key}`) | {label} | " + " | ".join(cells) + " |")
        scores.append(f"| `{key}` | " + " | ".join(score) + " |")
    lines += ["", "N in brackets; 95 % Wilson intervals.", "",
              "## The driving score", "",
              f"The mean driving score each rate gives: 1 for the right thing, x {_RAN} for a real sign not "
              f"stopped at, x {_NEEDLESS} for a needless stop. CARLA's leaderboard has no needless-stop "
              "infraction; its nearest, failing to keep the traffic's minimum speed, weighs x 0.70: a stop in a "
              "running lane with nothing to stop for is the rear-end hazard and the delay a phantom attack aims "
              "at, and it costs more than running a sign (x 0.80), as CARLA's minimum-speed penalty does.", "",
              *scores, "", *_claims(cards)]
    return "\n".join(lines)


def _claims(cards: dict) -> list[str]:
    """The issue's claims, each checked against the stored rows."""
    def value(name: str, key: str):
        row = cards.get(name, {}).get("closed_loop", {}).get(key)
        return None if row is None else _cell(row)

    def text(name: str, key: str) -> str:
        got = value(name, key)
        return "not stored" if got is None or got[1] is None else f"{rate(got[1], got[2])} (N {got[3]})"

    def holds(name: str, key: str, test) -> str:
        got = value(name, key)
        return "not stored" if got is None or got[1] is None else ("holds" if test(got[1]) else "**not met**")

    lines = ["## The claims", "", "| claim | measured | verdict |", "|---|---|---|"]
    for key, what in (("mapped_sticker", "the 0.6 sticker"), ("mapped_sticker_top", "the 0.4 top-edge sticker")):
        lines.append(f"| mapped signs, {what} up from the start: SCR >= 0.95 with the vote | vote {text('vote', key)}; "
                     f"detector-only {text('odca', key)} | {holds('vote', key, lambda v: v >= 0.95)} |")
    lines.append("| the strong patch from first sight, before the track is confirmed: SCR >= 0.95 with the vote | "
                 f"vote {text('vote', 'mapped_early_patch')}; detector-only {text('odca', 'mapped_early_patch')}; "
                 f"map-only {text('map_only', 'mapped_early_patch')} | "
                 f"{holds('vote', 'mapped_early_patch', lambda v: v >= 0.95)} |")
    for key, what in (("removed", "removed mapped signs"), ("phantom", "phantoms")):
        lines.append(f"| {what}: needless-stop rate <= 0.05 with the vote | vote {text('vote', key)}; map-only "
                     f"{text('map_only', key)}; detector-only {text('odca', key)} | "
                     f"{holds('vote', key, lambda v: v <= 0.05)} |")
    vote_t, odca_t = value("vote", "temporary_clean"), value("odca", "temporary_clean")
    same = ("holds" if vote_t and odca_t and vote_t[1] is not None and odca_t[1] is not None and vote_t[1] >= 0.98
            and vote_t[2][0] <= odca_t[2][1] and odca_t[2][0] <= vote_t[2][1] else "**not met**")
    lines.append(f"| unmapped temporary signs, clean: SCR >= 0.98, within detector-only's interval | vote "
                 f"{text('vote', 'temporary_clean')}; detector-only {text('odca', 'temporary_clean')} | {same} |")
    lines.append("| unmapped signs with a sticker: reported for every defence | see the table | reported |")
    lines.append("| the sign's depth and LiDAR returns moved away at 3 m/s (with the sticker): SCR >= 0.9 with the "
                 f"vote's static-world check | vote {text('vote', 'mapped_sticker_spoof')}; detector-only "
                 f"{text('odca', 'mapped_sticker_spoof')} | {holds('vote', 'mapped_sticker_spoof', lambda v: v >= 0.9)} |")
    white = [(key, value("vote", key)) for key in ("mapped_sticker_blind", "mapped_sticker_spoof")]
    white = [(k, v) for k, v in white if v is not None and v[1] is not None]
    if white:
        key, worst = min(white, key=lambda kv: kv[1][1])
        lines.append(f"| the strongest white-box attack on the vote | `{key}`: vote {rate(worst[1], worst[2])} "
                     f"(N {worst[3]}) | reported |")
    return lines + ["", "## What would do better", "",
                    "- **A sticker that blinds both detectors on a sign the map does not list** leaves no semantic "
                    "witness at all: the vote, like every defence, needs something that says *stop sign*. A "
                    "class-agnostic witness (a free-standing plate of a stop sign's size and height beside the lane) "
                    "would stand in, at the price of stopping for any such plate.",
                    "- **A spoof that moves the plate's depth and its LiDAR returns together** is caught while it "
                    "moves: the static-world check carries what the depth shows at the map's plate from frame to "
                    "frame by the car's own motion, and a depth that runs away from it is outvoted. A spoof that "
                    "holds a constant offset from before the sign comes into view never moves while the car looks: "
                    "it reads as a sign that is gone. A plate-shaped hole that reads further than what surrounds it "
                    "is the witness that would catch it.",
                    "- **A sticker optimised against both detectors at once** (the same EOT over the approach) is not "
                    "measured yet: the classical detector has no gradient, so it needs a differentiable stand-in.", ""]
