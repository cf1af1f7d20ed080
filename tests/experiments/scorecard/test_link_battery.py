"""The ``racf-link`` battery: the paper's offboard loop and its link attacked, each row served by the
service of its link, which the card starts itself."""

from __future__ import annotations

import pytest

from racf.experiments.scorecard.battery import BATTERIES, PAPER_LOOP_HZ


def test_every_row_is_the_papers_loop_served_over_its_link():
    battery = BATTERIES["racf-link"]
    rows = {row.key: row for row in battery.rows()}
    assert list(rows) == ["offboard_clean", "offboard_patch", "link_delay", "link_drop", "link_spoof_plain",
                          "link_spoof_curve"]
    for row in rows.values():
        specs = row.specs("odca", quick=True)
        assert len(specs) == row.n_quick and row.n == 30
        assert all(s.control_hz == PAPER_LOOP_HZ and s.estimator_endpoint and s.estimator == "odca" for s in specs)
    assert {r.link for r in rows.values()} == {"plain", "curve"}
    spoof_plain, spoof_curve = (rows[k].specs("vote") for k in ("link_spoof_plain", "link_spoof_curve"))
    assert [s.trial_id for s in spoof_plain] == [s.trial_id for s in spoof_curve]  # same episodes until served
    assert rows["link_spoof_curve"].link == "curve" and rows["link_spoof_plain"].link == "plain"


@pytest.mark.slow
def test_a_quick_card_runs_each_row_through_its_own_service(tmp_path):
    from racf.experiments.scorecard.card import run_card

    card = run_card("raw", BATTERIES["racf-link"], tmp_path, quick=True, workers=2, progress=False)
    assert set(card["closed_loop"]) == {row.key for row in BATTERIES["racf-link"].rows()}
    assert all(row["n"] == 4 for row in card["closed_loop"].values())
    assert (tmp_path / "link-keys" / "server.key_secret").exists()  # the CurveZMQ row's keys, kept for a resume
