"""The existence results page, from stored racf-5 cards (or saying what to run)."""

import json

from racf.experiments.pages.existence_page import EXISTENCE_COMMAND, existence_markdown

META = {"commit": "abc", "racf": "0.1.0", "measured": "2026-11-26", "machine": "2 CPU cores, no GPU",
        "command": EXISTENCE_COMMAND, "sensor_profile": "qcar2"}


def _real(scr, n=60):
    return {"title": "t", "n": n, "scr": scr, "scr_ci": [max(0.0, scr - 0.05), min(1.0, scr + 0.02)], "measures": []}


def _none(needless, n=60):
    return {"title": "t", "n": n, "scr": None, "scr_ci": [None, None], "n_needless": n,
            "measures": [{"measure": "needless_stop, share (existence)", "value": needless,
                          "ci": [max(0.0, needless - 0.04), min(1.0, needless + 0.06)], "n": n,
                          "higher_is_better": False}]}


def _card(name, rows):
    return {"defence": name, "closed_loop": rows}


def test_without_the_stored_cards_the_page_names_the_command(tmp_path):
    assert EXISTENCE_COMMAND in existence_markdown(tmp_path)


def test_each_row_shows_scr_or_needless_stops_and_the_claims_are_checked(tmp_path):
    vote = {"mapped_sticker": _real(0.98), "mapped_sticker_top": _real(0.90), "removed": _none(0.0),
            "phantom": _none(0.10), "temporary_clean": _real(1.0), "mapped_sticker_spoof": _real(0.85)}
    odca = {"mapped_sticker": _real(0.27), "mapped_sticker_top": _real(0.0), "removed": _none(0.0),
            "phantom": _none(1.0), "temporary_clean": _real(1.0)}
    data = {"meta": META, "cards": [_card("odca", odca), _card("vote", vote)]}
    (tmp_path / "scorecard-racf-5.json").write_text(json.dumps(data))
    text = existence_markdown(tmp_path)
    header = next(line for line in text.splitlines() if line.startswith("| row | measure |"))
    assert header.index("`vote`") < header.index("`odca`")  # the vote first
    phantom = next(line for line in text.splitlines() if "(`phantom`) | needless stops" in line)
    assert "0.10" in phantom and "1.00" in phantom
    claims = {line.split(" | ")[0]: line for line in text.splitlines() if line.startswith("| ")}
    assert claims["| mapped signs, the 0.6 sticker up from the start: SCR >= 0.95 with the vote"].endswith("holds |")
    assert "**not met**" in claims["| mapped signs, the 0.4 top-edge sticker up from the start: SCR >= 0.95 with the vote"]
    assert "**not met**" in claims["| phantoms: needless-stop rate <= 0.05 with the vote"]
    assert claims["| removed mapped signs: needless-stop rate <= 0.05 with the vote"].endswith("holds |")
    moving = "| the sign's depth and LiDAR returns moved away at 3 m/s (with the sticker): SCR >= 0.9 with the vote's static-world check"
    assert "**not met**" in claims[moving] and "0.85" in claims[moving]
    # The driving score: a needless stop at x 0.70, a sign run at x 0.80.
    assert "| `phantom` | 0.970 | 0.700 |" in text and "| `mapped_sticker` | 0.996 | 0.854 |" in text
