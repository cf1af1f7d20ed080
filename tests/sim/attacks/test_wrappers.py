"""The attack wrappers: spaces, seeding, and that each changes exactly what it claims."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

import sim
from sim.attacks import (AttackSchedule, ConfidenceDegradation, DepthBias, DepthBlackout, LidarDropout, LidarSpoof,
                         PatchAttack, patch_rows)

ALL = (PatchAttack, DepthBlackout, DepthBias, ConfidenceDegradation, LidarDropout, LidarSpoof)


def _env():
    return gym.make(sim.ENV_ID, camera_width=160, camera_height=120)


def _run(env, steps, seed=0, sign=0):
    """Drives straight at 1 m/s; yields (obs, clean obs, info) per step."""
    obs, info = env.reset(seed=seed, options={"sign": sign, "cruise_speed": 1.0, "run_up_m": 1.5})
    for _ in range(steps):
        obs, _, term, trunc, info = env.step(np.array([1.0, 0.0], np.float32))
        yield obs, env.unwrapped.sensor_observation(), info
        if term or trunc:
            return


@pytest.mark.parametrize("wrapper", ALL, ids=lambda w: w.__name__)
def test_check_env_passes_when_wrapped(wrapper):
    env = wrapper(_env(), trigger="always", duration_s=0.2)
    with pytest.warns(UserWarning):  # gymnasium notes that the env is wrapped
        check_env(env, skip_render_check=True)
    env.close()


def test_same_seed_same_attack_windows_and_observations():
    def windows(seed):
        env = PatchAttack(_env(), rho=(0.3, 1.0), duration_s=(0.2, 0.6), window_s=2.0)
        frames = [obs["rgb"] for obs, _, _ in _run(env, 40, seed=seed)]
        out = (list(env.schedule.windows), env.rho, frames)
        env.close()
        return out
    w1, rho1, f1 = windows(7)
    w2, rho2, f2 = windows(7)
    assert w1 and w1 == w2 and rho1 == rho2
    assert all(np.array_equal(a, b) for a, b in zip(f1, f2))
    assert windows(8)[:2] != (w1, rho1)


@pytest.mark.parametrize("rho", [0.0, 0.3, 0.6, 0.9, 1.0])
def test_patch_covers_rho_of_the_sign_within_one_row_and_nothing_else(rho):
    env = PatchAttack(_env(), rho=rho, duration_s=5.0, trigger="always")
    checked = 0
    for obs, clean, info in _run(env, 25):
        mask = info["sign_mask"]
        if mask.sum() < 30:
            continue
        covered = patch_rows(mask, rho)
        widest_row = mask.sum(axis=1).max()
        assert abs(covered.sum() - rho * mask.sum()) <= widest_row
        changed = (obs["rgb"] != clean["rgb"]).any(axis=2)
        assert not (changed & ~covered).any(), "the patch drew outside its rows of the sign"
        assert changed.sum() >= 0.9 * covered.sum()
        np.testing.assert_array_equal(obs["depth"], clean["depth"])  # the patch lies on the face
        assert info["attack"] == ("patch",) and info["attack_active"]
        checked += 1
    assert checked > 5
    env.close()


def test_patch_is_textured_not_flat():
    env = PatchAttack(_env(), rho=1.0, duration_s=5.0, trigger="always")
    stds = [obs["rgb"][info["sign_mask"]].std(axis=0).mean() for obs, _, info in _run(env, 20)
            if info["sign_mask"].sum() > 30]
    assert stds and min(stds) > 8.0
    env.close()


def test_blackout_invalidates_depth_only_inside_its_window_and_region():
    env = DepthBlackout(_env(), duration_s=0.2, window_s=5.0, stable_steps=2)
    active_steps = 0
    for obs, clean, info in _run(env, 40):
        if info["attack_active"]:
            active_steps += 1
            region = env.sign_region(info, env.margin_px)
            assert (obs["depth"][region] == 0).all()
            np.testing.assert_array_equal(obs["depth"][~region], clean["depth"][~region])
        else:
            np.testing.assert_array_equal(obs["depth"], clean["depth"])
    assert active_steps == 10  # 0.2 s at 50 Hz
    (start, end), = env.schedule.windows
    assert end - start == pytest.approx(0.2)
    env.close()


def test_bias_shifts_the_sign_depth_by_the_drawn_offset():
    env = DepthBias(_env(), bias_m=0.7, direction=1, duration_s=5.0, trigger="always")
    for obs, clean, info in _run(env, 10):
        region = env.sign_region(info, 1) & (clean["depth"][..., 0] > 0)
        np.testing.assert_allclose(obs["depth"][region], clean["depth"][region] + 0.7, atol=1e-5)
        np.testing.assert_array_equal(obs["depth"][~region], clean["depth"][~region])
    env.close()


def test_confidence_degradation_removes_the_share_and_adds_noise():
    env = ConfidenceDegradation(_env(), confidence_multiplier=0.3, noise_std_m=0.1, duration_s=5.0, trigger="always")
    kept = []
    for obs, clean, info in _run(env, 20):
        region = env.sign_region(info, 1) & (clean["depth"][..., 0] > 0)
        if region.sum() > 50:
            kept.append((obs["depth"][region] > 0).mean())
    assert kept and abs(np.mean(kept) - 0.3) < 0.08
    env.close()


def test_lidar_dropout_and_spoof_touch_only_the_sign_beams():
    drop = LidarDropout(_env(), share=1.0, margin_deg=0.0, duration_s=5.0, trigger="always")
    for obs, clean, info in _run(drop, 5):
        beams = drop.sign_beams(obs["lidar"].size)
        assert np.isinf(obs["lidar"][beams]).all()
        np.testing.assert_array_equal(obs["lidar"][~beams], clean["lidar"][~beams])
    drop.close()
    spoof = LidarSpoof(_env(), range_m=2.5, duration_s=5.0, trigger="always")
    for obs, clean, info in _run(spoof, 5):
        beams = spoof.sign_beams(obs["lidar"].size)
        assert (obs["lidar"][beams] == np.float32(2.5)).all()
        # The plate is hit by the beams the wrapper picked: the clean returns there are near the sign.
        assert np.isfinite(clean["lidar"][beams]).any()
        np.testing.assert_array_equal(obs["lidar"][~beams], clean["lidar"][~beams])
    spoof.close()


def test_wrappers_compose_and_mark_every_active_attack():
    env = DepthBias(PatchAttack(_env(), rho=0.5, duration_s=5.0, trigger="always"), bias_m=0.3,
                    duration_s=5.0, trigger="always")
    _, info = env.reset(seed=0, options={"sign": 3})
    assert info["attack"] == () and info["attack_active"] is False
    _, _, _, _, info = env.step(np.array([1.0, 0.0], np.float32))
    assert info["attack"] == ("patch", "depth_bias") and info["attack_active"]
    env.close()


@pytest.mark.parametrize("make, match", [
    (lambda e: PatchAttack(e, rho=1.5), "rho"),
    (lambda e: PatchAttack(e, rho=-0.1), "rho"),
    (lambda e: PatchAttack(e, duration_s=-1.0), "duration_s"),
    (lambda e: PatchAttack(e, duration_s=(2.0, 1.0)), "duration_s"),
    (lambda e: DepthBlackout(e, region="everywhere"), "region"),
    (lambda e: DepthBias(e, direction=2), "direction"),
    (lambda e: ConfidenceDegradation(e, confidence_multiplier=1.2), "confidence_multiplier"),
    (lambda e: LidarDropout(e, share=2.0), "share"),
    (lambda e: LidarSpoof(e, range_m=0.0), "range_m"),
    (lambda e: PatchAttack(e, cooldown_s=-1.0), "cooldown_s"),
    (lambda e: PatchAttack(e, trigger="later"), "trigger"),
])
def test_bad_parameters_are_value_errors(make, match):
    with pytest.raises(ValueError, match=match):
        make(_env())


def test_schedule_opens_after_a_stable_sighting_inside_the_braking_window():
    schedule = AttackSchedule(duration_s=0.1, cooldown_s=0.5, window_s=1.0, stable_steps=3, max_windows=2)
    seen, unseen = np.ones((8, 8), bool), np.zeros((8, 8), bool)

    def info(t, visible, dist, speed=1.0):
        return {"time": t, "sign_mask": seen if visible else unseen, "dist_to_stop_line": dist, "speed": speed}
    # Visible but far (2 s from the line): no attack.
    assert not any(schedule.update(info(0.02 * i, True, 2.0)) for i in range(10))
    # Inside the window but the sighting restarts: needs 3 consecutive visible steps.
    assert not schedule.update(info(0.20, False, 0.9))
    assert not schedule.update(info(0.22, True, 0.9))
    assert not schedule.update(info(0.24, True, 0.9))
    assert schedule.update(info(0.26, True, 0.9))
    assert schedule.windows == [(0.26, pytest.approx(0.36))]
    # Active for the drawn duration, then quiet through the cooldown.
    assert schedule.update(info(0.34, True, 0.8))
    assert not schedule.update(info(0.40, True, 0.8))
    assert not schedule.update(info(0.80, True, 0.5))
    assert schedule.update(info(0.90, True, 0.4))
