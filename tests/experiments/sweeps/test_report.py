"""The sweep report's stealth rows: one per attack, settings and estimator, stored as strict JSON."""

import json

import pandas as pd

from racf.experiments.sweeps.report import stealth_rows, write_report


def _frame():
    rows = []
    for estimator, err in (("raw", 0.9), ("odca", 0.1)):
        for seed in range(4):
            rows.append({"setting": f"clean+stealth_ramp+{estimator}", "attack": "stealth_ramp", "estimator": estimator,
                         "attack_params": "rate_mps=1.0", "param_rate_mps": 1.0, "success": estimator == "odca",
                         "attack_start_s": 1.0, "undetected_error_m": err + 0.01 * seed,
                         "detected": estimator == "odca", "detection_delay_s": 0.1 if estimator == "odca" else None,
                         "rho_set": 1.0, "t_atk_set": 1.5, "t_star_s": 2.0, "dt_brake_s": 0.1, "trigger_delay_s": 0.0,
                         "failure": "" if estimator == "odca" else "confirmed_lost", "lost_frames": 0})
    rows.append({**rows[0], "setting": "clean", "attack": "none", "estimator": "raw", "success": True,
                 "attack_start_s": None, "undetected_error_m": None, "attack_params": ""})
    return pd.DataFrame(rows)


def test_stealth_rows_group_by_attack_settings_and_estimator():
    rows = stealth_rows(_frame())
    assert [(r["attack"], r["estimator"]) for r in rows] == [("stealth_ramp", "odca"), ("stealth_ramp", "raw")]
    odca, raw = rows
    assert odca["n"] == raw["n"] == 4 and odca["scr"] == 1.0 and raw["scr"] == 0.0
    assert odca["undetected_error_median"] < raw["undetected_error_median"]
    assert odca["detected_share"] == 1.0 and raw["detected_share"] == 0.0


def test_the_report_stores_the_stealth_rows_as_strict_json(tmp_path):
    write_report(_frame(), tmp_path, name="t")
    stored = json.loads((tmp_path / "stealth.json").read_text())
    assert stored == json.loads(json.dumps(stealth_rows(_frame())))
    assert "NaN" not in (tmp_path / "stealth.json").read_text()
