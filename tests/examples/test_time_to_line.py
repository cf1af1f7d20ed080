"""The example metric, installed with pip and used with no edit to racf: it is listed with its
field, scored in every result row, summarised in a sweep's summary and report, shown as a
scorecard row, and editing it renews the ids of the episodes it scores."""

from __future__ import annotations

import json
import math

import pytest

from racf.experiments.cli import main
from tests.conftest import run_cli
from racf.experiments.sweeps.store import ResultStore

TINY = 'name = "ttl"\n[space]\nattack = ["patch_occlusion"]\nrho = [1.0]\nt_atk = [2.0]\nspeed = [1.5]\nsign = [1]\n'


def test_the_metric_is_listed_with_its_field(time_to_line_installed):
    code, out = run_cli(["list", "--json"])
    entry = json.loads(out)["metric"]["time_to_line"]
    assert code == 0 and entry["origin"] == "racf-time-to-line" and entry["always"]
    assert entry["fields"]["time_to_line_s"] == {"unit": "s", "summary": "median",
                                                 "meaning": "time to the stop line at the car's speed when the "
                                                            "attack began"}


def test_a_sweep_scores_summarises_and_reports_it(time_to_line_installed, tmp_path):
    spec = tmp_path / "ttl.toml"
    spec.write_text(TINY)
    code, _ = run_cli(["sweep", str(spec), "--out", str(tmp_path / "out"), "--workers", "1", "--json"])
    assert code == 0
    rows = ResultStore(tmp_path / "out").rows()
    value = float(rows["time_to_line_s"].iloc[0])
    # The attack began with the stop line ahead, at 1.5 m/s: a few seconds to go, not more than the run-up allows.
    assert rows["attack_start_s"].notna().all() and 0.0 < value < 5.0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())["attack"]
    assert summary["n_time_to_line_s"] == 1 and math.isclose(summary["time_to_line_s_median"], value)
    report = (tmp_path / "out" / "summary.md").read_text()
    assert "time_to_line_s s, median (time_to_line)" in report


@pytest.mark.slow  # a sweep or a card end to end: CI's slow stage runs it
def test_a_scorecard_row_shows_it(time_to_line_installed, tmp_path, monkeypatch, capsys):
    from racf.experiments.scorecard import battery as battery_module
    from racf.experiments.scorecard.battery_types import Battery, LoopRow, paper_row as _paper
    from racf.experiments.scorecard.rows import card_rows
    from tests.conftest import write_bench_dataset

    tiny = Battery(name="tiny-ttl", loop=(LoopRow("paper_attack", "attack", 1, 1, _paper("attack")),), drives=(),
                   offline_presets=("strong",), offline_draws=1, offline_draws_quick=1)
    monkeypatch.setitem(battery_module.BATTERIES, "tiny-ttl", tiny)
    data = write_bench_dataset(tmp_path / "data", n_series=10)
    code = main(["scorecard", "--defence", "raw", "--battery", "tiny-ttl", "--quick", "--workers", "1",
                 "--out", str(tmp_path), "--dataset", str(data), "--json"])
    card = json.loads(capsys.readouterr().out)["cards"][0]
    rows = [r for r in card_rows(card) if r[2] == "time_to_line_s s, median (time_to_line)"]
    assert code == 0 and len(rows) == 1 and rows[0][5] == 1 and rows[0][6] is True


def test_editing_the_metric_renews_the_ids_it_scores(time_to_line_installed):
    from tests.conftest import _forget_plugins

    from racf.experiments.episode import TrialSpec

    before = TrialSpec("attack", 0, 1.0, 0).trial_id
    source = time_to_line_installed / "__init__.py"
    text = source.read_text()
    source.write_text(text.replace('max(float(step["speed"]), 0.05)', 'max(float(step["speed"]), 0.1)'))
    _forget_plugins()
    assert TrialSpec("attack", 0, 1.0, 0).trial_id != before
