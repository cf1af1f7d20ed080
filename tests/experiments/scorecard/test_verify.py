"""`racf board verify`: a card carries its episodes, and proves itself by being measured again. A
rate changed by hand, a step log that does not repeat, episodes the battery does not make and code
that is not the card's are each refused, naming the row; an honest card verifies."""

import copy
import json

import pytest

from racf.errors import UserError
from racf.experiments.cli import main
from racf.experiments.scorecard import battery as battery_module
from racf.experiments.scorecard.battery_types import Battery, LoopRow, paper_row
from racf.experiments.scorecard.card import run_card
from racf.experiments.scorecard.proof import card_episodes, episode_frame, log_digest, record_of
from racf.experiments.scorecard.verify import summary_differences, verify_card

TWO = Battery(name="two", loop=(LoopRow("clean", "clean", 2, 2, paper_row("clean"), attacked=False),
                                LoopRow("patch", "the patch", 2, 2, paper_row("attack"))),
              drives=(), offline_presets=())


@pytest.fixture(scope="module")
def card(tmp_path_factory):
    with pytest.MonkeyPatch.context() as mp:
        mp.setitem(battery_module.BATTERIES, "two", TWO)
        yield run_card("raw", TWO, tmp_path_factory.mktemp("card"), workers=1, progress=False)


@pytest.fixture
def two(monkeypatch):
    monkeypatch.setitem(battery_module.BATTERIES, "two", TWO)


def _problems(card, **kw):
    verdicts, _ = verify_card(card, workers=1, **kw)
    return {v.key: v.problems for v in verdicts if v.problems}


def test_an_honest_card_verifies_and_its_sampled_episodes_repeat_to_the_bit(card, two):
    verdicts, seed = verify_card(card, sample=1, seed=3, workers=1)
    assert [(v.key, v.n, v.rerun, v.ok) for v in verdicts] == [("clean", 2, 1, True), ("patch", 2, 1, True)]
    assert seed == 3 and all(v.seconds > 0 for v in verdicts)


def test_a_rate_changed_by_hand_is_refused_naming_the_row_and_the_number(card, two):
    tampered = copy.deepcopy(card)
    tampered["closed_loop"]["patch"]["scr"] = 0.99
    measured = card["closed_loop"]["patch"]["scr"]
    assert measured != 0.99 and _problems(tampered, sample=0) == {"patch": (f"scr is 0.99, its episodes give {measured:.4g}",)}


def test_a_step_log_that_does_not_repeat_is_refused(card, two):
    tampered = copy.deepcopy(card)
    tampered["episodes"]["clean"]["log_sha256"] = ["0" * 64, "0" * 64]
    problems = _problems(tampered, sample=1)
    assert list(problems) == ["clean"] and "its step log differs" in problems["clean"][0]


def test_a_record_that_does_not_repeat_is_refused_naming_the_field(card, two):
    tampered = copy.deepcopy(card)
    episodes = tampered["episodes"]["patch"]
    for values in episodes["values"]:
        values[episodes["columns"].index("rho_set")] = 0.5  # read by no summary: only a re-run can tell
    problems = _problems(tampered, sample=1)
    assert list(problems) == ["patch"] and "does not reproduce: rho_set differ" in problems["patch"][0]


def test_episodes_the_battery_does_not_make_are_refused(card, two):
    tampered = copy.deepcopy(card)
    tampered["episodes"]["clean"]["values"].reverse()
    assert _problems(tampered, sample=0) == {"clean": ("its episodes are not the ones the battery makes for this "
                                                       "defence (their ids differ)",)}


@pytest.mark.parametrize("change, words", [
    (lambda c: c.update(version="racf 0.1.0, code 000000000000"), "check out its commit"),
    (lambda c: c.pop("episodes"), "carries no episodes"),
    (lambda c: c.update(defence="nobody"), "not registered here"),
    (lambda c: c.update(battery="racf-9"), "none of racf's"),
])
def test_a_card_of_other_code_or_without_episodes_is_refused_before_anything_runs(card, two, change, words):
    tampered = copy.deepcopy(card)
    change(tampered)
    with pytest.raises(UserError, match=words):
        verify_card(tampered, sample=1, workers=1)


def test_the_command_line_prints_a_line_per_row_and_refuses_naming_the_row(card, two, tmp_path, capsys):
    (tmp_path / "card.json").write_text(json.dumps(card))
    assert main(["board", "verify", str(tmp_path / "card.json"), "--sample", "0", "--workers", "1"]) == 0
    out = capsys.readouterr().out
    assert "row clean (N 2): ok" in out and "2 of 2 rows verified" in out and "sample seed" in out
    card = copy.deepcopy(card)
    card["closed_loop"]["clean"]["scr"] = 0.5
    (tmp_path / "bad.json").write_text(json.dumps(card))
    assert main(["board", "verify", str(tmp_path / "bad.json"), "--sample", "0", "--workers", "1"]) == 2
    out, err = capsys.readouterr()
    assert "row clean (N 2): REFUSED: scr is 0.5, its episodes give 1" in out
    assert err.strip() == "racf board verify: the card is refused: row(s) clean (each line above says why)"


