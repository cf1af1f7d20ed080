"""A card's headline: the few numbers a reader looks for first, each a rate with its N and
Wilson interval, pooled over the battery's rows of one kind.

- ``worst``: the lowest rate over the attacked rows (SCR where the stop rule judged the row, else
  the share its criteria declare for a card, ``Criterion.card``: collision-free, say), and which row it is;
- ``attacked``: that rate pooled over every attacked row (successes over episodes);
- ``clean``: the same over the rows with no attack;
- ``needless``: the rows' costs, pooled: needless stops (no sign stands) and any share a criterion
  declares lower-is-better (needless hard brakes, say);
- ``driving``: the mean driving score (the criteria's penalties, CARLA's way) over every row that has
  one, drives included, each row weighted by its N; ``trainable``: the defence's trainable parameters.

A measure the battery has no row for is None. The board (``racf.experiments.scorecard.board``) and
the card page (``racf.experiments.scorecard.card_page``) read it.
"""

from __future__ import annotations

from dataclasses import dataclass

from racf.stats import wilson_interval

__all__ = ["Rate", "Headline", "headline", "row_rates", "HEADLINE_COLUMNS"]

#: (key, label, higher is better) of the headline's columns, in the order a reader wants them.
HEADLINE_COLUMNS = (("worst", "worst attacked row", True), ("attacked", "attacked rows, pooled", True),
                    ("clean", "clean rows, pooled", True), ("needless", "needless stops or hard brakes", False),
                    ("driving", "driving score", True), ("trainable", "trainable parameters", False))


@dataclass(frozen=True)
class Rate:
    """A rate of ``k`` in ``n`` (or a mean, where ``k`` is None) with its 95 % interval."""

    value: float
    ci: tuple[float, float] | None
    n: int
    k: int | None = None
    row: str | None = None  # the row it comes from, where it is one row's

    @classmethod
    def of(cls, value: float, ci, n: int, row: str | None = None) -> "Rate":
        return cls(float(value), tuple(ci) if ci and ci[0] is not None else None, int(n), round(value * n), row)

    @classmethod
    def pooled(cls, rates: list["Rate"]) -> "Rate | None":
        if not rates:
            return None
        k, n = sum(r.k for r in rates), sum(r.n for r in rates)
        return cls(k / n, wilson_interval(k, n), n, k)


@dataclass(frozen=True)
class Headline:
    defence: str
    battery: str
    worst: Rate | None
    attacked: Rate | None
    clean: Rate | None
    needless: Rate | None
    driving: Rate | None
    trainable: int | None

    def get(self, key: str):
        return getattr(self, key)


def row_rates(card: dict) -> list[tuple[str, str, str, Rate, bool, bool]]:
    """Each closed-loop row's headline measure: (key, title, measure, rate, higher is better,
    attacked). A row gives its SCR or collision-free rate, and its needless stops or hard brakes
    where it counts them; rows in the battery's order."""
    from racf.experiments.scorecard.battery import BATTERIES

    from racf.experiments.scorecard.card_format import current_card

    card = current_card(card)
    battery = BATTERIES.get(card["battery"].removesuffix("-quick"))
    rows = {r.key: r for r in battery.rows()} if battery else {}
    order = list(rows)
    out = []
    for key, r in sorted(card["closed_loop"].items(), key=lambda kv: order.index(kv[0]) if kv[0] in order else 99):
        attacked = rows[key].attacked if key in rows else True
        declared = r.get("headline", [])  # the row's criteria's own measures (Criterion.card)
        for m in declared:
            out.append((key, r["title"], m["measure"], Rate.of(m["value"], m["ci"], m["n"], key), m["higher_is_better"],
                        attacked))
        if not declared and r.get("scr") is not None:
            out.append((key, r["title"], "SCR", Rate.of(r["scr"], r["scr_ci"], r["n"], key), True, attacked))
        for m in r.get("measures", []):
            if m["measure"].startswith("needless") and m["value"] is not None:
                out.append((key, r["title"], "needless stop", Rate.of(m["value"], m["ci"], m["n"], key), False,
                            attacked))
    return out


def headline(card: dict) -> Headline:
    """The card's headline (see the module's docstring)."""
    rows = row_rates(card)
    # A row's primary measure is one where higher is better (SCR, or its criteria's kept share); one where
    # lower is better is a cost (needless stops, needless hard brakes).
    primary = [(rate, attacked) for _, _, _, rate, higher, attacked in rows if higher]
    attacked = [rate for rate, hit in primary if hit]
    needless = [rate for _, _, _, rate, higher, _ in rows if not higher]
    scored = [r for r in (*card.get("closed_loop", {}).values(), *card.get("drives", {}).values())
              if r.get("driving_score") is not None]
    driving = None
    if scored:  # every row whose episodes the criteria judged, each weighted by its N
        n = sum(r["n"] for r in scored)
        mean = sum(r["driving_score"] * r["n"] for r in scored) / n
        driving = Rate(mean, None, n)
    return Headline(card["defence"], card["battery"], min(attacked, key=lambda r: r.value, default=None),
                    Rate.pooled(attacked), Rate.pooled([rate for rate, hit in primary if not hit]),
                    Rate.pooled(needless), driving, card.get("cost", {}).get("parameters", {}).get("trainable"))
