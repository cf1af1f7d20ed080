"""The following page: a sweep's episodes summarised with intervals, and its table."""

import json
from pathlib import Path

import pandas as pd
import pytest

from racf.experiments.pages.following_page import following_markdown, main, summarise


def sweep(folder, rows):
    (folder / "parts").mkdir(parents=True)
    (folder / "spec.toml").write_text("")
    for k, row in enumerate(rows):
        pd.DataFrame([row]).to_parquet(folder / "parts" / f"p{k}.parquet")


def row(setting, estimator, profile, free, ttc=1.0, headway=0.0):
    return {"trial_id": f"{setting}-{profile}", "setting": setting, "estimator": estimator, "scenario_profile": profile, "no_lead_collision": free,
            "min_ttc_s": ttc, "headway_violation_s": headway, "hard_brakes": 2}


def test_it_counts_collision_free_episodes_per_attack_and_defence_with_wilson_intervals(tmp_path):
    sweep(tmp_path / "a", [row("clean+lead_patch", "raw", "cruise", False, 0.0),
                           row("clean+lead_patch", "raw", "hard_brake", True, 1.5, 0.2),
                           row("clean+lead_patch+odca", "odca", "cruise", True, 1.2)])
    sweep(tmp_path / "b", [row("clean+lead_frustum+odca", "odca", "cruise", True, None)])
    rows = summarise([tmp_path / "a", tmp_path / "b"])["rows"]
    raw = rows["clean+lead_patch|raw"]
    assert raw["n"] == 2 and raw["collision_free"]["k"] == 1 and raw["collision_free"]["ci"][0] < 0.5
    assert raw["headway_violated"]["k"] == 1 and raw["by_profile"]["cruise"]["k"] == 0
    assert rows["clean+lead_patch|odca"]["collision_free"]["rate"] == 1.0
    frustum = rows["clean+lead_frustum|odca"]
    assert frustum["min_ttc_median_s"] is None  # they never closed: no median to give


def test_its_page_shows_the_table_and_says_how_to_make_what_is_missing(tmp_path):
    assert "Not stored yet (`following`)" in following_markdown(tmp_path)
    sweep(tmp_path / "s", [row("clean", "raw", "cruise", True)])
    data = summarise([tmp_path / "s"])
    data["meta"] = {"command": "racf sweep following.toml", "commit": "abc", "racf": "0.1.0", "machine": "m",
                    "measured": "2026-11-27"}
    (tmp_path / "following.json").write_text(json.dumps(data))
    page = following_markdown(tmp_path)
    assert "| none | raw | 1 | 1.00 [" in page and "| none | raw | 1 / 1 |" in page


def test_a_part_from_older_code_is_left_out(tmp_path):
    from racf.experiments.sweeps.spec import parse_spec

    text = (Path(__file__).resolve().parents[3] / "experiments/sweeps/specs/following-hide.toml").read_text()
    episodes = parse_spec(text).episodes()
    current = {**row("clean+lead_hide", "raw", "cruise", False), "trial_id": episodes[0].trial_id}
    sweep(tmp_path / "s", [current, row("clean+lead_hide", "raw", "cruise", True)])
    (tmp_path / "s" / "spec.toml").write_text(text)
    kept = summarise([tmp_path / "s"])["rows"]["clean+lead_hide|raw"]
    assert kept["n"] == 1 and kept["collision_free"]["k"] == 0  # the current episode's, not the old one's


def test_a_folder_without_episodes_is_refused_in_one_line(tmp_path, capsys):
    assert main([str(tmp_path)]) == 2
    assert capsys.readouterr().err.count("\n") == 1


def test_the_frustum_spoof_that_moves_the_depth_too_is_its_own_row(tmp_path):
    from racf.experiments.sweeps.spec import parse_spec

    text = (Path(__file__).resolve().parents[3] / "experiments/sweeps/specs/following-frustum.toml").read_text()
    first = parse_spec(text).episodes()[0]
    sweep(tmp_path / "s", [{**row(first.setting, first.estimator, "cruise", True), "trial_id": first.trial_id}])
    (tmp_path / "s" / "spec.toml").write_text(text)
    assert list(summarise([tmp_path / "s"])["rows"]) == [f"clean+lead_frustum[depth]|{first.estimator}"]


