"""Episode specs: settings, content-hashed ids (stale-result protection) and bad flags rejected early."""

import dataclasses

import pytest

import racf.experiments.episode.spec as spec_module
from racf.controllers import BrakingConfig
from racf.experiments.cli import main
from racf.experiments.episode import TABLE_SETTINGS, TrialSpec, parse_setting, setting_name


def test_settings_parse_into_attacks_and_estimator():
    assert parse_setting("clean") == ((), "raw")
    assert parse_setting("attack+odca") == (("patch_occlusion",), "odca")
    assert parse_setting("attack+lidar_spoof+odca") == (("patch_occlusion", "lidar_spoof"), "odca")
    assert setting_name(["lidar_spoof", "patch_occlusion"], "ekf") == "attack+lidar_spoof+ekf"
    for name in TABLE_SETTINGS:
        assert setting_name(*parse_setting(name)) == name
    with pytest.raises(ValueError, match="unknown attack"):
        setting_name(["laser"], "raw")


def test_the_id_changes_with_the_spec_the_configs_and_the_code(monkeypatch):
    base = TrialSpec("attack+odca", 1, 1.5, 7)
    assert base.trial_id == TrialSpec("attack+odca", 1, 1.5, 7).trial_id
    others = [TrialSpec("attack+ekf", 1, 1.5, 7), TrialSpec("attack+odca", 1, 1.5, 7, rho=1.0),
              TrialSpec("attack+odca", 1, 1.5, 7, delay_ms=49.0),
              TrialSpec("attack+odca", 1, 1.5, 7, braking=BrakingConfig(confirm_frames=4)),
              TrialSpec("attack+odca", 1, 1.5, 7, sensor_profile="ideal"),
              TrialSpec("attack+odca", 1, 1.5, 7, sign_geometry="pole")]
    assert len({base.trial_id, *(o.trial_id for o in others)}) == 1 + len(others)
    base_id = base.trial_id  # the id is computed on access: keep the one from before the edit
    monkeypatch.setattr(spec_module, "code_version", lambda *roots: "edited")
    assert TrialSpec("attack+odca", 1, 1.5, 7).trial_id != base_id


def test_bad_sensor_profile_and_sign_geometry_are_named_with_what_is_allowed():
    with pytest.raises(ValueError, match=r"sensor_profile must be one of \('qcar2', 'ideal'\), got 'true'"):
        TrialSpec("clean", 0, 1.5, 0, sensor_profile="true")
    with pytest.raises(ValueError, match=r"sign_geometry must be one of \('plate', 'pole'\), got 'post'"):
        TrialSpec("clean", 0, 1.5, 0, sign_geometry="post")


def test_attack_waits_for_more_steps_than_confirmation_needs():
    spec = TrialSpec("attack", 0, 1.0, 0)
    assert spec.attack_stable_steps > spec.braking.confirm_frames
    assert dataclasses.replace(spec, stable_steps=4).attack_stable_steps == 4
    # A 20 Hz controller with the paper's 49 ms delay needs longer: 6 of its steps + the delay.
    slow = dataclasses.replace(spec, control_hz=20.0, delay_ms=49.0)
    assert slow.attack_stable_steps == 6 * 2 + 2


@pytest.mark.parametrize("argv, message", [
    (["--estimator", "kalman"], "estimator must be one of"),
    (["--attack", "patch,laser"], "unknown attack"),
    (["--setting", "attack+foo"], "unknown part"),
    (["--setting", "attack", "--estimator", "odca"], "not both"),
    (["--setting", "clean", "--rho", "0.5"], "apply to settings with an attack"),
    (["--setting", "attack", "--control-hz", "200"], "control_hz"),
    (["--table", "--estimator", "odca"], "--table runs its own settings"),
])
def test_bad_flags_are_rejected_before_any_episode_runs(argv, message, monkeypatch, capsys, tmp_path):
    import racf.experiments.sweeps.batches as batches_module

    monkeypatch.setattr(batches_module, "run_batch", lambda *a, **k: pytest.fail("ran an episode"))
    assert main(["trials", "-n", "2", "--out", str(tmp_path), *argv]) == 2
    assert message in capsys.readouterr().err


def test_rho_outside_the_unit_interval_is_a_usage_error(capsys):
    assert main(["trial", "--attack", "patch_occlusion", "--rho", "1.5"]) == 2
    assert "rho must be in [0, 1]" in capsys.readouterr().err


def test_the_supervisor_names_its_episodes_and_leaves_the_others_ids_as_they_were():
    alone = TrialSpec("clean+lead_patch+odca", 1, 1.0, 3, target="lead_vehicle")
    supervised = dataclasses.replace(alone, supervisor=True)
    # Off, the field is not in the spec's form: every unsupervised id is what it was before it existed.
    assert "supervisor" not in alone.to_dict() and supervised.to_dict()["supervisor"] is True
    assert TrialSpec.from_dict(supervised.to_dict()) == supervised
    assert supervised.trial_id.startswith("clean+lead_patch+odca+supervisor_lead_vehicle1_")
    assert supervised.label == "clean+lead_patch+odca+supervisor" and alone.label == alone.setting
    assert supervised.trial_id.split("_")[-1] != alone.trial_id.split("_")[-1]
    with pytest.raises(ValueError, match="supervisor must be true or false"):
        TrialSpec("clean+odca", 1, 1.0, 3, supervisor="yes")


def test_the_supervisor_is_assembled_by_the_car_above_every_published_track_and_the_engine_swaps_nothing():
    from racf.experiments.car.supervisor.static import StaticSupervisor
    from racf.experiments.car.supervisor.vehicle import VehicleSupervisor
    from racf.experiments.episode.plan import plan_episode
    from racf.experiments.episode.stack import car_stages

    spec = TrialSpec("clean+odca", 1, 1.0, 3, target="lead_vehicle")
    assert plan_episode(spec).mission.stages == ("following",)
    supervised = dataclasses.replace(spec, supervisor=True)
    plan = plan_episode(supervised)
    assert plan.mission.stages == ("following",) and plan.mission.target_decel_mps2 == 6.0
    names = [type(stage).__name__ for stage in car_stages(supervised, plan)]
    assert names[0] == "FollowingStage" and {"VehicleSupervisor", "StaticSupervisor_sign"} <= set(names)
    # The stop sign alone: its supervisor is the static one, over the car's own loop.
    sign = TrialSpec("clean+odca", 1, 1.0, 3, supervisor=True)
    stages = car_stages(sign, plan_episode(sign))
    assert len(stages) == 1 and isinstance(stages[0], StaticSupervisor) and stages[0].supervises == "sign"
    assert not any(isinstance(stage, VehicleSupervisor) for stage in stages)
