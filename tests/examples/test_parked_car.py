"""The example scenario, installed with pip and used with no edit to racf: it is listed with its
parameters, a trial runs it (and its van hides the sign), a sweep spec and a falsification space
take its parameters, and editing it renews its episodes' ids."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from racf.experiments.cli import main
from tests.conftest import run_cli


def test_the_scenario_is_listed_with_its_parameters(parked_car_installed):
    code, out = run_cli(["list", "--json"])
    entry = json.loads(out)["scenario"]["parked_car"]
    assert code == 0 and entry["origin"] == "racf-parked-car"
    assert entry["params"]["ahead_m"]["low"] == 0.2 and entry["params"]["ahead_m"]["unit"] == "m"


@pytest.mark.slow  # 2.2 s, an episode: the default run keeps under two minutes on 2 cores
def test_a_trial_runs_it_and_the_van_hides_the_sign_for_the_far_part(parked_car_installed, tmp_path):
    first_seen = {}
    for target in ("sign", "parked_car"):
        code, out = run_cli(["trial", "--target", target, "--sign", "1", "--speed", "1.0",
                             "--out", str(tmp_path / target), "--json"])
        assert code == 0
        row = json.loads(out)
        log = pd.read_parquet(row["log"])
        assert row["target"] == target
        first_seen[target] = log.loc[log["sign_in_view"].astype(bool), "t"].min()
    assert first_seen["parked_car"] > first_seen["sign"] + 0.5  # hidden for half a second or more


def test_a_bad_parameter_is_one_line_naming_the_range(parked_car_installed, capsys):
    code = main(["trial", "--target", "parked_car", "--scenario-param", "ahead_m=9", "--out", "/tmp/racf-unused"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "ahead_m" in err and "[0.2, 2.5]" in err


def test_a_sweep_spec_and_a_falsification_space_take_its_parameters(parked_car_installed, tmp_path):
    from racf.experiments.falsify.space import load_space
    from racf.experiments.sweeps.spec import parse_spec

    sweep = parse_spec('name = "van"\ntarget = "parked_car"\n[space]\nsign = [0]\nattack = ["none"]\n'
                       '[scenario.parked_car]\nahead_m = [0.5, 1.5]\n')
    assert [e.scenario_params["ahead_m"] for e in sweep.episodes()] == [0.5, 1.5]
    assert {e.target for e in sweep.episodes()} == {"parked_car"}
    space_file = tmp_path / "space.toml"
    space_file.write_text('[scenario]\ntarget = "parked_car"\nsign = [0, 3]\n'
                          '[scenario.parked_car]\nahead_m = {low = 0.3, high = 2.0}\n')
    space = load_space("odca", ("dropout_timed",), space_file)
    spec = space.trial_spec({"sign": 3, "scenario.parked_car.ahead_m": 0.7}, seed=1)
    assert spec.target == "parked_car" and spec.scenario_params == {"ahead_m": 0.7, "kerb_gap_m": 0.16}


def test_editing_the_scenario_renews_its_ids(parked_car_installed):
    from tests.conftest import _forget_plugins

    from racf.experiments.episode import TrialSpec

    before = TrialSpec("clean", 0, 1.0, 0, target="parked_car").trial_id
    source = parked_car_installed / "__init__.py"
    source.write_text(source.read_text().replace("VAN_SIZE_M = (0.40, 0.22, 0.35)", "VAN_SIZE_M = (0.45, 0.22, 0.35)"))
    _forget_plugins()
    assert TrialSpec("clean", 0, 1.0, 0, target="parked_car").trial_id != before


@pytest.mark.slow  # a sweep or a card end to end: CI's slow stage runs it
def test_a_sweep_runs_it(parked_car_installed, tmp_path):
    from racf.experiments.sweeps.store import ResultStore

    spec = tmp_path / "van.toml"
    spec.write_text('name = "van"\ntarget = "parked_car"\n[space]\nattack = ["none"]\nspeed = [1.0]\nsign = [1]\n'
                    '[scenario.parked_car]\nahead_m = [0.5]\n')
    code, _ = run_cli(["sweep", str(spec), "--out", str(tmp_path / "out"), "--workers", "1", "--json"])
    rows = ResultStore(tmp_path / "out").rows()
    assert code == 0 and rows["target"].tolist() == ["parked_car"]


@pytest.mark.slow  # a sweep or a card end to end: CI's slow stage runs it
def test_a_scorecard_runs_a_battery_in_it(parked_car_installed, tmp_path, monkeypatch, capsys):
    from racf.experiments.scorecard import battery as battery_module
    from racf.experiments.scorecard.battery_types import Battery, LoopRow, paper_row as _paper
    from tests.conftest import write_bench_dataset

    tiny = Battery(name="tiny-van", loop=(LoopRow("paper_clean", "clean", 1, 1, _paper("clean"), attacked=False),),
                   drives=(), offline_presets=("strong",), offline_draws=1, offline_draws_quick=1)
    monkeypatch.setitem(battery_module.BATTERIES, "tiny-van", tiny)
    data = write_bench_dataset(tmp_path / "data", n_series=10)
    code = main(["scorecard", "--defence", "raw", "--battery", "tiny-van", "--target", "parked_car",
                 "--scenario-param", "ahead_m=0.5", "--quick", "--workers", "1", "--out", str(tmp_path),
                 "--dataset", str(data), "--json"])
    card = json.loads(capsys.readouterr().out)["cards"][0]
    name = "tiny-van@parked_car[ahead_m=0.5, kerb_gap_m=0.16]-quick"
    assert code == 0 and card["battery"] == name and card["closed_loop"]["paper_clean"]["n"] == 1
    # The parameters are in the card's name and its file: another ahead_m never overwrites it.
    assert (tmp_path / "cards" / "tiny-van@parked_car_ahead_m=0.5_kerb_gap_m=0.16_-quick" / "raw.json").exists()
