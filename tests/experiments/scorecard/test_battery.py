"""The released batteries: each keeps its episodes, and each names the car's detector in its rows."""

import dataclasses

from racf.experiments.scorecard.battery import BATTERIES, DEFAULT_BATTERY


def _detectors(battery, defence="odca"):
    return {row.key: {spec.detector for spec in row.specs(defence, quick=True)} for row in battery.rows()}


def test_every_row_runs_the_batterys_detector_unless_it_says_otherwise():
    for name, battery in BATTERIES.items():
        for key, detectors in _detectors(battery).items():
            if key == "sticker":  # the first sticker's row attacks the learned segmenter by its title
                assert detectors == {"learned"}
            else:
                assert detectors == {battery.detector}, (name, key)


def test_each_battery_is_the_one_before_and_its_new_rows():
    one, two, three = (BATTERIES[n] for n in ("racf-1", "racf-2", "racf-3"))
    assert [r.key for r in two.rows()] == [r.key for r in one.loop] + ["frustum_scaled", "sticker_default"] + \
        [r.key for r in one.drives]
    for row in one.rows():  # racf-1's episodes are racf-2's (ids included): a battery never changes
        same = next(r for r in two.rows() if r.key == row.key)
        assert [s.trial_id for s in row.specs("raw", quick=True)] == [s.trial_id for s in same.specs("raw", quick=True)]
    assert [r.key for r in three.rows()] == [r.key for r in two.loop] + ["sticker_placed"] + [r.key for r in two.drives]
    assert three.detector == two.detector == one.detector == "classical"
    four = BATTERIES["racf-4"]
    assert [r.key for r in four.rows()] == [r.key for r in three.loop] + ["traffic_strong"] + \
        [r.key for r in three.drives]
    for row in three.rows():  # racf-3's episodes are racf-4's
        same = next(r for r in four.rows() if r.key == row.key)
        assert [s.trial_id for s in row.specs("raw", quick=True)] == [s.trial_id for s in same.specs("raw", quick=True)]
    traffic = next(r for r in four.loop if r.key == "traffic_strong")
    assert traffic.driving and all(s.scenario_params.get("cars") == 1 for s in traffic.specs("odca"))
    assert DEFAULT_BATTERY == "racf-4"


def test_a_battery_in_a_scenario_is_named_with_its_parameters_and_stored_apart():
    """Two cards of one scenario with other parameters never share a name or a file."""
    from pathlib import Path

    from racf.experiments.cli.scorecard import _card_path
    from racf.experiments.scorecard.battery import BATTERIES

    removed = BATTERIES["racf-4"].in_scenario("stale_map", {"case": "removed"})
    phantom = BATTERIES["racf-4"].in_scenario("stale_map", {"case": "phantom"})
    assert removed.name == "racf-4@stale_map[case=removed, shift_m=1.0]"
    paths = {_card_path(Path("out"), b.name, "raw") for b in (removed, phantom)}
    assert len(paths) == 2 and Path("out/cards/racf-4@stale_map_case=removed_shift_m=1.0/raw.json") in paths
    assert BATTERIES["racf-4"].in_scenario("sign").name == "racf-4@sign"


def test_racf_6_follows_the_car_ahead_through_its_profiles_paired_over_defences():
    six = BATTERIES["racf-6"]
    assert [r.key for r in six.rows()] == ["following_clean", "following_patch", "following_frustum",
                                          "following_frustum_depth", "following_hide", "following_phantom"]
    for row in six.rows():
        specs = row.specs("odca")
        assert len(specs) == 60 and {s.target for s in specs} == {"lead_vehicle"}
        profiles = [s.scenario_params["profile"] for s in specs]
        assert {profiles.count(p) for p in ("cruise", "slow_down", "hard_brake", "stop_and_go")} == {15}
        # The same episodes for every defence: only the defence differs.
        assert [(s.seed, s.scenario_params) for s in row.specs("raw")] == [(s.seed, s.scenario_params) for s in specs]
    depth = next(r for r in six.loop if r.key == "following_frustum_depth").specs("odca")[0]
    assert depth.attack_params == {"lead_frustum": {"depth": True}}
    assert not six.rows()[0].attacked and six.rows()[0].specs("odca")[0].setting == "clean+odca"
    assert six.offline_presets == () and six.drives == ()


def test_a_following_row_is_rated_by_what_its_criteria_declare_not_by_scr():
    import pandas as pd

    from racf.experiments.scorecard.card import _loop_summary
    from racf.experiments.scorecard.rows import card_rows

    frame = pd.DataFrame({"target": "lead_vehicle", "setting": "clean+lead_patch+odca",
                          "no_lead_collision": [True, True, True, False, None],
                          "no_needless_hard_brake": [True, False, True, False, None], "lost_frames": 0,
                          "attack_start_s": 2.0, "driving_score": 1.0, "collision": False})
    summary = _loop_summary(frame, attacked=True)
    declared = {m["measure"]: m for m in summary["headline"]}  # Criterion.card: NoLeadCollision, NoNeedlessHardBrake
    assert declared["collision-free"]["n"] == 4  # an episode the criterion does not apply to is left out
    assert declared["collision-free"]["value"] == 0.75 and declared["needless hard brake"]["value"] == 0.5
    assert declared["collision-free"]["ci"][0] < 0.75 < declared["collision-free"]["ci"][1]
    assert not {"scr", "asr", "failures", "robustness_median_m"} & set(summary)  # the stop rule's: they do not apply
    card = {"battery": "racf-6", "closed_loop": {"following_phantom": {"title": "t", "n": 4, **summary}}, "drives": {},
            "cost": {"parameters": {"from": "none", "trainable": 0}}}
    measures = {m: (v, n) for _, _, m, v, _, n, _ in card_rows(card)}
    assert not {"SCR", "SCR, attack before t*", "STL robustness m, median"} & set(measures)  # the stop rule's
    assert measures["collision-free"] == (0.75, 4)
    assert measures["needless hard brake"] == (0.5, 4)


