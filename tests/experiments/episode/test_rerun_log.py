"""An episode written to rerun reads back with rerun's own reader: entities and timeline length."""

import numpy as np
import pytest

from racf.sim.world.lead_manager import LeadManager

from racf.experiments.episode import TrialSpec, run_trial
from racf.experiments.episode.rerun_log import (CONTROL, SERIES, STYLE, FrameRecorder, _blueprint, _shown, target_depth_true,
                                               write_rrd)


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    recorder = FrameRecorder(every=5)
    _, log = run_trial(TrialSpec("attack+odca", 1, 1.5, 0), on_step=recorder)
    path = write_rrd(tmp_path_factory.mktemp("rrd") / "episode.rrd", log, recorder)
    return path, log, recorder


def _chunks(path):
    from rerun.chunk import RrdReader

    return list(RrdReader(str(path)).stream())


def test_entities_and_timeline_length_match_the_episode(recorded):
    path, log, recorder = recorded
    rows: dict[str, int] = {}
    times: dict[str, list] = {}
    for chunk in _chunks(path):
        name = str(chunk.entity_path)
        if "sim_time" not in chunk.timeline_names:  # static: styles, the map, the car's body
            rows.setdefault(name, 0)
            continue
        rows[name] = rows.get(name, 0) + chunk.num_rows
        if "sim_time" in chunk.timeline_names:
            batch = chunk.to_record_batch()
            times.setdefault(name, []).extend(batch.column("sim_time").to_pylist())
    for name in [f"/series/{k}" for k in SERIES] + [f"/control/{k}" for k in CONTROL] + ["/estimator/odca_source"]:
        assert rows[name] == len(log), name  # one sample per step on the sim_time timeline
        assert len(set(times[name])) == len(log)
    for name in ("/world/camera/image", "/world/camera/depth", "/world/car/lidar", "/world/car", "/map/car"):
        assert rows[name] == len(recorder.frames) == int(np.ceil(len(log) / 5)), name
    for name in ("/world/camera", "/map/mat", "/world/car/body", "/map/trajectory", "/map/trajectory_estimate", "/map/stop_signs",
                 "/world/camera/image/detection",
                 "/world/camera/image/patch", "/world/car/lidar/track"):
        assert name in rows, name


def test_the_patch_is_boxed_only_while_the_attack_is_active(recorded):
    _, log, recorder = recorded
    active = log.set_index("t")["attack_active"]
    boxed = [f.patch_box is not None for f in recorder.frames]
    assert any(boxed)
    assert all(active.loc[f.t] for f, b in zip(recorder.frames, boxed) if b)


def test_bad_input_is_refused(tmp_path):
    with pytest.raises(ValueError, match="every"):
        FrameRecorder(every=0)
    import pandas as pd

    with pytest.raises(ValueError, match="empty"):
        write_rrd(tmp_path / "x.rrd", pd.DataFrame())


@pytest.mark.slow  # 2.5-6 s: the default run keeps under two minutes on 2 cores
def test_trials_record_every_trial_they_run(tmp_path):
    from racf.experiments.sweeps.batches import batch_specs, run_batch

    specs = batch_specs("clean", 2, signs=(1,), speeds=(1.5,))
    run_batch(specs, tmp_path, workers=1, progress=False, rerun=True)
    assert sorted(p.stem for p in (tmp_path / "trials").glob("*.rrd")) == sorted(s.trial_id for s in specs)


def test_every_series_has_its_own_colour_and_legend_and_gaps_where_undefined(recorded):
    _, log, _ = recorded
    assert set(STYLE) == set(SERIES) | set(CONTROL) | {"target_true"}
    colours = [colour for colour, _ in STYLE.values()]
    assert len(set(colours)) == len(colours)
    shown = _shown(log, "d_true")
    assert np.isnan(shown[~log["sign_in_view"].to_numpy(bool)]).all()
    gate = _shown(log, "w")
    assert np.isnan(gate[~np.isfinite(log["d_fused"].to_numpy(float))]).all()  # no target: no gate drawn


def test_the_default_layout_shows_the_story():
    blueprint = _blueprint()
    names = [view.name for view in _views(blueprint.root_container)]
    assert names == ["camera (detection green, patch magenta)", "depth", "distances (m)", "gate w, brake, attack",
                     "existence witnesses (1: says a sign stands)", "the car's stages (m from the camera)", "map (top view)",
                     "car, camera and LiDAR"]


def _views(container):
    for item in container.contents:
        if hasattr(item, "contents") and not hasattr(item, "class_identifier"):
            yield from _views(item)
        else:
            yield item


@pytest.mark.slow  # 1.3 s, an episode: the default run keeps under two minutes on 2 cores
def test_other_cars_appear_in_the_world_and_on_the_map(tmp_path):
    recorder = FrameRecorder(every=10)
    _, log = run_trial(TrialSpec("clean", 3, 1.5, 0, target="cross_traffic", scenario_params={"cars": 2}), on_step=recorder, clean_pass=False)
    rows: dict[str, int] = {}
    for chunk in _chunks(write_rrd(tmp_path / "traffic.rrd", log, recorder)):
        rows[str(chunk.entity_path)] = rows.get(str(chunk.entity_path), 0) + chunk.num_rows
    # The cars and the conflict point are the world manager's columns: drawn as actors, named as logged.
    for k in (0, 1):
        assert rows[f"/world/actors/traffic{k}"] == len(recorder.frames)
        assert rows[f"/map/actors/traffic{k}/now"] == len(recorder.frames)
        assert f"/map/actors/traffic{k}/path" in rows
    assert "/map/actors/conflict" in rows and "/world/actors/traffic2" not in rows


@pytest.mark.slow  # 2.5-6 s: the default run keeps under two minutes on 2 cores
def test_the_car_ahead_and_its_witnesses_are_drawn(tmp_path):
    recorder = FrameRecorder(every=25)
    _, log = run_trial(TrialSpec("clean+odca", 1, 1.0, 0, target="lead_vehicle"), on_step=recorder, clean_pass=False)
    rows: dict[str, int] = {}
    target = LeadManager().targets()[0]
    for chunk in _chunks(write_rrd(tmp_path / "lead.rrd", log, recorder, targets=(target,))):
        rows[str(chunk.entity_path)] = rows.get(str(chunk.entity_path), 0) + chunk.num_rows
    assert rows["/world/actors/lead"] == len(recorder.frames) and "/map/actors/lead/path" in rows
    # The following stage's own series (``FollowingStage.series``), under its name, beside the truth.
    assert {f"/stages/following/{k}" for k in ("lead_d_meas", "lead_lidar", "lead_d_size", "lead_d_fused")} <= set(rows)
    assert "/stages/truth/lead" in rows  # the declared target's truth
    # The truth is the lead's rear from the camera: the LiDAR's track of it reads it within a few centimetres.
    true, lidar = target_depth_true(log, target), log["lead_lidar"].to_numpy(float)
    both = np.isfinite(lidar)
    assert both.sum() > 50 and np.median(np.abs(lidar[both] - true[both])) < 0.05


@pytest.mark.slow
def test_an_existence_defences_witnesses_have_their_own_panel(tmp_path):
    _, log = run_trial(TrialSpec("clean+vote", 2, 1.5, 0, target="stale_map"), clean_pass=False)
    entities = {str(chunk.entity_path) for chunk in _chunks(write_rrd(tmp_path / "vote.rrd", log))}
    assert {"/existence/wit_depth", "/existence/wit_map", "/existence/stands"} <= entities
    assert not [e for e in entities if e.startswith("/estimator/wit_")]
