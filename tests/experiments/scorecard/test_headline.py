"""A card's headline: the worst attacked row, rates pooled over rows of one kind with Wilson
intervals, needless stops and hard brakes, and nothing where the battery has no such row."""

import pytest
from hypothesis import given, strategies as st

from racf.experiments.scorecard.headline import Rate, headline, row_rates


def sign_row(title, scr, n=60):
    return {"title": title, "scr": scr, "scr_ci": [max(scr - 0.1, 0), min(scr + 0.1, 1)], "n": n}


def card(battery="racf-5", **rows):
    return {"defence": "d", "battery": battery, "closed_loop": rows, "drives": {},
            "cost": {"parameters": {"trainable": 917, "from": "declared"}}}


def test_the_worst_attacked_row_and_the_pooled_rates_come_from_the_battery_s_own_rows():
    needless = {"title": "phantom", "scr": None, "scr_ci": [None, None], "n": 60, "n_needless": 60,
                "measures": [{"measure": "needless_stop, share (existence)", "value": 0.25, "ci": [0.15, 0.37],
                              "n": 60, "higher_is_better": False}]}
    h = headline(card(mapped_clean=sign_row("clean", 1.0), mapped_sticker=sign_row("sticker", 0.5),
                      temporary_sticker=sign_row("temporary", 0.25), phantom=needless))
    assert (h.worst.value, h.worst.row) == (0.25, "temporary_sticker")
    assert (h.attacked.k, h.attacked.n) == (45, 120) and h.attacked.ci[0] < 45 / 120 < h.attacked.ci[1]
    assert (h.clean.k, h.clean.n) == (60, 60)  # mapped_clean is no attacked row of racf-5
    assert (h.needless.k, h.needless.n) == (15, 60) and h.driving is None and h.trainable == 917


def test_a_following_row_gives_collision_free_and_needless_hard_brakes():
    row = {"title": "patch", "n": 60, "n_following": 60, "scr": None, "collision_free": 0.9,
           "collision_free_ci": [0.8, 0.95], "needless_hard_brake": 0.1, "needless_hard_brake_ci": [0.05, 0.2]}
    measures = [(m, hib) for _, _, m, _, hib, _ in row_rates(card("racf-6", following_patch=row))]
    assert measures == [("collision-free", True), ("needless hard brake", False)]
    h = headline(card("racf-6", following_patch=row))
    assert h.worst.value == 0.9 and h.needless.value == pytest.approx(0.1) and h.clean is None


@given(st.lists(st.tuples(st.integers(1, 100), st.floats(0, 1)), min_size=1, max_size=8))
def test_a_pooled_rate_lies_between_its_rows_and_inside_its_interval(rows):
    rates = [Rate.of(round(v * n) / n, None, n) for n, v in rows]
    pooled = Rate.pooled(rates)
    assert min(r.value for r in rates) - 1e-9 <= pooled.value <= max(r.value for r in rates) + 1e-9
    assert pooled.ci[0] <= pooled.value <= pooled.ci[1] and pooled.n == sum(n for n, _ in rows)