def test_the_carried_records_sum_up_to_the_card_s_own_summary(card):
    from racf.experiments.scorecard.card import row_summary

    for row in TWO.rows():
        section = card["closed_loop"][row.key]
        assert summary_differences(section, row_summary(episode_frame(card["episodes"][row.key]), row.attacked)) == []


def test_a_record_holds_no_nan_and_no_wall_clock():
    import pandas as pd

    record = record_of({"a": float("nan"), "b": 1, "service_rtt_p50_ms": 3.0})
    assert record == {"a": None, "b": 1}
    log = pd.DataFrame({"t": [0.0, 0.02], "service_rtt_ms": [1.0, 2.0], "phase": ["cruise", "brake"]})
    timed_otherwise = log.assign(service_rtt_ms=[9.0, 9.0])
    assert log_digest(log) == log_digest(timed_otherwise) != log_digest(log.assign(phase=["cruise", "cruise"]))
    assert card_episodes(log.head(0), [])["values"] == []


def test_summary_differences_compare_within_rounding_and_name_nested_keys():
    assert summary_differences({"x": 0.1 + 0.2}, {"x": 0.3}) == []
    assert summary_differences({"h": {"collision_free": 0.9}}, {"h": {"collision_free": 0.8}}) == [
        "h.collision_free is 0.9, its episodes give 0.8"]
    assert summary_differences({}, {"n": 2}) == ["n is missing"]
    assert summary_differences({"ci": [0.1, None]}, {"ci": [0.1, 0.2]}) == ["ci is [0.1, null], its episodes give [0.1, 0.2]"]


def test_the_shipped_submission_s_numbers_are_what_its_episodes_give():
    """The lidar_cusum card on the board carries its 720 episodes, and every number on it is theirs (re-running
    a sample to the bit needs the code it names: `racf board verify` on that commit)."""
    from pathlib import Path

    from racf.experiments.scorecard.battery import BATTERIES
    from racf.experiments.scorecard.card import row_summary
    from racf.experiments.scorecard.submission import load_card

    card = load_card(Path(__file__).resolve().parents[3] / "docs/results/submissions/racf-5-lidar_cusum.json")
    rows = BATTERIES["racf-5"].rows()
    assert sum(len(card["episodes"][r.key]["values"]) for r in rows) == 720
    for row in rows:
        frame = episode_frame(card["episodes"][row.key])
        assert summary_differences(card["closed_loop"][row.key], row_summary(frame, row.attacked)) == [], row.key


def test_differences_reach_into_lists_and_tables_and_a_nan_or_a_flag_is_never_a_number():
    assert summary_differences({"m": [{"v": 1.0}]}, {"m": [{"v": 1.0}]}) == []
    assert summary_differences({"m": [{"v": 1.0}]}, {"m": [{"v": 2.0}]}) == ['m is [{"v": 1.0}], its episodes give [{"v": 2.0}]']
    assert summary_differences({"m": {"a": 1}}, {"m": {"a": 1, "b": 2}}) == ["m.b is missing"]
    assert summary_differences({"h": 0.5}, {"h": {"a": 1}}) == ['h is 0.5, its episodes give {"a": 1}']
    assert summary_differences({"x": [1, 2]}, {"x": [1, 2, 3]}) != [] and summary_differences({"x": {"a": 1}}, {"x": [1]}) != []
    assert summary_differences({"x": [{"a": 1}]}, {"x": [{"b": 1}]}) != []
    assert summary_differences({"x": float("nan")}, {"x": float("nan")}) == ["x is nan, its episodes give nan"]
    assert summary_differences({"x": None}, {"x": float("nan")}) == ["x is null, its episodes give nan"]
    assert summary_differences({"x": True}, {"x": 1}) == ["x is true, its episodes give 1"]


def test_a_negative_sample_is_refused_and_a_missing_row_is_named(card, two):
    with pytest.raises(UserError, match="--sample must be >= 0, got -1"):
        verify_card(card, sample=-1, workers=1)
    short = copy.deepcopy(card)
    short["closed_loop"].pop("clean")
    verdicts, _ = verify_card(short, sample=0, workers=1)
    assert (verdicts[0].key, verdicts[0].n, verdicts[0].rerun, verdicts[0].seconds, verdicts[0].problems) == \
        ("clean", 0, 0, 0.0, ("the row is missing from the card",))
    tampered = copy.deepcopy(card)
    tampered["closed_loop"]["clean"]["n"] = 3
    bad = verify_card(tampered, sample=1, workers=1)[0][0]
    assert (bad.n, bad.rerun, bad.seconds, bad.ok) == (2, 0, 0.0, False)


def test_a_row_served_over_a_link_is_checked_by_its_numbers_and_not_run(card, monkeypatch):
    import dataclasses

    served = dataclasses.replace(TWO, loop=(dataclasses.replace(TWO.loop[0], link="plain"), TWO.loop[1]))
    monkeypatch.setitem(battery_module.BATTERIES, "two", served)
    verdict = verify_card(card, sample=2, workers=1)[0][0]
    assert (verdict.ok, verdict.n, verdict.rerun, verdict.seconds) == (True, 2, 0, 0.0)
    assert verdict.note.startswith("served over a link: its records are checked, its episodes not re-run")
