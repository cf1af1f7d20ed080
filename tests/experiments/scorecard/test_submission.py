"""A card's way onto the board: the check (full battery, full N, a version and a committed tree),
the submission file, and the regenerated board with the submitted card beside racf's own."""

import json

import pytest

from racf.errors import UserError
from racf.experiments.cli import main
from racf.experiments.scorecard.battery import BATTERIES
from racf.experiments.scorecard.submission import Submission, card_problems, load_card


def full_card(defence="mine", battery="racf-link", **extra):
    rows = {row.key: {"title": row.title, "scr": 0.9, "scr_ci": [0.8, 0.95], "n": row.n}
            for row in BATTERIES[battery].rows()}
    return {"defence": defence, "battery": battery, "quick": False, "version": "racf 0.1.0, code 0123456789ab",
            "commit": "abc1234", "sensor_profile": "qcar2", "closed_loop": rows, "drives": {}, "detection": None,
            "penalties": {"ran_stop_sign": 0.8}, "timing": {"wall_s": 1.0},
            "cost": {"parameters": {"trainable": 3, "from": "declared"}}, **extra}


def test_a_full_card_on_a_committed_tree_may_go_on_the_board():
    assert card_problems(full_card()) == []


@pytest.mark.parametrize("change, words", [
    (lambda c: c.update(quick=True), "quick card"),
    (lambda c: c["closed_loop"].pop("link_drop"), "row 'link_drop' is missing"),
    (lambda c: c["closed_loop"]["link_drop"].update(n=4), "row 'link_drop' has N 4, the battery's is 30"),
    (lambda c: c["closed_loop"]["link_drop"].update(n=31), "row 'link_drop' has N 31, the battery's is 30"),
    (lambda c: c.update(commit="abc1234+changes"), "uncommitted changes"),
    (lambda c: c.pop("commit"), "names no commit"),
    (lambda c: c.update(version="racf 0.1.0"), "names no code digest"),
    (lambda c: c.update(battery="racf-9"), "is none of racf's"),
    (lambda c: c.update(battery="racf-4", closed_loop=full_card(battery="racf-4")["closed_loop"]),
     "the offline rows are missing"),
])
def test_each_thing_that_keeps_a_card_off_the_board_is_named(change, words):
    card = full_card()
    change(card)
    assert any(words in p for p in card_problems(card))


def test_a_card_with_nan_or_no_card_at_all_is_one_line(tmp_path):
    (tmp_path / "nan.json").write_text('{"defence": "x", "battery": "racf-5", "closed_loop": {"r": NaN}}')
    with pytest.raises(UserError, match="strict JSON"):
        load_card(tmp_path / "nan.json")
    (tmp_path / "list.json").write_text("[1, 2]")
    with pytest.raises(UserError, match="not a card"):
        load_card(tmp_path / "list.json")


def test_a_name_the_board_has_is_refused():
    with pytest.raises(UserError, match="already has a defence named 'odca'"):
        Submission.make(full_card("odca"), "racf", "racf scorecard --defence odca", taken={"odca"})


@pytest.fixture
def verified(monkeypatch):
    """`board submit` verifies first (tests/experiments/scorecard/test_verify.py runs that for real): here
    every card verifies, by a sample of 5 with the seed 7."""
    from racf.experiments.scorecard import verify
    from racf.experiments.scorecard.verify import RowVerdict

    monkeypatch.setattr(verify, "verify_card", lambda card, **kw: ([RowVerdict("r", 30, 5, 1.0)], 7))


