"""The cut-in, an example package written against the docs with no edit to racf: a QCar 2 body added in
one call, declared as a vehicle; racf's following stage follows it and racf's attacks on a car ahead
act on it, found through that declaration."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from tests.conftest import run_cli


def _trial(tmp_path, setting: str) -> tuple[dict, pd.DataFrame]:
    attack = ["--t-atk", "6"] if "lead_" in setting else []
    code, out = run_cli(["trial", "--target", "cut_in", "--sign", "1", "--setting", setting, *attack,
                         "--out", str(tmp_path / setting), "--json"])
    assert code == 0, out
    row = json.loads(out)
    return row, pd.read_parquet(row["log"])


@pytest.mark.slow  # a long episode (10 s or more): CI's slow stage runs it
def test_the_car_follows_the_car_that_cut_in_without_touching_it(cut_in_installed, tmp_path):
    row, log = _trial(tmp_path, "clean+odca")
    assert row["no_cutin_contact"] is True and row["collision_with"] is None
    assert 0.1 < row["cutin_min_gap_m"] < 1.0
    # No stop-sign measure where the scenario judges no stop rule; the following stage's columns are the car's.
    assert "success" not in row and "stop_distance_m" not in row and "robustness_m" not in row
    merged = log["t"] > 1.5
    assert log.loc[merged, "lead_detected"].mean() > 0.5 and (log["lead_cap"] < log["speed_cap"]).any()


@pytest.mark.slow  # 4-5 s: the default run keeps under two minutes on 2 cores
def test_racf_s_attacks_on_a_car_ahead_act_on_it(cut_in_installed, tmp_path):
    from racf.experiments.episode import TrialSpec
    from racf.experiments.episode.stack import default_env
    from racf.sim.attacks.lead import attacked_vehicle

    target = attacked_vehicle(default_env(TrialSpec("clean+lead_hide", 1, 1.0, 0, target="cut_in")))
    assert (target.name, target.kind, target.body) == ("cutin", "vehicle", "cutin_0")
    row, log = _trial(tmp_path, "clean+lead_hide+raw")
    hidden = log["attack_active"].astype(bool)
    seen_before = log.loc[(log["t"] > 1.5) & ~hidden, "lead_detected"].mean()
    # Gone from every sensor: the car loses it, and drives into it (as it does into the lead: racf-6's row).
    assert hidden.any() and log.loc[hidden, "lead_detected"].mean() < 0.5 * seen_before
    assert row["collision_with"] == "cutin" and row["no_cutin_contact"] is False
