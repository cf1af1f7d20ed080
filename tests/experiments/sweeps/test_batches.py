"""Batches of trials on the one batch path: every sign and speed, resume, and the one summary."""

import json
import math

import pandas as pd
import pytest

from racf.experiments.sweeps.batches import batch_specs, run_batch
from racf.stats import wilson_interval
from racf.experiments.sweeps.summary import summarize


@pytest.mark.slow  # 2.1 s, a batch: the default run keeps under two minutes on 2 cores
def test_batch_covers_every_sign_and_speed_and_resumes(tmp_path, monkeypatch):
    specs = batch_specs("clean", 12)
    assert {(s.sign, s.speed) for s in specs} == {(g, v) for g in range(4) for v in (1.0, 1.5, 2.0)}
    assert len({s.seed for s in specs}) == 12
    two = batch_specs("clean", 2, seed=5)
    first = run_batch(two, tmp_path, workers=1, progress=False)
    assert len(first) == 2 and (tmp_path / "results.parquet").exists()
    # A rerun finds both trials finished and runs nothing.
    import racf.experiments.sweeps.executors as executors_module

    monkeypatch.setattr(executors_module, "run_episode", lambda *a, **k: pytest.fail("re-ran a finished trial"))
    again = run_batch(two, tmp_path, workers=1, progress=False)
    pd.testing.assert_frame_equal(first, again)


def test_summary_has_the_protocol_keys_and_wilson_interval():
    rows = pd.DataFrame({"setting": "attack", "success": [True] * 9 + [False],
                         "trigger_delay_s": [0.02] * 9 + [math.nan], "dt_brake_s": [0.1] * 9 + [math.nan],
                         "failure": [None] * 9 + ["confirmed_lost"],
                         "lost_frames": [0] * 9 + [30], "attack_start_s": [math.nan] * 8 + [2.0, 1.2],
                         "t_star_s": [1.5] * 10})
    s = summarize(rows, attack=True)
    assert set(s) == {"n", "n_scr", "scr", "scr_ci", "asr", "asr_ci", "trigger_delay_mean", "trigger_delay_std",
                      "dt_brake_mean", "dt_brake_std", "n_latency", "failures", "lost_frames_mean", "attacked_share",
                      "n_attack_before_t_star", "scr_attack_before_t_star", "scr_attack_before_t_star_ci",
                      "max_fused_jump_m"}
    assert s["max_fused_jump_m"] is None  # the rows carry no jumps
    assert summarize(rows.assign(fused_jump_m=[0.1] * 9 + [math.nan]))["max_fused_jump_m"] == 0.1
    # Only the last trial's attack began before t* (1.2 < 1.5 s), and it failed.
    assert s["n_attack_before_t_star"] == 1 and s["scr_attack_before_t_star"] == 0.0
    assert s["dt_brake_mean"] == pytest.approx(0.1) and s["trigger_delay_mean"] == pytest.approx(0.02)
    assert s["failures"]["confirmed_lost"] == 1 and sum(s["failures"].values()) == 1
    json.dumps(s, allow_nan=False)  # strict JSON
    assert s["lost_frames_mean"] == 3.0 and s["attacked_share"] == pytest.approx(0.2)
    assert s["n"] == 10 and s["scr"] == 0.9 and s["asr"] == pytest.approx(0.1) and s["n_latency"] == 9
    assert s["scr_ci"] == pytest.approx(list(wilson_interval(9, 10)))
    lo, hi = wilson_interval(9, 10)
    assert lo == pytest.approx(0.596, abs=1e-3) and hi == pytest.approx(0.982, abs=1e-3)
    assert summarize(rows.assign(setting="clean"))["asr"] is None


def test_a_sweeps_report_gives_the_scr_of_episodes_attacked_before_t_star(tmp_path):
    from racf.experiments.sweeps.report import write_report

    rows = pd.DataFrame({"trial_id": [f"t{i}" for i in range(4)], "setting": "attack", "attack": "patch_occlusion",
                         "estimator": "raw", "success": [True, True, False, True],
                         "trigger_delay_s": [0.0, 0.0, math.nan, 0.0], "dt_brake_s": [0.1, 0.1, math.nan, 0.1],
                         "failure": [None, None, "confirmed_lost", None], "lost_frames": [0, 0, 30, 5],
                         "attack_start_s": [3.0, 3.0, 1.0, 1.1], "t_star_s": [2.0] * 4,
                         "rho_set": 1.0, "t_atk_set": 2.0})
    write_report(rows, tmp_path, "t")
    summary = json.loads((tmp_path / "summary.json").read_text())["attack"]
    assert summary["n_attack_before_t_star"] == 2 and summary["scr_attack_before_t_star"] == 0.5
    assert "| attack | 4 | 0.75 [" in (tmp_path / "summary.md").read_text()
    assert "0.50 [" in (tmp_path / "summary.md").read_text()


