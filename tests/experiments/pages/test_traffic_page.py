"""The cross-traffic results page, from stored results (or saying what to run)."""

import json

from racf.experiments.pages.traffic_page import TRAFFIC_RESULTS, crossed_key, traffic_markdown

META = {"commit": "abc", "racf": "0.1.0", "measured": "2026-11-26", "machine": "2 CPU cores, no GPU",
        "command": "racf sweep cross-traffic.toml", "sensor_profile": "qcar2"}


def _summary(n, scr, collisions=None):
    s = {"n": n, "scr": scr, "scr_ci": [0.5, 1.0]}
    if collisions is not None:
        s.update(n_traffic=n, collision_rate=collisions / n, collision_rate_ci=[0.1, 0.5],
                 n_traffic_attack_before_t_star=4, collision_rate_attack_before_t_star=0.75,
                 collision_rate_attack_before_t_star_ci=[0.3, 0.95],
                 conflicts={"collision": collisions, "crash": 0, "near_miss": 0, "passed": 0,
                            "yielded": n - collisions})
    return s


def test_without_stored_results_the_page_names_each_command(tmp_path):
    text = traffic_markdown(tmp_path)
    for command in TRAFFIC_RESULTS.values():
        assert command in text


def test_the_sweep_table_pairs_each_setting_with_its_traffic_twin(tmp_path):
    data = {"meta": META, "settings": {"attack": _summary(8, 0.5), crossed_key("attack"): _summary(8, 0.5, 3)},
            "traffic": {"attack": {"n_pairs": 8, "n_outcome_changed": 1, "stop_distance_change_max_m": 0.01,
                                   "changed": [{"seed": 7, "sign": 1, "speed": 1.5, "empty": "success",
                                                "traffic": "braked_late", "conflict": "near_miss",
                                                "collision_with": None}]}}}
    (tmp_path / "cross-traffic.json").write_text(json.dumps(data))
    text = traffic_markdown(tmp_path)
    row = next(line for line in text.splitlines() if line.startswith("| attack |"))
    assert "0.38 [0.10, 0.50]" in row and "0.75 [0.30, 0.95] (4)" in row and "3 / 0 / 0 / 0 / 5" in row
    assert "1 of 8 pairs end differently: sign 1 at 1.5 m/s, seed 7: success -> braked_late (near_miss)" in text
