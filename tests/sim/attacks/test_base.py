"""What every attack wrapper shares: the checker, seeding, composition, ``info`` marks and argument checks."""

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from racf.sim.attacks import ConfidenceDegradation, DepthBias, DepthBlackout, LidarDropout, LidarSpoof, PatchOcclusion

ALL = (PatchOcclusion, DepthBlackout, DepthBias, ConfidenceDegradation, LidarDropout, LidarSpoof)


@pytest.mark.parametrize("wrapper", ALL, ids=lambda w: w.__name__)
def test_check_env_passes_when_wrapped(wrapper, stub_env):
    env = wrapper(stub_env(), trigger="always", duration_s=0.2)
    with pytest.warns(UserWarning):  # gymnasium notes that the env is wrapped
        check_env(env, skip_render_check=True)


def test_same_seed_same_attack_windows_and_observations(stub_env, drive):
    def windows(seed):
        env = PatchOcclusion(stub_env(), rho=(0.3, 1.0), duration_s=(0.2, 0.6), window_s=2.0)
        frames = [obs["rgb"] for obs, _, _ in drive(env, 40, seed=seed)]
        return list(env.schedule.windows), env.rho, frames
    w1, rho1, f1 = windows(7)
    w2, rho2, f2 = windows(7)
    assert w1 and w1 == w2 and rho1 == rho2
    assert len(f1) == len(f2) == 40 and all(np.array_equal(a, b) for a, b in zip(f1, f2))
    assert windows(8)[:2] != (w1, rho1)


def test_reset_marks_no_attack_and_steps_mark_the_active_ones(stub_env, drive):
    env = DepthBlackout(stub_env(), duration_s=0.1, window_s=5.0, stable_steps=3)
    _, info = env.reset(seed=0)
    assert info["attack"] == () and info["attack_active"] is False
    marks = [info["attack"] for _, _, info in drive(env, 12)]
    assert marks == [()] * 2 + [("depth_blackout",)] * 5 + [()] * 5  # 3 visible steps, then 0.1 s at 50 Hz


def test_wrappers_compose_and_mark_every_active_attack(stub_env):
    env = DepthBias(PatchOcclusion(stub_env(), rho=0.5, duration_s=5.0, trigger="always"), bias_m=0.3,
                    duration_s=5.0, trigger="always")
    _, info = env.reset(seed=0, options={"sign": 3})
    assert info["attack"] == () and info["attack_active"] is False
    obs, _, _, _, info = env.step(np.array([1.0, 0.0], np.float32))
    assert info["attack"] == ("patch_occlusion", "depth_bias") and info["attack_active"]
    # Both changes reach the outside: the inner patch on the image, the outer bias on the depth.
    clean = env.unwrapped.sensor_observation()
    sign = info["sign_mask"]
    assert (obs["rgb"] != clean["rgb"]).any(axis=2)[sign].any()
    valid = sign & (clean["depth"][..., 0] > 0)
    np.testing.assert_allclose(obs["depth"][valid], clean["depth"][valid] + 0.3, atol=1e-5)


def test_an_inactive_outer_wrapper_passes_the_inner_attack_and_its_mark_through(stub_env):
    env = LidarSpoof(PatchOcclusion(stub_env(), rho=1.0, duration_s=5.0, trigger="always"), range_m=2.0,
                     duration_s=5.0, window_s=0.0)  # a zero braking window never opens
    env.reset(seed=0)
    inner_only = PatchOcclusion(stub_env(), rho=1.0, duration_s=5.0, trigger="always")
    inner_only.reset(seed=0)
    for _ in range(5):
        obs, _, _, _, info = env.step(np.array([1.0, 0.0], np.float32))
        expected, _, _, _, _ = inner_only.step(np.array([1.0, 0.0], np.float32))
        assert info["attack"] == ("patch_occlusion",) and info["attack_active"]
        for key in expected:
            np.testing.assert_array_equal(obs[key], expected[key])


@pytest.mark.parametrize("wrapper", ALL, ids=lambda w: w.__name__)
@pytest.mark.parametrize("schedule, match", [
    ({"duration_s": -1.0}, "duration_s"),
    ({"duration_s": (2.0, 1.0)}, "duration_s"),
    ({"cooldown_s": -1.0}, "cooldown_s"),
    ({"trigger": "later"}, "trigger"),
])
def test_bad_schedule_parameters_are_value_errors(wrapper, schedule, match, stub_env):
    with pytest.raises(ValueError, match=match):
        wrapper(stub_env(), **schedule)


@pytest.mark.parametrize("wrapper", ALL, ids=lambda w: w.__name__)
def test_a_misspelt_schedule_parameter_is_an_error_not_ignored(wrapper, stub_env):
    with pytest.raises(TypeError, match="duraton_s"):
        wrapper(stub_env(), duraton_s=1.0)


@pytest.mark.parametrize("wrapper", ALL, ids=lambda w: w.__name__)
def test_an_env_without_the_racf_observations_is_refused(wrapper):
    env = gym.make("CartPole-v1")
    with pytest.raises(ValueError, match="'rgb', 'depth' and 'lidar'"):
        wrapper(env)
    env.close()


def test_every_attack_is_registered_under_its_own_name(stub_env):
    from racf.sim.attacks import ATTACKS, AttackWrapper

    assert set(ATTACKS) >= {"patch_occlusion", "physical_patch", "lidar_spoof", "lidar_dropout", "depth_blackout",
                            "depth_bias", "confidence_degradation", "delay", "dropout_timed", "stealth_ramp",
                            "frustum_spoof"}
    own = [name for name in ATTACKS if ATTACKS.plugin(name).builtin]
    assert own == sorted(own)  # racf's own by name: the order attacks take in a setting's name
    for name, cls in ATTACKS.items():
        assert issubclass(cls, AttackWrapper) and cls.name == name
        wrapped = cls(stub_env(), **{param: (0.5, 0.5) for param in cls.episode_params})
        assert wrapped.name == name
