"""The board at a glance: one line per defence, the worst first, each cell coloured with its value,
interval and N; the heatmap has every defence and row; names lead to the cards."""

import re

from racf.experiments.scorecard.board import board_html, heat_colour


def card(defence, scrs):
    rows = {k: {"title": f"row {k}", "scr": v, "scr_ci": [max(v - 0.1, 0), min(v + 0.1, 1)], "n": 60}
            for k, v in scrs.items()}
    return {"defence": defence, "battery": "racf-5", "closed_loop": rows, "drives": {},
            "cost": {"parameters": {"trainable": 0, "from": "declared"}}}


CARDS = [card("raw", {"mapped_clean": 1.0, "mapped_sticker": 0.25}),
         card("vote", {"mapped_clean": 1.0, "mapped_sticker": 0.98})]


def test_the_best_worst_row_comes_first_and_names_lead_to_cards():
    page = board_html(CARDS, "racf-5")
    board, heat = page.split("racf-heatmap-wrap")
    assert board.index("<code>vote</code>") < board.index("<code>raw</code>")
    assert 'href="cards/racf-5-vote.html"' in board and 'href="cards/racf-5-raw.html"' in heat
    assert 'data-sort="0.250000"' in board and "[0.15, 0.35] N 60" in board
    # Every defence and row in the heatmap, with its N and interval on hover.
    assert heat.count("<tr>") == 3 and "<td rowspan=\"1\">60</td>" in heat and 'title="vote, SCR: 0.980 [0.880, 1.000], N 60"' in heat


def test_no_links_where_asked_for_none():
    assert "href" not in board_html(CARDS, "racf-5", href=None)
    only_vote = board_html(CARDS, "racf-5", href=lambda _, d: "v.html" if d == "vote" else None)
    assert only_vote.count('href="v.html"') == 2 and "<a href" not in only_vote.split("<code>raw</code>")[0][-30:]


def test_the_colour_is_green_for_good_and_red_for_bad_whichever_way_a_measure_points():
    hue = lambda colour: int(re.match(r"hsl\((\d+)", colour).group(1))
    assert hue(heat_colour(1.0, True)) == 120 and hue(heat_colour(0.0, True)) == 0
    assert hue(heat_colour(0.0, False)) == 120 and hue(heat_colour(0.9, False)) < 20


def test_a_row_with_two_measures_is_titled_once_across_both():
    following = {"title": "the patch", "n": 60, "n_following": 60, "scr": None, "collision_free": 0.9,
                 "collision_free_ci": [0.8, 0.95], "needless_hard_brake": 0.1, "needless_hard_brake_ci": [0.05, 0.2]}
    card = {"defence": "odca", "battery": "racf-6", "closed_loop": {"following_patch": following}, "drives": {},
            "cost": {"parameters": {"trainable": 0, "from": "declared"}}}
    heat = board_html([card], "racf-6").split("racf-heatmap-wrap")[1]
    assert heat.count("the patch</td>") == 1 and 'rowspan="2" title="following_patch"' in heat
