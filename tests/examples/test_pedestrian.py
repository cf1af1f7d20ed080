"""The pedestrian crossing, an example package (a scenario and the car stage its mission engages) used
with no edit to racf: it is listed with its parameters and criteria, a trial runs it (the car's own
emergency brake stops it for the person it would hit; the episode runs on until the person has
crossed), its columns are the referee's and its stage's the car's, a sweep splits its rows by its
parameters, a falsification space and a scorecard take it."""

from __future__ import annotations

import json
import math

import pandas as pd
import pytest

from tests.conftest import run_cli


def test_the_scenario_is_listed_with_its_parameters_and_criteria(pedestrian_installed):
    code, out = run_cli(["list", "--json"])
    entry = json.loads(out)["scenario"]["pedestrian_crossing"]
    assert code == 0 and entry["origin"] == "racf-pedestrian"
    assert set(entry["params"]) == {"ahead_m", "gap_s", "speed_mps", "walks"}
    assert json.loads(out)["car stage"]["upright_in_lane"]["origin"] == "racf-pedestrian"
    assert entry["criteria"]["no_pedestrian_collision"] == {"checks": "the car touched no person", "penalty": 0.5,
                                                             "terminates": True}


def _trial(tmp_path, gap_s: float, *extra: str) -> tuple[dict, pd.DataFrame]:
    code, out = run_cli(["trial", "--target", "pedestrian_crossing", "--sign", "2", "--speed", "1.0",
                         "--scenario-param", f"gap_s={gap_s}", "--out", str(tmp_path / f"gap{gap_s}"), "--json",
                         *extra])
    assert code == 0, out
    row = json.loads(out)
    return row, pd.read_parquet(row["log"])


@pytest.mark.slow  # a long episode (10 s or more): CI's slow stage runs it
def test_the_car_that_meets_the_person_stops_for_them_with_its_own_emergency_brake(pedestrian_installed, tmp_path):
    """Timed to meet the car (gap 0): its LiDAR scans over a 1/10-scale person, but the example's car stage
    finds them upright in the lane in the depth and caps the speed: the car stops short and drives on once
    they have crossed."""
    row, log = _trial(tmp_path, 0.0)
    assert row["collision_with"] is None and row["no_pedestrian_collision"] is True and row["success"]
    assert row["driving_score"] == 1.0 and row["scenario_gap_s"] == 0.0 and row["scenario_ahead_m"] == 1.0
    # The stage's columns are the car's, and its cap is what stopped the car before the crosswalk.
    capped = log["aeb_cap"] < log["state_speed_mps"] + 0.05
    assert capped.any() and log["aeb_nearest_m"].min() < 0.4
    before = log["t"] < log.loc[capped, "t"].max()
    assert log.loc[before, "speed"].min() < 0.25 and log["pedestrian_crossed"].iloc[-1]


@pytest.mark.slow  # a long episode (10 s or more): CI's slow stage runs it
def test_under_the_supervisor_its_stage_is_supervised_through_the_track_it_publishes(pedestrian_installed, tmp_path):
    """The stage publishes a person's track; the supervisor reads it (one witness: never vouched, so it adds
    no limit) and the stop sign's, and the car still stops for the person."""
    row, log = _trial(tmp_path, 0.0, "--supervisor")
    assert row["collision_with"] is None and row["success"] and row["sup_stop_steps"] == 0
    assert {"sup_person_vouched", "sup_sign_vouched"} <= set(log.columns)
    assert not log["sup_person_vouched"].any() and log["sup_person_cap"].eq(float("inf")).all()


@pytest.mark.slow  # a long episode (10 s or more): CI's slow stage runs it
def test_a_late_person_crosses_behind_the_stopped_car_and_the_episode_waits_for_them(pedestrian_installed, tmp_path):
    row, log = _trial(tmp_path, 2.0)
    assert row["success"] and row["no_pedestrian_collision"] is True and row["driving_score"] == 1.0
    # The car stopped at its line long before: the scenario ran the episode on until the person crossed.
    assert log["pedestrian_crossed"].iloc[-1] and not log["pedestrian_crossed"].iloc[-2]
    assert (log["phase"] == "done").sum() > 1
    assert math.isfinite(log["pedestrian_x"].iloc[0])


