"""A card's page: the headline first, beside raw's and the best other's; every section under its
heading, shares drawn as bars with their intervals; a plot with nothing to show says why."""

import warnings

from racf.experiments.scorecard.card_page import card_document, card_fragment
from racf.experiments.scorecard.report import card_plots, write_scorecard


def card(defence, scr, quick=False, detection=None):
    return {"defence": defence, "battery": "racf-5", "quick": quick, "version": "racf 0.1.0, code x",
            "sensor_profile": "qcar2", "penalties": {"ran_stop_sign": 0.8}, "drives": {},
            "timing": {"wall_s": 1.0}, "detection": detection,
            "cost": {"parameters": {"trainable": 917 if defence != "raw" else 0, "from": "declared"}},
            "closed_loop": {"mapped_sticker": {"title": "the sticker", "scr": scr, "scr_ci": [scr / 2, scr], "n": 60}}}


def test_the_headline_comes_first_beside_raw_and_the_best_other():
    page = card_fragment(card("vote", 0.9), [card("raw", 0.2), card("odca", 0.5), card("vote", 0.1)])
    assert page.index("racf-headline") < page.index("<h2>Closed loop</h2>")
    headline = page.split("</table>")[0]
    assert "<code>raw</code>" in headline and "<code>odca</code>" in headline and "0.90" in headline
    assert 'aria-label="0.900 [0.450, 0.900]"' in page  # the bar says its value and interval
    # Raw's own card has no second raw column: only its own, in each table.
    own = card_fragment(card("raw", 0.2), [card("vote", 0.9)])
    assert own.count("<th><code>raw</code></th>") == 1 and own.count("<th><code>raw</code></th>") < page.count("<th><code>raw</code></th>")


def test_a_quick_card_says_so_once_at_the_top():
    page = card_document(card("vote", 0.9, quick=True))
    assert page.count("Quick battery") == 1 and page.index("Quick battery") < page.index("racf-headline")


def test_a_defence_that_never_flags_gets_a_sentence_not_an_empty_roc(recwarn):
    never = {"roc": {"fpr": [0.0, 1.0], "tpr": [0.0, 0.0]}, "auroc": 0.5}
    assert "No ROC to draw" in card_plots(card("raw", 0.2, detection=never))["detection"][0]
    flags = {"roc": {"fpr": [0.0, 0.1, 1.0], "tpr": [0.0, 0.8, 1.0]}, "auroc": 0.9}
    assert card_plots(card("vote", 0.9, detection=flags))["detection"][0].startswith("<img")
    assert not [w for w in recwarn if "legend" in str(w.message).lower()]


def test_write_scorecard_writes_a_page_per_card_and_a_board(tmp_path, capsys):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no library warning while it is made
        paths = write_scorecard([card("vote", 0.9), card("raw", 0.2)], tmp_path)
    assert (tmp_path / "card-vote.html").exists() and (tmp_path / "card-raw.html").exists()
    board = paths["html"].read_text()
    assert 'href="card-vote.html"' in board and "<script>" in board
    assert capsys.readouterr().err == ""


def test_an_undetected_error_has_no_best_other():
    """Raw's undetected error is small where the attack hides the depth: no contest to win."""
    def with_error(defence, error):
        c = card(defence, 0.5)
        c["closed_loop"]["mapped_sticker"].update(undetected_error_median=error, undetected_error_ci=[0.0, error])
        return c

    page = card_fragment(with_error("vote", 0.3), [with_error("odca", 0.1)])
    row = next(r for r in page.split("<tr>") if "undetected error" in r).split("</tr>")[0]
    assert row.endswith('<td class="num">-</td>')


def test_the_best_other_is_on_the_better_side_whichever_way_a_measure_points_and_on_the_same_battery_only():
    """Two of the board's bugs a hand mutation run let through (issue 71): "best other" taken as the higher
    even where lower is better, and a card of another battery taken as a peer."""
    def costly(defence, needless, battery="racf-5"):
        c = card(defence, 0.5)
        c["battery"] = battery
        c["closed_loop"]["removed"] = {"title": "a sign that is gone", "scr": None, "scr_ci": [None, None], "n": 60,
                                       "measures": [{"measure": "needless stop", "value": needless,
                                                     "ci": [0.0, needless], "n": 60, "higher_is_better": False}]}
        return c

    page = card_fragment(costly("vote", 0.3), [costly("odca", 0.1), costly("ekf", 0.6), costly("far", 0.0, "racf-4")])
    headline = page.split("</table>")[0]
    row = next(r for r in headline.split("<tr>") if "needless" in r)
    assert "<code>odca</code>" in row and "<code>ekf</code>" not in row  # lower is better: odca's 0.10
    assert "<code>far</code>" not in page  # another battery's card is no peer