def test_the_phantom_s_section_counts_episodes_with_a_needless_hard_brake(tmp_path):
    assert "Not stored yet (`following-phantom`)" in following_markdown(tmp_path)
    phantom = [{**row("clean+lead_phantom", "raw", p, True), "needless_hard_brakes": n}
               for p, n in (("cruise", 2), ("slow_down", 0), ("hard_brake", 1))]
    sweep(tmp_path / "s", phantom + [{**row("clean", "raw", "cruise", True), "needless_hard_brakes": 0}])
    data = summarise([tmp_path / "s"])
    attacked = data["rows"]["clean+lead_phantom|raw"]["needless_hard_brake"]
    assert (attacked["k"], attacked["n"]) == (2, 3) and attacked["ci"][0] < 2 / 3 < attacked["ci"][1]
    data["meta"] = {"command": "racf sweep following-phantom.toml", "commit": "abc", "racf": "0.1.0", "machine": "m",
                    "measured": "2026-11-27"}
    (tmp_path / "following-phantom.json").write_text(json.dumps(data))
    page = following_markdown(tmp_path)
    assert "| a phantom car 0.5 m ahead (camera only) | raw | 3 | 0.67 [" in page
    assert page.index("| none | raw | 1 | 0.00 [") < page.index("| a phantom car")  # clean first


def test_a_defence_run_with_options_is_its_own_row(tmp_path):
    from racf.experiments.sweeps.spec import parse_spec

    text = (Path(__file__).resolve().parents[3] / "experiments/sweeps/specs/following-phantom.toml").read_text()
    text = text.replace('estimator = ["raw", "odca", "ekf", "chronos"]', 'estimator = ["vote"]')
    text += '\n[estimators.vote]\ninner = "ekf"\n'
    episodes = [e for e in parse_spec(text).episodes() if e.setting == "clean+lead_phantom+vote"]
    assert episodes and episodes[0].estimator_options == {"inner": "ekf"}
    sweep(tmp_path / "s", [{**row(e.setting, "vote", "cruise", True), "trial_id": e.trial_id,
                            "needless_hard_brakes": k % 2} for k, e in enumerate(episodes[:4])])
    (tmp_path / "s" / "spec.toml").write_text(text)
    assert list(summarise([tmp_path / "s"])["rows"]) == ["clean+lead_phantom|vote (inner=ekf)"]


def test_the_existence_section_sets_the_vote_with_the_check_beside_each_racf_6_card(tmp_path):
    assert "Not stored yet (`scorecard-racf-6`)" in following_markdown(tmp_path)
    assert "Not stored yet (`racf-6-vote-lead-check`)" in following_markdown(tmp_path)

    def card(defence, free, needless):
        cell = {"n_following": 60, "collision_free": free, "collision_free_ci": [free - 0.1, 1.0],
                "needless_hard_brake": needless, "needless_hard_brake_ci": [0.0, needless + 0.1]}
        return {"defence": defence, "closed_loop": {"following_clean": cell, "following_phantom": cell}}

    meta = {"command": "racf scorecard", "commit": "abc", "racf": "0.1.0", "machine": "m", "measured": "2026-11-27"}
    (tmp_path / "scorecard-racf-6.json").write_text(json.dumps({"meta": meta, "cards": [card("odca", 1.0, 0.1),
                                                                                        card("raw", 0.9, 0.2)]}))
    (tmp_path / "racf-6-vote-lead-check.json").write_text(json.dumps({"meta": meta, "cards": [card("vote", 0.8, 0.05)]}))
    page = following_markdown(tmp_path)
    assert "| raw | 0.90 [" in page and page.index("| raw |") < page.index("| odca | 1.00 [")
    assert "| vote (lead_check=true) | 0.80 [0.70, 1.00]; 0.05 [0.00, 0.15] |" in page
    assert "| — | — |" in page and "N per cell: 60" in page  # no frustum-with-depth row stored: a dash


def test_the_adaptive_frustum_spoof_is_its_own_row_and_its_own_section(tmp_path):
    from racf.experiments.sweeps.spec import parse_spec

    assert "Not stored yet (`following-adaptive`)" in following_markdown(tmp_path)
    text = (Path(__file__).resolve().parents[3] / "experiments/sweeps/specs/following-adaptive.toml").read_text()
    episodes = [e for e in parse_spec(text).episodes() if e.estimator == "odca"][:3]
    sweep(tmp_path / "s", [{**row(e.setting, e.estimator, "cruise", k == 0), "trial_id": e.trial_id}
                           for k, e in enumerate(episodes)])
    (tmp_path / "s" / "spec.toml").write_text(text)
    data = summarise([tmp_path / "s"])
    assert list(data["rows"]) == ["clean+lead_frustum[adaptive]|odca"]
    data["meta"] = {"command": "racf sweep following-adaptive.toml", "commit": "abc", "racf": "0.1.0", "machine": "m",
                    "measured": "2026-11-27"}
    (tmp_path / "following-adaptive.json").write_text(json.dumps(data))
    page = following_markdown(tmp_path)
    assert "## The adaptive attack: every witness moved" in page
    assert "| adaptive frustum spoof: depth, LiDAR and picture moved away at 0.5 m/s up to 2 m | odca | 3 | 0.33 [" in page
