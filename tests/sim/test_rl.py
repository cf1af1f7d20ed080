"""RL users: stable-baselines3's checker passes without warnings and PPO runs a few steps."""

import warnings

import gymnasium as gym
import numpy as np
import pytest

from racf import sim
from racf.sim.env.rl import DepthAsImage, rl_env

SMALL = {"camera_width": 160, "camera_height": 120}


@pytest.mark.slow  # 2.5-6 s: the default run keeps under two minutes on 2 cores
def test_sb3_check_env_has_nothing_to_say_and_ppo_learns_a_few_steps():
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_checker import check_env

    env = rl_env(**SMALL)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        check_env(env, warn=True)
    sb3 = [str(w.message) for w in caught if "stable_baselines3" in (w.filename or "")]
    assert sb3 == []
    model = PPO("MultiInputPolicy", env, n_steps=16, batch_size=16, n_epochs=1, seed=0, device="cpu")
    model.learn(32)
    action, _ = model.predict(env.reset(seed=1)[0], deterministic=True)
    assert env.action_space.contains(action.astype(np.float32))
    env.close()


def test_plain_env_depth_is_an_image_shaped_float_and_older_versions_point_to_v4():
    env = gym.make(sim.ENV_ID, **SMALL)
    assert env.observation_space["depth"].shape == (120, 160, 1)
    env.close()
    for old in ("RACF/QCar2-v0", "RACF/QCar2-v1", "RACF/QCar2-v2", "RACF/QCar2-v3"):
        with pytest.raises(gym.error.Error, match="RACF/QCar2-v4"):
            gym.make(old)


def test_depth_as_image_maps_metres_to_uint8_and_keeps_no_return_at_zero():
    env = gym.make(sim.ENV_ID, **SMALL)
    wrapped = DepthAsImage(env, max_depth_m=5.0)
    depth = np.array([[[0.0], [2.5], [5.0], [9.0]]], np.float32)
    out = wrapped.observation({"depth": depth})["depth"]
    np.testing.assert_array_equal(out[0, :, 0], [0, 128, 255, 255])
    with pytest.raises(ValueError, match="max_depth_m"):
        DepthAsImage(env, max_depth_m=0)
    env.close()
