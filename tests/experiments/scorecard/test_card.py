"""A card end to end on a tiny battery: every section filled, strict JSON, a second run reuses
every episode and gives the same card bar its timings; the CLI names bad input in one line;
a plug-in defence gets a card with no edit to racf."""

import json

import pytest

from racf.experiments.cli import main
from racf.experiments.data.dataset import load_dataset
from racf.experiments.scorecard import battery as battery_module
from racf.experiments.scorecard.battery_types import Battery, LoopRow, paper_row as _paper, sweep_row as _sweep
from racf.experiments.scorecard.card import run_card
from racf.experiments.scorecard.report import compare_markdown, strict_json, write_scorecard
from tests.conftest import write_bench_dataset

TINY = Battery(name="tiny", loop=(
    LoopRow("paper_clean", "clean", 1, 1, _paper("clean"), attacked=False),
    LoopRow("stealth_ramp", "stealth_ramp", 1, 1,
            _sweep("adaptive", "stealth_ramp", mode="grid", params={"stealth_ramp": {"rate_mps": [3.0]}},
                   speed=[2.0])),
), drives=(), offline_presets=("strong",), offline_draws=1, offline_draws_quick=1)


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    return load_dataset(write_bench_dataset(tmp_path_factory.mktemp("data"), n_series=10), split="by_series")


def _without_timing(card):
    return {k: v for k, v in card.items() if k != "timing"}


@pytest.mark.slow  # 7 s: the default suite keeps under two minutes
def test_a_card_fills_every_section_and_a_rerun_reuses_everything(tmp_path, dataset):
    card = run_card("ekf", TINY, tmp_path, quick=True, dataset=dataset, workers=1, progress=False)
    assert set(card["closed_loop"]) == {"paper_clean", "stealth_ramp"} and card["battery"] == "tiny-quick"
    assert card["closed_loop"]["stealth_ramp"]["n"] == 4  # grid: the four signs
    assert card["detection"]["n_positive_steps"] > 0 and card["detection"]["auroc_from"] == "score"
    assert card["offline"]["strong"]["rmse"] is not None and "strong_ratio_to_chronos" in card["offline"]
    assert card["cost"]["parameters"] == {"trainable": 0, "frozen": 0, "from": "declared"}
    from racf.experiments.scorecard.card import racf_commit

    assert card["commit"] == racf_commit() and card["options"] == {}  # what `racf board check` asks of it
    again = run_card("ekf", TINY, tmp_path, quick=True, dataset=dataset, workers=1, progress=False)
    assert strict_json(_without_timing(again)) == strict_json(_without_timing(card))
    assert card["timing"]["episodes_run"] == card["timing"]["episodes"] == 5 and again["timing"]["episodes_run"] == 0
    paths = write_scorecard([card], tmp_path)
    assert "NaN" not in paths["json"].read_text() and paths["md"].read_text().lower().count("quick battery") == 1
    page = paths["card ekf"].read_text()  # its page: the ROC (or why none) and the ramp's plot, under their sections
    assert page.count("data:image/png;base64") + page.count("No ROC to draw") == 2
    assert "<table" in page and "|---" not in page  # tables, not Markdown


def test_compare_marks_rows_whose_intervals_do_not_overlap():
    def card(name, scr, ci):
        return {"defence": name, "battery": "racf-1", "drives": {}, "cost": {"parameters": {"trainable": 0,
                "from": "declared"}}, "closed_loop": {"r": {"title": "row", "scr": scr, "scr_ci": ci, "n": 30}}}
    text = compare_markdown(card("a", 0.9, [0.8, 0.95]), card("b", 0.3, [0.2, 0.5]))
    assert "**yes: a**" in text
    assert "**yes" not in compare_markdown(card("a", 0.9, [0.6, 0.95]), card("b", 0.7, [0.5, 0.8]))


@pytest.mark.parametrize("argv,message", [
    (["--defence", "nope"], "unknown defence(s) ['nope']"),
    (["--defence", "raw", "--battery", "racf-0"], "unknown battery 'racf-0'; released: racf-1"),
    (["--compare", "raw", "odca"], "no card"),
    (["--attack", "nope"], "unknown attack 'nope'"),
])
def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys, argv, message):
    assert main(["scorecard", *argv, "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "\n" not in err


@pytest.mark.slow  # 6 s: the default suite keeps under two minutes
def test_the_example_plugin_defence_gets_a_card_with_no_edit_to_racf(cusum_installed, tmp_path, dataset,
                                                                       monkeypatch, capsys):
    monkeypatch.setitem(battery_module.BATTERIES, "tiny", TINY)
    data = tmp_path / "data"
    write_bench_dataset(data, n_series=10)
    code = main(["scorecard", "--defence", "lidar_cusum", "--battery", "tiny", "--quick", "--workers", "1",
                 "--out", str(tmp_path), "--dataset", str(data), "--json"])
    assert code == 0
    card = json.loads(capsys.readouterr().out)["cards"][0]
    assert card["defence"] == "lidar_cusum" and card["detection"]["n_positive_steps"] > 0
    assert (tmp_path / "cards" / "tiny-quick" / "lidar_cusum.json").exists()


#: A battery of one row of 12 episodes, for the kill-and-resume test's subprocess.
_SMALL_BATTERY = """
import sys

from racf.experiments.cli import main
from racf.experiments.scorecard import battery as b

b.BATTERIES["small"] = b.Battery(name="small", loop=(b.LoopRow("paper_clean", "clean", 12, 12, b.paper_row("clean"),
                                                               attacked=False),),
                                 drives=(), offline_presets=("strong",), offline_draws=1, offline_draws_quick=1)
if __name__ == "__main__":  # the pool's spawned workers import this file again
    sys.exit(main(sys.argv[1:]))
"""


@pytest.mark.slow
def test_a_sigkilled_quick_battery_resumes_without_redoing_finished_episodes(tmp_path):
    import os
    import signal
    import subprocess
    import sys
    import time

    data = write_bench_dataset(tmp_path / "data", n_series=10)
    script = tmp_path / "small_battery.py"
    script.write_text(_SMALL_BATTERY)
    argv = [sys.executable, str(script), "scorecard", "--defence", "raw", "--battery", "small", "--quick", "--out",
            str(tmp_path / "out"), "--dataset", str(data), "--json"]
    proc = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    parts = tmp_path / "out" / "episodes"
    deadline = time.time() + 600
    while time.time() < deadline and sum(1 for _ in parts.rglob("parts/*.parquet")) < 4:
        assert proc.poll() is None, "the battery ended before it was killed"
        time.sleep(0.2)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    done = sum(1 for _ in parts.rglob("parts/*.parquet"))
    out = subprocess.run(argv, capture_output=True, text=True, check=True).stdout
    timing = json.loads(out)["cards"][0]["timing"]
    assert 4 <= done < 12 and timing["episodes_run"] == timing["episodes"] - done  # only the unfinished ran


@pytest.mark.slow
def test_an_attack_card_runs_the_attack_against_every_defence(tmp_path, monkeypatch):
    from racf.experiments.scorecard import attack_card
    from racf.plugins import ESTIMATORS

    monkeypatch.setattr(attack_card, "ATTACK_DRAWS", (1, 1))
    card = attack_card.run_attack_card("stealth_ramp", tmp_path, quick=True, workers=1, progress=False)
    assert set(card["defences"]) == set(ESTIMATORS) and all(r["n"] == 1 for r in card["defences"].values())
    assert "stealth_ramp" in attack_card.attack_card_markdown(card) and "QUICK" in attack_card.attack_card_markdown(card)