def test_a_card_written_before_the_criteria_declared_their_measures_reads_the_same():
    from racf.experiments.scorecard.card_format import current_row

    old = {"title": "t", "n": 60, "n_following": 60, "scr": None, "asr": 1.0, "failures": {"braked_early": 45},
           "collision_free": 0.9, "collision_free_ci": [0.8, 0.95], "needless_hard_brake": 0.1,
           "needless_hard_brake_ci": [0.05, 0.2]}
    row = current_row(old)
    assert row["headline"] == [{"measure": "collision-free", "value": 0.9, "ci": [0.8, 0.95], "n": 60, "higher_is_better": True},
                               {"measure": "needless hard brake", "value": 0.1, "ci": [0.05, 0.2], "n": 60,
                                "higher_is_better": False}]
    assert not {"asr", "failures", "scr", "n_following"} & set(row) and current_row(row) == row


def test_rows_whose_criteria_declare_no_card_measure_put_none_on_the_card():
    import pandas as pd

    from racf.experiments.metrics.criteria import card_measures

    signs = pd.DataFrame({"target": "sign", "stop_rule": [True, False], "no_needless_stop": [None, None]})
    assert card_measures(signs) == []
    assert card_measures(signs.assign(target="lead_vehicle")) == []  # its criteria's columns are not in the rows


def test_racf_7_pairs_each_following_row_alone_and_under_the_supervisor_on_the_same_episodes():
    seven, six = BATTERIES["racf-7"], BATTERIES["racf-6"]
    following = ["following_clean", "following_patch", "following_frustum_depth", "following_adaptive",
                 "following_hide", "following_phantom"]
    broadcast = ["broadcast_clean", "broadcast_adaptive", "broadcast_jammed", "broadcast_replayed", "broadcast_forged",
                 "broadcast_lie", "broadcast_lie_spoofed"]
    assert [r.key for r in seven.rows()] == following + [f"{k}_supervised" for k in following] + \
        [f"{k}_supervised" for k in broadcast] + ["temporary_sticker", "patch_whole_approach"]
    for key in following:
        alone = next(r for r in seven.loop if r.key == key).specs("odca", quick=True)
        supervised = next(r for r in seven.loop if r.key == f"{key}_supervised").specs("odca", quick=True)
        assert not any(s.supervisor for s in alone) and all(s.supervisor for s in supervised)
        assert [dataclasses.replace(s, supervisor=False) for s in supervised] == alone
        assert all("+supervisor_" in s.trial_id for s in supervised)
        if key in {r.key for r in six.loop}:  # racf-6's episodes, alone, are racf-7's at full N: ids included
            same = next(r for r in six.loop if r.key == key).specs("odca")
            assert [s.trial_id for s in same] == [s.trial_id for s in next(r for r in seven.loop if r.key == key)
                                                                   .specs("odca")]
    # The broadcast rows: the supervised rows' episodes with the lead broadcasting (the same seeds).
    def row(key):
        return next(r for r in seven.loop if r.key == key).specs("odca", quick=True)

    for key, silent in (("broadcast_clean", "following_clean"), ("broadcast_adaptive", "following_adaptive")):
        told = row(f"{key}_supervised")
        assert all(s.scenario_params["broadcast"] == "on" and s.supervisor for s in told)
        assert [dataclasses.replace(s, scenario_params={**s.scenario_params, "broadcast": "off"}) for s in told] == \
            row(f"{silent}_supervised")
    lie = row("broadcast_lie_spoofed_supervised")[0]
    assert lie.setting == "clean+lead_frustum+radio_lie+odca"
    assert lie.attack_params["radio_lie"] == {"bias_m": 2.0, "rate_mps": 0.5, "faster_mps": 0.5}
    adaptive = next(r for r in seven.loop if r.key == "following_adaptive").specs("odca")[0]
    assert adaptive.attack_params["lead_frustum"] == {"depth": True, "scale_box": True, "rate_mps": 0.5, "bias_m": 2.0}


def test_racf_link_2_is_racf_link_with_the_onboard_fallback():
    old, new = BATTERIES["racf-link"], BATTERIES["racf-link-2"]
    assert [(r.key, r.title, r.n, r.link, r.attacked) for r in old.loop] == \
        [(r.key, r.title, r.n, r.link, r.attacked) for r in new.loop]
    for a, b in zip(old.loop, new.loop):
        before, after = a.specs("odca", quick=True), b.specs("odca", quick=True)
        assert all(s.estimator_fallback == "raw" for s in before) and all(s.estimator_fallback == "odca" for s in after)
        assert [dataclasses.replace(s, estimator_fallback="raw") for s in after] == before
