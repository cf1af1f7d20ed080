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
    assert 'href="cards/racf-5-vote.md"' in board and 'href="cards/racf-5-raw.md"' in heat  # GitHub's; the site's build: .html
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


def _heads_and_marks(page):
    board = page.split("racf-heatmap-wrap")[0]
    heads = re.findall(r"<th(?: [^>]*)?>(.*?)</th>", board)
    rows = re.findall(r"<tr>(.*?)</tr>", board.split("<tbody>")[1])
    return heads, [re.findall(r"<td([^>]*)>", row) for row in rows]


def test_every_head_names_its_measure_and_its_direction():
    heads, _ = _heads_and_marks(board_html(CARDS, "racf-5"))
    assert heads[0] == "defence"
    assert all("is better" in h for h in heads[1:]) and "stop compliance" in heads[1]
    assert any("lower is better" in h and "trainable" in h for h in heads)


def test_one_best_mark_a_column_on_the_better_side_whichever_way_it_points():
    from racf.experiments.scorecard.board import best_rows
    from racf.experiments.scorecard.headline import HEADLINE_COLUMNS, Rate, headline

    costly = card("costly", {"mapped_clean": 1.0, "mapped_sticker": 0.5})
    costly["cost"]["parameters"]["trainable"] = 921
    heads = [headline(c) for c in [*CARDS, costly]]
    best = best_rows(heads, HEADLINE_COLUMNS)
    assert best["worst"] == "vote" and best["trainable"] in ("raw", "vote")  # fewer parameters is better
    _, cells = _heads_and_marks(board_html([*CARDS, costly], "racf-5"))
    columns = len(cells[0])
    for i in range(1, columns):
        assert sum('class="racf-best"' in row[i] for row in cells) == 1
    # A tie on the value goes to the tighter side of the interval (lower is better: the lower upper end).
    a, b = Rate(0.1, (0.05, 0.3), 60), Rate(0.1, (0.05, 0.2), 60)
    tie = [type("H", (), {"defence": d, "get": lambda self, k, r=r: r})() for d, r in (("a", a), ("b", b))]
    assert best_rows(tie, [("needless", "x", False)]) == {"needless": "b"}
    assert best_rows(tie[:1], [("needless", "x", False)]) == {}  # a lone value is no one's best


def test_the_driving_score_is_every_judged_row_s_weighted_by_n_or_the_board_says_why_not():
    from racf.experiments.scorecard.headline import headline

    scored = card("odca", {"mapped_clean": 1.0, "mapped_sticker": 0.5})
    scored["closed_loop"]["mapped_clean"] |= {"driving_score": 1.0, "n": 60}
    scored["closed_loop"]["mapped_sticker"] |= {"driving_score": 0.6, "n": 20}
    assert headline(scored).driving.value == (60 * 1.0 + 20 * 0.6) / 80 and headline(scored).driving.n == 80
    assert "No driving score" in board_html(CARDS, "racf-5")
    assert "No driving score" not in board_html([*CARDS, scored], "racf-5")


def test_cards_from_two_commits_are_said_and_two_defences_that_coincide_are_named_with_why():
    from racf.experiments.scorecard.board_notes import coincidence_note, commit_note

    a, b = dict(CARDS[0], commit="aaaaaaa"), dict(CARDS[1], commit="bbbbbbb")
    note = commit_note([a, b])
    assert note.startswith("**Measured on 2 commits**") and "`aaaaaaa` (`raw`)" in note and "git log" in note
    assert commit_note([a, dict(a, defence="x")]) == ""
    twin = dict(CARDS[1], defence="twin")
    page = board_html([*CARDS, twin], "racf-5")
    assert "`twin` and `vote` score the same in every cell" in page and "carry no episodes" in page
    assert "`raw` and" not in page
    same = lambda c: (1,)
    racf6 = [dict(CARDS[0], defence="odca"), dict(CARDS[0], defence="vote")]
    assert "its check of the car ahead (`lead_check`) is off" in coincidence_note(racf6, "racf-6", same)
