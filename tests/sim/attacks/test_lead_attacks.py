"""The attacks on the car ahead: they find the lead where the simulator has it, and move its depth
and its LiDAR returns by what they say; outside the lead's scenario they refuse in one line."""

import numpy as np
import pytest

from racf.experiments.episode import TrialSpec
from racf.experiments.episode.plan import plan_episode
from racf.experiments.episode.stack import default_env
from racf.sim.attacks.lead import lead_beams, lead_pixels


def attacked(setting: str, **params):
    spec = TrialSpec(setting, 1, 1.0, 0, target="lead_vehicle", t_atk=5.0, scenario_params={"gap_m": 0.6},
                     attack_params={setting.split("+")[1]: {"start_s": 0.0, **params}})
    env = default_env(spec)
    obs, info = env.reset(seed=0, options=plan_episode(spec).reset_options)
    obs, *_, info = env.step(np.zeros(2, np.float32))
    return env, obs, info, env.unwrapped.sensor_observation()


def test_the_patch_reads_the_lead_s_pixels_far_and_no_others():
    env, obs, info, clean = attacked("clean+lead_patch", bias_m=1.0)
    assert info["attack_active"]
    moved = obs["depth"][..., 0] != clean["depth"][..., 0]
    where = lead_pixels(env, info, clean["depth"][..., 0])
    assert moved.sum() > 500 and not (moved & ~where).any()
    np.testing.assert_allclose(obs["depth"][..., 0][moved] - clean["depth"][..., 0][moved], 1.0, atol=1e-4)
    # The lead's pixels are where it stands: about its rear's distance away (0.6 m gap, the camera 0.12 m behind the bumper).
    assert np.median(clean["depth"][..., 0][where]) == pytest.approx(0.75, abs=0.1)
    np.testing.assert_array_equal(obs["lidar"], clean["lidar"])


def test_the_lead_s_beams_are_those_whose_return_is_the_lead_not_every_beam_its_bearing_spans():
    env, _, info, clean = attacked("clean+lead_frustum", bias_m=0.8)
    scan = np.asarray(clean["lidar"], np.float64)
    beams = lead_beams(env, info, scan)
    # The lead's returns lie at its rear, about 0.6 m of gap plus the LiDAR's place ahead of the bumper.
    assert 0 < beams.sum() < 10 and np.all(scan[beams] < 1.0)
    # A return from beyond the lead along the same bearings (a wall 2 m further) is not the lead's.
    beyond = scan.copy()
    beyond[beams] += 2.0
    assert not lead_beams(env, info, beyond).any()
    # Nor is a bearing without any return.
    beyond[beams] = np.inf
    assert not lead_beams(env, info, beyond).any()


def test_the_frustum_spoof_moves_the_lead_s_returns_and_with_depth_its_depth():
    env, obs, info, clean = attacked("clean+lead_frustum", bias_m=0.8)
    beams = lead_beams(env, info, clean["lidar"])
    assert beams.any() and beams.sum() < 40
    np.testing.assert_allclose(obs["lidar"][beams] - clean["lidar"][beams], 0.8, atol=1e-4)
    np.testing.assert_array_equal(obs["lidar"][~beams], clean["lidar"][~beams])
    np.testing.assert_array_equal(obs["depth"], clean["depth"])
    _, both, _, clean = attacked("clean+lead_frustum", bias_m=0.8, depth=True)
    assert (both["depth"] != clean["depth"]).sum() > 500


def test_an_attack_on_the_car_ahead_refuses_a_scenario_without_one_before_any_simulator():
    # The spec is refused: no env is built (the world's declared targets are read from its managers).
    with pytest.raises(ValueError, match="acts on a vehicle that the scenario's world declares; scenario 'sign' declares none"):
        TrialSpec("clean+lead_patch", 1, 1.0, 0, t_atk=2.0)
    # A world of crossing cars declares them as vehicles: the attack aims at the first of them.
    crossing = TrialSpec("clean+lead_patch", 1, 1.0, 0, t_atk=2.0, target="cross_traffic")
    from racf.sim.attacks.lead import attacked_vehicle

    assert attacked_vehicle(default_env(crossing)).name == "traffic0"


def test_the_attacks_find_their_car_through_the_world_s_declaration():
    from racf.sim.attacks.lead import attacked_vehicle
    from racf.sim.world.manager import QCAR2_BOX_M

    spec = TrialSpec("clean+lead_patch", 1, 1.0, 0, t_atk=2.0, target="lead_vehicle")
    target = attacked_vehicle(default_env(spec))
    assert (target.kind, target.pose_columns, target.size_m) == ("vehicle", ("lead_x", "lead_y", "lead_yaw"), QCAR2_BOX_M)
    assert attacked_vehicle(default_env(TrialSpec("clean", 1, 1.0, 0))) is None


def test_the_lead_hidden_leaves_no_return_and_no_car_for_the_detector():
    from racf.controllers.vehicle_detector import LearnedVehicleDetector

    env, obs, info, clean = attacked("clean+lead_hide")
    where = lead_pixels(env, info, clean["depth"][..., 0])
    assert where.sum() > 500 and (obs["depth"][..., 0][where] == 0).all()
    assert np.isinf(obs["lidar"][lead_beams(env, info, clean["lidar"])]).all()
    detector = LearnedVehicleDetector()
    assert detector.passing(clean["rgb"]) and not detector.passing(obs["rgb"])


