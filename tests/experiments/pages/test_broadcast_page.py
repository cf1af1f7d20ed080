"""The broadcast's page: its rows, what issue 70 asked (met or not, worked out from the numbers), the
onboard fallback's cards and the cost of a message's check."""

import json

from racf.experiments.pages.broadcast_page import broadcast_markdown, checks

META = {"command": "racf sweep following-broadcast.toml", "commit": "abc", "racf": "0.1.0", "machine": "m",
        "measured": "2026-11-28"}
SUP = "odca + supervisor"


def _share(k, n):
    return {"k": k, "n": n, "rate": k / n, "ci": [max(k / n - 0.1, 0.0), min(k / n + 0.1, 1.0)]}


def _row(attack, free, needless=0, gap=2.0, estimator=SUP, broadcast=None, injected=0, refused=0, all_refused=0):
    row = {"attack": attack, "estimator": estimator, "n": 60, "collision_free": _share(free, 60),
           "needless_hard_brake": _share(needless, 60),
           "mean_time_gap_s_median": {"median": gap, "ci": [gap - 0.1, gap + 0.1], "n": 60}}
    if broadcast is not None:
        row["scenario_broadcast"] = broadcast
    if injected:
        row |= {"bc_injected": injected, "bc_refused": refused, "foreign_refused": _share(all_refused, 60)}
    return row


def _data(*rows):
    return {"rows": {f"{r['attack']}|{r['estimator']}|{r.get('scenario_broadcast', '')}": r for r in rows},
            "meta": META}


BROADCAST = _data(_row("clean", 60, 1), _row("clean+lead_frustum[adaptive]", 58),
                  _row("clean+lead_frustum+radio_jam[adaptive]", 35),
                  _row("clean+lead_frustum+radio_replay[adaptive]", 60, injected=900, refused=900, all_refused=60),
                  _row("clean+lead_frustum+radio_forge[adaptive]", 60, injected=500, refused=499, all_refused=59),
                  _row("clean+radio_lie", 59), _row("clean+lead_frustum+radio_lie[adaptive]", 10))
SILENT = _data(_row("clean+lead_frustum[adaptive]", 33, broadcast="off"))
OFF = _data(_row("clean", 60, 1, 2.2, broadcast="on"), _row("clean", 60, 0, 3.0, broadcast="off"),
            _row("clean", 60, 0, 2.1, estimator="odca", broadcast="off"),
            _row("clean", 60, 4, 2.1, estimator="odca", broadcast="on"))


def test_what_was_asked_is_judged_from_the_numbers():
    text = "\n".join(checks(BROADCAST, OFF, SILENT))
    assert "the broadcast honest: collision-free 0.97 [0.87, 1.00] (N 60; asked >= 0.95): met" in text
    assert "the broadcast jammed: collision-free 0.58" in text and "with the lead silent" in text
    assert "met (the intervals overlap)" in text
    assert "refused in 60 of 60 episodes (900 of 900 messages; asked 100 %): met" in text
    assert "refused in 59 of 60 episodes (499 of 500 messages; asked 100 %): **not met**" in text
    assert "The lying lead alone: collision-free 0.98" in text and "asked: no collision): **not met**" in text
    assert "with the broadcast, the supervisor over ODCA: needless hard brakes in 0.02" in text
    assert "(asked <= 0.05): met" in text
    assert "2.20 s, against 3.00 s for the supervisor without it (medians), -27% (asked within 10 %): **not met**" in text
    assert "2.20 s, against 2.10 s for ODCA alone without it (medians), +5% (asked within 10 %): met" in text


def test_odca_alone_with_the_broadcast_is_judged_too_and_a_silent_lead_is_named_so(tmp_path):
    assert "with the broadcast, ODCA alone: needless hard brakes in 0.07" in "\n".join(checks(BROADCAST, OFF, SILENT))
    (tmp_path / "following-broadcast-silent.json").write_text(json.dumps(SILENT))
    assert "| adaptive spoof; the lead silent | odca + supervisor | off | 60 | 0.55" in broadcast_markdown(tmp_path)


def test_a_jammed_row_far_from_todays_number_is_said():
    far = _data(_row("clean+lead_frustum+radio_jam[adaptive]", 59))
    assert "**not met** (the intervals do not overlap)" in "\n".join(checks(far, None, SILENT))


def test_the_page_shows_each_stored_table_and_names_what_is_missing(tmp_path):
    (tmp_path / "following-broadcast.json").write_text(json.dumps(BROADCAST))
    page = broadcast_markdown(tmp_path)
    assert "| adaptive spoof; the broadcast honest | odca + supervisor | 60 | 0.97" in page
    assert "Not stored yet (`following-broadcast-off`)" in page and "Not stored yet (`scorecard-racf-link-2`)" in page
    assert "Not stored yet (`bench-radio`)" in page
    (tmp_path / "bench-radio.json").write_text(json.dumps({"meta": META, "result": {
        "messages": 5000, "p50_us": 60.0, "p99_us": 90.0, "max_us": 300.0, "control_period_ms": 20.0,
        "p99_share_of_period": 0.0045}}))
    assert "p50 60 us, p99 90 us, max 300 us. The p99 is 0.45 % of the 20 ms control period" in broadcast_markdown(tmp_path)


def test_the_fallback_table_sets_the_onboard_card_beside_the_raw_depth_one(tmp_path):
    def card(scr):
        return {"defence": "odca", "closed_loop": {"link_spoof_curve": {
            "title": "offboard, the patch, a man in the middle answering 5 m, CurveZMQ link", "n": 30, "scr": scr,
            "scr_ci": [scr - 0.1, min(scr + 0.05, 1.0)], "measures": [
                {"measure": "service_fallback, share (service)", "value": 1.0, "ci": [0.89, 1.0], "n": 30}]}}}

    (tmp_path / "scorecard-racf-link.json").write_text(json.dumps({"meta": META, "cards": [card(0.5)]}))
    (tmp_path / "scorecard-racf-link-2.json").write_text(json.dumps({"meta": META, "cards": [card(0.97)]}))
    page = broadcast_markdown(tmp_path)
    assert "| offboard, the patch, a man in the middle answering 5 m, CurveZMQ link | 30 | 0.50" in page
    assert "Measured 0.97 [0.87, 1.00] (N 30): met." in page


def test_the_radio_probes_are_a_table_of_what_was_taken_and_refused(tmp_path):
    import json as _json

    from racf.experiments.pages.broadcast_page import broadcast_markdown

    assert "Not stored yet (`radio-probes`)" in broadcast_markdown(tmp_path)
    meta = {"commit": "abc", "command": "python -m tests.sim.radio.radio_probes", "racf": "0.1.0",
            "machine": "2 CPU cores", "measured": "2026-11-29"}
    row = {"episodes": [{}] * 5, "injected": 650, "foreign_accepted": 0, "genuine_refused": 2}
    (tmp_path / "radio-probes.json").write_text(_json.dumps({"meta": meta, "probes": {"derived key": row}}))
    assert "| derived key | 5 | 650 | 0 | 2 |" in broadcast_markdown(tmp_path)