def test_its_columns_are_the_referees_and_never_the_cars(pedestrian_installed):
    from racf.experiments.episode import TrialSpec
    from racf.experiments.episode.plan import plan_episode
    from racf.experiments.episode.record import REFEREE, world_columns
    from racf.plugins import SCENARIOS

    spec = TrialSpec("clean", 2, 1.0, 0, target="pedestrian_crossing")
    world = SCENARIOS["pedestrian_crossing"]().world(spec, spec.scenario_params)
    columns = world_columns(world)
    assert [c.name for c in columns][:2] == ["pedestrian_x", "pedestrian_y"] and {c.side for c in columns} == {REFEREE}
    plan = plan_episode(spec)
    assert "pedestrian" in plan.reset_options and plan.mission.stages == ("upright_in_lane",)
    # The plain approach: no person, the car's emergency brake still on.
    plain = TrialSpec("clean", 2, 1.0, 0, target="pedestrian_crossing", scenario_params={"walks": False})
    assert "pedestrian" not in plan_episode(plain).reset_options


def test_a_falsification_space_takes_its_parameters(pedestrian_installed, tmp_path):
    from racf.experiments.falsify.space import load_space

    space_file = tmp_path / "space.toml"
    space_file.write_text('[scenario]\ntarget = "pedestrian_crossing"\nsign = [2]\n'
                          '[scenario.pedestrian_crossing]\ngap_s = {low = -1.0, high = 1.0}\n')
    space = load_space("odca", ("dropout_timed",), space_file)
    spec = space.trial_spec({"sign": 2, "scenario.pedestrian_crossing.gap_s": 0.4}, seed=1)
    assert spec.target == "pedestrian_crossing" and spec.scenario_params["gap_s"] == 0.4


@pytest.mark.slow  # a sweep and a card end to end: CI's slow stage runs them
def test_a_sweep_splits_its_rows_by_its_parameters_and_a_scorecard_names_them(pedestrian_installed, tmp_path,
                                                                              monkeypatch, capsys):
    from racf.experiments.scorecard import battery as battery_module
    from racf.experiments.scorecard.battery_types import Battery, LoopRow, paper_row as _paper
    from tests.conftest import write_bench_dataset

    spec = tmp_path / "walk.toml"
    spec.write_text('name = "walk"\ntarget = "pedestrian_crossing"\n[space]\nattack = ["none"]\nspeed = [1.0]\n'
                    'sign = [2]\n[scenario.pedestrian_crossing]\ngap_s = [0.0, 2.0]\n')
    code, _ = run_cli(["sweep", str(spec), "--out", str(tmp_path / "out"), "--workers", "1", "--json"])
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    met = "clean@pedestrian_crossing[ahead_m=1.0, gap_s=0.0, speed_mps=0.3, walks=True]"
    assert code == 0 and set(summary) == {met, "clean@pedestrian_crossing[ahead_m=1.0, gap_s=2.0, speed_mps=0.3, walks=True]"}
    assert summary[met]["n_no_pedestrian_collision"] == 1 and summary[met]["no_pedestrian_collision_rate"] == 1.0

    tiny = Battery(name="tiny-walk", loop=(LoopRow("paper_clean", "clean", 1, 1, _paper("clean"), attacked=False),),
                   drives=(), offline_presets=("strong",), offline_draws=1, offline_draws_quick=1)
    monkeypatch.setitem(battery_module.BATTERIES, "tiny-walk", tiny)
    data = write_bench_dataset(tmp_path / "data", n_series=10)
    code = run_cli(["scorecard", "--defence", "raw", "--battery", "tiny-walk", "--target", "pedestrian_crossing",
                    "--scenario-param", "gap_s=2.0", "--quick", "--workers", "1", "--out", str(tmp_path / "cards"),
                    "--dataset", str(data), "--json"])[0]
    assert code == 0
    assert (tmp_path / "cards" / "cards" / "tiny-walk@pedestrian_crossing_ahead_m=1.0_gap_s=2.0_speed_mps=0.3_walks=True_-quick"
            / "raw.json").exists()