def test_the_phantom_draws_a_nearer_car_in_the_colour_image_only():
    from racf.controllers.vehicle_detector import LearnedVehicleDetector

    env, obs, info, clean = attacked("clean+lead_phantom", distance_m=0.4)
    np.testing.assert_array_equal(obs["depth"], clean["depth"])
    np.testing.assert_array_equal(obs["lidar"], clean["lidar"])
    drawn = np.any(obs["rgb"] != clean["rgb"], axis=-1)
    where = lead_pixels(env, info, clean["depth"][..., 0])
    assert drawn.sum() > 2 * where.sum()  # about (0.75 / 0.4)^2 the lead's pixels
    detector = LearnedVehicleDetector()
    real, phantom = (max(detector.passing(img), key=lambda d: d.box[3] - d.box[1]) for img in (clean["rgb"], obs["rgb"]))
    assert phantom.box[3] - phantom.box[1] > 1.5 * (real.box[3] - real.box[1])  # taller: the size says nearer
    # A phantom further than the lead would stand behind it: nothing is drawn.
    _, behind, _, clean = attacked("clean+lead_phantom", distance_m=1.5)
    np.testing.assert_array_equal(behind["rgb"], clean["rgb"])


def test_the_adaptive_frustum_moves_every_witness_the_picture_too_and_grows_at_its_rate():
    from racf.controllers.vehicle_detector import LearnedVehicleDetector

    env, obs, info, clean = attacked("clean+lead_frustum", bias_m=0.8, depth=True, scale_box=True)
    plane, seen = clean["depth"][..., 0], obs["depth"][..., 0]
    where = lead_pixels(env, info, plane)
    d = float(np.median(plane[where]))
    # The lead's depth in the picture reads d + 0.8, and there is less of it: (d / (d + 0.8))^2 the pixels.
    moved = np.abs(seen - (plane + 0.8)) < 0.05
    farther = np.abs(seen - (d + 0.8)) < 0.1
    assert farther.sum() == pytest.approx(where.sum() * (d / (d + 0.8)) ** 2, rel=0.35)
    assert not (moved & where).all()
    detector = LearnedVehicleDetector()
    real, spoofed = (max(detector.passing(img), key=lambda b: b.box[3] - b.box[1]) for img in (clean["rgb"], obs["rgb"]))
    # Smaller by about d / (d + 0.8): the size says the lead is 0.8 m farther, as the depth and the LiDAR do.
    ratio = (spoofed.box[3] - spoofed.box[1]) / (real.box[3] - real.box[1])
    assert ratio == pytest.approx(d / (d + 0.8), abs=0.12)
    beams = lead_beams(env, info, clean["lidar"])
    np.testing.assert_allclose(obs["lidar"][beams] - clean["lidar"][beams], 0.8, atol=1e-4)
    # With a rate the move grows from nothing at that rate, as the LiDAR reads it.
    env, obs, info, _ = attacked("clean+lead_frustum", bias_m=0.8, depth=True, scale_box=True, rate_mps=1.0)
    assert env.bias(info) == 0.0
    t0 = float(info["time"])
    for _ in range(5):
        obs, *_, info = env.step(np.zeros(2, np.float32))
    clean = env.unwrapped.sensor_observation()
    assert env.bias(info) == pytest.approx(float(info["time"]) - t0, abs=1e-6) and env.bias(info) > 0.05
    beams = lead_beams(env, info, clean["lidar"])
    np.testing.assert_allclose(obs["lidar"][beams] - clean["lidar"][beams], env.bias(info), atol=1e-4)


@pytest.mark.parametrize("params, message", [({"scale_box": 1}, "scale_box must be true or false"),
                                             ({"rate_mps": -1.0}, r"rate_mps must be in \[0, 10\]")])
def test_the_frustum_spoof_refuses_a_bad_option_in_one_line(params, message):
    with pytest.raises(ValueError, match=message):
        attacked("clean+lead_frustum", **params)


def test_the_range_error_moves_every_range_witness_of_the_lead_by_the_same_bounded_error():
    env, obs, info, clean = attacked("clean+lead_range_error", bias_m=0.03, amp_m=0.05, period_s=2.0, phase_rad=0.5)
    start = env.schedule.windows[-1][0]
    error = env.error(info)
    assert error == pytest.approx(0.03 + 0.05 * np.sin(2 * np.pi * (float(info["time"]) - start) / 2.0 + 0.5))
    assert abs(error) <= 0.08 and error != 0.0
    beams = lead_beams(env, info, clean["lidar"])
    where = lead_pixels(env, info, clean["depth"][..., 0])
    assert beams.any() and where.sum() > 500
    np.testing.assert_allclose(obs["lidar"][beams] - clean["lidar"][beams], error, atol=1e-4)
    np.testing.assert_allclose(obs["depth"][..., 0][where] - clean["depth"][..., 0][where], error, atol=1e-4)
    np.testing.assert_array_equal(obs["lidar"][~beams], clean["lidar"][~beams])
    np.testing.assert_array_equal(obs["rgb"], clean["rgb"])


@pytest.mark.parametrize("params, message", [({"amp_m": -0.1}, "amp_m must be a number in"),
                                             ({"period_s": 0.0}, "period_s must be a number in"),
                                             ({"bias_m": True}, "bias_m must be a number in")])
def test_the_range_error_refuses_a_bad_option_in_one_line(params, message):
    from racf.sim.attacks.lead import LeadRangeError

    with pytest.raises(ValueError, match=message):
        LeadRangeError(object(), **params)