def test_a_scenarios_parameters_key_its_summaries_apart():
    """Rows of one setting under a scenario's parameters group apart (cross-traffic's collision rate
    with one car, none without), and the rows say which parameters made them."""
    from racf.experiments.sweeps.summary import summarize_settings

    base = {"setting": "attack", "trigger_delay_s": math.nan, "dt_brake_s": math.nan, "lost_frames": 0,
            "t_star_s": 1.5}
    traffic = pd.DataFrame([{**base, "target": "cross_traffic", "scenario_cars": 1, "scenario_gap_s": 0.0,
                             "scenario_speed": 1.0, "success": ok, "failure": None if ok else "confirmed_lost",
                             "attack_start_s": start, "traffic_cars": 1, "collision": hit,
                             "conflict": "collision" if hit else "yielded", "min_ttc_s": 0.0 if hit else 1.2}
                            for ok, start, hit in [(True, 1.0, False), (False, 1.0, True), (False, 2.0, True),
                                                   (True, 2.0, False)]])
    # A plain row has no such parameters: NaN, which makes the column float, as a stored frame holds it.
    empty = traffic.assign(target="sign", scenario_cars=math.nan, scenario_gap_s=math.nan, scenario_speed=math.nan,
                           collision=False)
    empty = empty.drop(columns=["traffic_cars", "conflict", "min_ttc_s"])
    out = summarize_settings(pd.concat([traffic, empty], ignore_index=True))
    crossed = "attack@cross_traffic[cars=1, gap_s=0.0, speed=1.0]"
    assert set(out) == {"attack", crossed}
    s = out[crossed]
    assert s["n_traffic"] == 4 and s["collision_rate"] == 0.5
    assert s["collision_rate_ci"] == pytest.approx(list(wilson_interval(2, 4)))
    assert s["conflicts"]["collision"] == 2 and s["conflicts"]["yielded"] == 2
    # Over the attacks that began before t* (1.0 < 1.5 s): one of two hit the other car.
    assert s["n_traffic_attack_before_t_star"] == 2 and s["collision_rate_attack_before_t_star"] == 0.5
    assert "n_traffic" not in out["attack"]
    json.dumps(out, allow_nan=False)
    stale = pd.DataFrame([{**base, "target": "stale_map", "scenario_case": case, "scenario_shift_m": 1.0,
                           "success": None, "attack_start_s": math.nan} for case in ("removed", "phantom")])
    keys = set(summarize_settings(stale))
    assert keys == {"attack@stale_map[case=removed, shift_m=1.0]", "attack@stale_map[case=phantom, shift_m=1.0]"}


def test_the_report_gives_no_scr_where_no_sign_stands_and_each_criterion_where_it_applies(tmp_path):
    from racf.experiments.sweeps.report import write_report

    base = {"setting": "clean+vote", "attack": "none", "estimator": "vote", "target": "stale_map",
            "scenario_shift_m": 1.0, "trigger_delay_s": math.nan, "dt_brake_s": math.nan, "lost_frames": 0,
            "attack_start_s": math.nan, "t_star_s": math.nan, "failure": None, "rho_set": 0.95, "t_atk_set": 1.75}
    rows = pd.DataFrame([{**base, "scenario_case": "removed", "success": None, "stop_rule": None,
                          "no_needless_stop": False, "needless_stop": True},
                         {**base, "scenario_case": "mapped", "success": True, "stop_rule": True,
                          "no_needless_stop": None, "needless_stop": None}])
    write_report(rows, tmp_path, "t")
    text = (tmp_path / "summary.md").read_text()
    assert "| clean+vote@stale_map[case=removed, shift_m=1.0] | 1 | — (no sign stands) |" in text
    assert "| clean+vote@stale_map[case=removed, shift_m=1.0] | no_needless_stop | 0.00 [" in text
    assert "| clean+vote@stale_map[case=mapped, shift_m=1.0] | stop_rule | 1.00 [" in text
    assert "needless_stop, share (existence) | 1.000" in text and "| none | 1.00 (N 1) |" in text
