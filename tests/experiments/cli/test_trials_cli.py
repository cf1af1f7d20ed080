"""``racf trial`` and ``racf trials``: what they print and write."""

import json
from pathlib import Path

import pandas as pd
import pytest

from racf.experiments.cli import main

PROTOCOL_SIGNALS = ("d_true", "d_clean", "d_meas", "c_meas", "lidar", "d_fused")


def test_cli_trials_json(tmp_path, capsys):
    assert main(["trials", "-n", "1", "--seed", "11", "--workers", "1", "--json", "--out", str(tmp_path)]) == 0
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert summary["n"] == 1 and summary["scr"] == 1.0
    assert list((tmp_path / "trials").glob("*.parquet"))


def test_cli_trial_writes_log_and_result(tmp_path, capsys):
    assert main(["trial", "--sign", "2", "--speed", "1.0", "--seed", "0", "--out", str(tmp_path), "--json"]) == 0
    printed = capsys.readouterr().out
    assert printed.count("\n") == 1  # one JSON object on one line, as its siblings print
    out = json.loads(printed)
    assert out["success"] is True
    log = pd.read_parquet(out["log"])
    assert set(PROTOCOL_SIGNALS) <= set(log.columns)


def test_cli_attack_trials_json_has_lost_frames(tmp_path, capsys):
    assert main(["trials", "--setting", "attack", "--rho", "1.0", "--t-atk", "3.0", "-n", "1", "--seed", "2",
                 "--workers", "1", "--json", "--out", str(tmp_path)]) == 0
    summary = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert {"n", "scr", "scr_ci", "asr", "dt_brake_mean", "dt_brake_std", "n_latency", "lost_frames_mean"} <= set(summary)
    assert summary["asr"] == 1.0 - summary["scr"]
    assert main(["trials", "--setting", "clean", "--rho", "0.5", "-n", "1"]) == 2
    assert main(["trials", "--setting", "attack", "--rho", "1.5"]) == 2


def test_cli_trial_with_traffic_reports_the_conflict(tmp_path, capsys):
    assert main(["trial", "--sign", "3", "--speed", "1.5", "--seed", "0", "--traffic-cars", "1",
                 "--out", str(tmp_path), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["traffic_cars"] == 1 and out["conflict"] == "yielded" and out["collision"] is False
    assert pd.read_parquet(out["log"])["traffic0_x"].notna().all()
    # The flags are cross-traffic's parameters by older names: a sign approach's only, in its ranges.
    assert out["target"] == "cross_traffic" and out["scenario_cars"] == 1
    assert main(["trial", "--traffic-gap", "1.0", "--target", "obstacle"]) == 2
    assert "--traffic-gap set scenario 'cross_traffic' (a sign approach); --target obstacle" in capsys.readouterr().err
    assert main(["trial", "--traffic-cars", "9"]) == 2
    assert "parameter 'cars' must be an int in [1, 4]" in capsys.readouterr().err


def test_cli_trial_prints_a_summary_a_reader_can_scan(tmp_path, capsys):
    assert main(["trial", "--sign", "2", "--speed", "1.0", "--seed", "0", "--out", str(tmp_path)]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0] == "racf trial: clean on sign 2 at 1 m/s, seed 0: success"
    measures = {line.split()[0]: line.split()[1] for line in lines[1:-1]}  # the name, its value, what it means
    assert measures["stopped"] == "True" and float(measures["stop_distance_m"]) < 0.5
    assert "t_star_s" in measures and not any(v == "None" for v in measures.values())  # unmeasured: left out
    row = json.loads(Path(lines[-1].split("row: ")[1].split(" (")[0]).read_text())
    assert row["success"] is True and lines[-1].startswith("log: ")


@pytest.mark.parametrize("argv, index", [([], 2), (["--target", "drive"], 0), (["--target", "obstacle"], 0),
                                         (["--target", "obstacle", "--sign", "1"], 1)])
def test_an_episode_goes_to_sign_2_unless_its_scenario_has_no_third_target(argv, index):
    """`racf bag export --target drive` once said "drive index must be 0..0, got 2": the default was sign 2's."""
    from racf.experiments.cli import build_parser
    from racf.experiments.cli.episode_flags import trial_spec

    for command in ("trial", "export-bag"):
        args = build_parser().parse_args([command, *(["/tmp/racf-unused-bag"] if command == "export-bag" else []), *argv])
        assert trial_spec(args, command).sign == index


def test_a_trial_s_printed_fields_say_what_they_mean_and_where_the_glossary_is(tmp_path):
    from racf.experiments.cli.trials import GLOSSARY, trial_summary

    row = {"trial_id": "x", "setting": "attack", "estimator": "raw", "target": "sign", "sign": 1, "speed": 1.0,
           "seed": 0, "success": False, "failure": "confirmed_lost", "detected": False, "trigger_delay_s": -0.12,
           "robustness_m": -1.1, "undetected_error_m": 0.4, "lost_frames": 21, "stop_rule": False}
    text = trial_summary(row, tmp_path / "log.parquet", tmp_path / "row.json")
    lines = {line.split()[0]: line for line in text.splitlines()[1:-1]}
    assert "never flagged it" in lines["detected"] and "early, not wrong" in lines["trigger_delay_s"]
    assert "negative: it broke it" in lines["robustness_m"] and "first flag" in lines["undetected_error_m"]
    assert "unattacked frame" in lines["lost_frames"] and "the criterion: the car came to rest" in lines["stop_rule"]
    assert text.splitlines()[-1].endswith(f"every field: {GLOSSARY}")
    from pathlib import Path

    page, anchor = GLOSSARY.split("#")
    assert f"## {anchor.replace('-', ' ').capitalize()}" in Path(page).read_text()


def test_a_supervised_trial_s_first_line_names_the_supervisor(tmp_path):
    from racf.experiments.cli.trials import trial_summary

    row = {"trial_id": "x", "setting": "clean+odca", "estimator": "odca", "target": "sign", "sign": 1, "speed": 1.0,
           "seed": 0, "success": True, "failure": None, "sup_stop_steps": 3}
    first = trial_summary(row, tmp_path / "log.parquet", tmp_path / "row.json").splitlines()[0]
    assert first.startswith("racf trial: clean+odca+supervisor on sign 1")
    alone = {k: v for k, v in row.items() if k != "sup_stop_steps"}
    alone = trial_summary(alone, tmp_path / "l", tmp_path / "r").splitlines()[0]
    assert alone.startswith("racf trial: clean+odca on sign 1")
