"""The stop sign's supervised rows: a table from sweep folders, each defence alone and supervised."""

import json

import pandas as pd

from racf.experiments.pages.sign_rows import main, sign_rows_markdown, summarise


def _sweep(folder, rows):
    (folder / "parts").mkdir(parents=True)
    for i, row in enumerate(rows):
        pd.DataFrame([row]).to_parquet(folder / "parts" / f"{i}.parquet")


def test_the_rows_split_by_case_defence_and_supervision_and_count_what_applies(tmp_path, capsys):
    base = {"estimator": "odca", "collision": False}
    _sweep(tmp_path / "stale", [
        {**base, "trial_id": "clean+odca_stale_map0_seed1_x", "scenario_case": "phantom", "stop_rule": None,
         "no_needless_stop": True},
        {**base, "trial_id": "clean+odca+supervisor_stale_map0_seed1_y", "scenario_case": "phantom", "stop_rule": None,
         "no_needless_stop": False},
        {**base, "trial_id": "clean+odca+supervisor_stale_map0_seed2_z", "scenario_case": "temporary",
         "stop_rule": True, "no_needless_stop": None}])
    rows = summarise([tmp_path / "stale"])["rows"]
    alone, supervised = rows["stale|phantom|odca|False"], rows["stale|phantom|odca|True"]
    assert alone["needless_stop"]["k"] == 0 and supervised["needless_stop"]["k"] == 1 and supervised["n"] == 1
    assert alone["stop_rule"]["n"] == 0 and rows["stale|temporary|odca|True"]["stop_rule"]["k"] == 1
    assert main([str(tmp_path / "stale"), "--out", str(tmp_path / "out.json")]) == 0
    data = json.loads((tmp_path / "out.json").read_text())
    data["meta"] = {"command": "c", "commit": "abc", "racf": "0.1.0", "machine": "m", "measured": "d"}
    (tmp_path / "sign-supervisor.json").write_text(json.dumps(data))
    page = "\n".join(sign_rows_markdown(tmp_path))
    assert "| stale | phantom | odca + supervisor | 1 | — | 1 of 1 (1.00 [0.21, 1.00]) | 0 |" in page
    assert main([str(tmp_path / "nowhere")]) == 2 and "holds no episodes" in capsys.readouterr().err


def test_a_part_left_from_older_code_is_not_counted(tmp_path):
    """The folder of a sweep run again by new code keeps the old code's parts (their ids carry the code's
    identity): the rows count the episodes the spec makes with this code, each once."""
    from racf.experiments.sweeps.spec import parse_spec

    spec = '''name = "s"
mode = "grid"
repeats = 1
seed = 0
target = "stale_map"
supervisor = [true]

[space]
attack = ["none"]
estimator = ["odca"]
sign = [0]
speed = [1.5]

[scenario.stale_map]
case = ["temporary"]
'''
    (tid,) = [s.trial_id for s in parse_spec(spec).episodes()]
    base = {"estimator": "odca", "collision": False, "scenario_case": "temporary", "no_needless_stop": None}
    _sweep(tmp_path / "s", [{**base, "trial_id": tid, "stop_rule": True},
                            {**base, "trial_id": tid, "stop_rule": True},  # the same episode, stored twice
                            {**base, "trial_id": tid.rsplit("_", 1)[0] + "_0ldc0de0ldc0", "stop_rule": False}])
    (tmp_path / "s" / "spec.toml").write_text(spec)
    row = summarise([tmp_path / "s"])["rows"]["s|temporary|odca|True"]
    assert row["n"] == 1 and row["stop_rule"]["k"] == 1 and row["stop_rule"]["n"] == 1