def test_a_submitted_card_appears_on_the_regenerated_board_beside_racf_s_own(tmp_path, capsys, verified):
    from racf.experiments.pages.leaderboard_page import card_pages, leaderboard_markdown
    from racf.experiments.pages.results_format import StoredResults

    data = tmp_path / "results" / "data"
    data.mkdir(parents=True)
    meta = {"command": "racf scorecard", "commit": "abc1234", "racf": "0.1.0", "machine": "m", "measured": "d"}
    (data / "scorecard-racf-link.json").write_text(json.dumps({"meta": meta, "cards": [full_card("raw")]}))
    (tmp_path / "mine.json").write_text(json.dumps(full_card("mine")))
    into = tmp_path / "results" / "submissions"
    code = main(["board", "submit", str(tmp_path / "mine.json"), "--code", "racf-mine==1.0",
                 "--command", "racf scorecard --defence mine --battery racf-link --json", "--into", str(into)])
    assert code == 0 and (into / "racf-link-mine.json").exists()
    assert json.loads((into / "racf-link-mine.json").read_text())["verified"] == {
        "sample": 5, "seed": 7, "rows": 1, "episodes_rerun": 5}
    page = leaderboard_markdown(StoredResults(data))
    assert "<code>raw</code>" in page and "<code>mine</code></a> <small>submitted</small>" in page
    assert "<code>raw</code></a> <small>submitted</small>" not in page  # racf's own card is not marked
    pages = card_pages(data)
    assert "`racf-mine==1.0`" in pages["cards/racf-link-mine.md"]() and "cards/racf-link-raw.md" in pages
    # A quick card is refused in one line, and nothing is written.
    (tmp_path / "quick.json").write_text(json.dumps(full_card("quick", quick=True)))
    capsys.readouterr()
    assert main(["board", "submit", str(tmp_path / "quick.json"), "--code", "x", "--command", "racf scorecard",
                 "--into", str(into)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "quick card" in err and not (into / "racf-link-quick.json").exists()


def test_board_check_says_per_card_whether_it_may_go(tmp_path, capsys):
    (tmp_path / "ok.json").write_text(json.dumps(full_card()))
    (tmp_path / "dirty.json").write_text(json.dumps(full_card(commit="abc1234+changes")))
    assert main(["board", "check", str(tmp_path / "ok.json")]) == 0
    assert main(["board", "check", str(tmp_path / "ok.json"), str(tmp_path / "dirty.json")]) == 2
    out = capsys.readouterr().out
    assert "ok.json: mine on racf-link: may go on the board" in out and "dirty.json" in out and "not yet" in out


def test_a_battery_s_cards_from_two_stored_results_share_one_board_each_with_its_provenance(tmp_path):
    from racf.experiments.pages.leaderboard_page import card_pages, leaderboard_markdown
    from racf.experiments.pages.results_format import StoredResults

    def meta(commit):
        return {"command": f"racf scorecard ({commit})", "commit": commit, "racf": "0.1.0", "machine": "m",
                "measured": "d"}

    (tmp_path / "scorecard-racf-link.json").write_text(json.dumps({"meta": meta("aaa1111"), "cards": [full_card("raw")]}))
    (tmp_path / "scorecard-racf-link-more.json").write_text(json.dumps({"meta": meta("bbb2222"),
                                                                        "cards": [full_card("vote")]}))
    page = leaderboard_markdown(StoredResults(tmp_path))
    assert page.count("## `racf-link`") == 1 and "`aaa1111`" in page and "`bbb2222`" in page
    assert "<code>raw</code>" in page and "<code>vote</code>" in page
    assert "`bbb2222`" in card_pages(tmp_path)["cards/racf-link-vote.md"]()


def test_submit_writes_nowhere_unless_told_where(tmp_path, monkeypatch, capsys, verified):
    (tmp_path / "mine.json").write_text(json.dumps(full_card("mine")))
    monkeypatch.chdir(tmp_path)
    assert main(["board", "submit", "mine.json", "--code", "x", "--command", "racf scorecard --defence mine"]) == 2
    assert "--into" in capsys.readouterr().err and sorted(p.name for p in tmp_path.rglob("*")) == ["mine.json"]


def test_submit_writes_nothing_for_a_card_verify_refuses(tmp_path, monkeypatch, capsys):
    from racf.experiments.scorecard import verify
    from racf.experiments.scorecard.verify import RowVerdict

    def refuse(card, progress, **kw):
        progress(RowVerdict("r", 30, 5, 1.0, ("scr is 0.99",)))
        return [RowVerdict("r", 30, 5, 1.0, ("scr is 0.99",))], 7

    monkeypatch.setattr(verify, "verify_card", refuse)
    (tmp_path / "mine.json").write_text(json.dumps(full_card("mine")))
    assert main(["board", "submit", str(tmp_path / "mine.json"), "--code", "x", "--command", "racf scorecard --defence "
                 "mine", "--into", str(tmp_path / "subs")]) == 2
    assert "row r (N 30): REFUSED: scr is 0.99" in capsys.readouterr().out and not (tmp_path / "subs").exists()


def test_submit_refuses_a_name_from_any_stored_result_of_the_battery(tmp_path, monkeypatch, capsys):
    data = tmp_path / "docs" / "results" / "data"
    data.mkdir(parents=True)
    meta = {"command": "racf scorecard", "commit": "abc1234", "racf": "0.1.0", "machine": "m", "measured": "d"}
    (data / "scorecard-racf-link-more.json").write_text(json.dumps({"meta": meta, "cards": [full_card("vote")]}))
    (tmp_path / "vote.json").write_text(json.dumps(full_card("vote")))
    monkeypatch.chdir(tmp_path)
    assert main(["board", "submit", "vote.json", "--code", "x", "--command", "racf scorecard --defence vote",
                 "--into", "subs"]) == 2
    assert "already has a defence named 'vote'" in capsys.readouterr().err
