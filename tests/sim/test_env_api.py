"""Gymnasium API of ``RACF/QCar2-v4``: checker, registration, vectorisation, seeding, bad input."""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from racf import sim  # noqa: F401  (registers RACF/QCar2-v4)
import racf.sim.world.map_facts  # noqa: F401
from racf.sim.env.config import EnvConfig

REPO_ROOT = Path(__file__).resolve().parents[2]
SMALL = {"camera_width": 160, "camera_height": 120}


@pytest.fixture(scope="module")
def env():
    e = gym.make("RACF/QCar2-v4", **SMALL)
    yield e
    e.close()


def test_check_env_passes(env):
    check_env(env.unwrapped, skip_render_check=True)


def test_observation_matches_space_after_reset_and_step(env):
    obs, info = env.reset(seed=3, options={"sign": 2, "cruise_speed": 1.0})
    assert env.observation_space.contains(obs)
    assert obs["rgb"].shape == (120, 160, 3) and obs["depth"].shape == (120, 160, 1)
    obs, reward, terminated, truncated, info = env.step(np.array([1.0, 0.0], np.float32))
    assert env.observation_space.contains(obs)
    assert np.isfinite(reward)
    assert info["target_sign"] == 2


def test_make_with_module_prefix_in_fresh_process():
    code = (
        "import gymnasium as gym\n"
        "env = gym.make('racf.sim:RACF/QCar2-v4', camera_width=160, camera_height=120)\n"
        "obs, info = env.reset(seed=0)\n"
        "print('SHAPES', {k: tuple(v.shape) for k, v in sorted(obs.items())})\n"
        "env.close()\n"
    )
    child_env = dict(os.environ)
    child_env["PYTHONPATH"] = os.pathsep.join(
        [str(REPO_ROOT)] + ([child_env["PYTHONPATH"]] if child_env.get("PYTHONPATH") else []))
    proc = subprocess.run([sys.executable, "-c", code], cwd=str(REPO_ROOT / "tests"), env=child_env,
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-3000:]
    line = next(ln for ln in proc.stdout.splitlines() if ln.startswith("SHAPES"))
    assert "'rgb': (120, 160, 3)" in line
    assert "'depth': (120, 160, 1)" in line
    assert "'lidar': (360,)" in line
    assert "'state': (4,)" in line
    assert "'gps': (3,)" in line and "'timestamps': (5,)" in line


@pytest.mark.slow  # 2.5-6 s: the default run keeps under two minutes on 2 cores
def test_make_vec_async_spawn():
    venv = gym.make_vec("RACF/QCar2-v4", num_envs=2, vectorization_mode="async",
                        vector_kwargs={"context": "spawn"}, **SMALL)
    try:
        obs, infos = venv.reset(seed=0)
        assert obs["rgb"].shape == (2, 120, 160, 3)
        assert obs["lidar"].shape == (2, 360)
        for _ in range(3):
            actions = np.tile(np.array([1.0, 0.0], np.float32), (2, 1))
            obs, rewards, terminated, truncated, infos = venv.step(actions)
            assert rewards.shape == (2,)
            assert obs["depth"].shape == (2, 120, 160, 1)
            assert np.isfinite(rewards).all()
    finally:
        venv.close()


# -- determinism ------------------------------------------------------------------------

def _rollout(seed: int, n_steps: int = 10) -> list[dict[str, np.ndarray]]:
    e = gym.make("RACF/QCar2-v4", **SMALL)
    try:
        obs, _ = e.reset(seed=seed, options={"sign": 3, "cruise_speed": 1.0, "run_up_m": 1.5})
        out = [obs]
        for k in range(n_steps):
            action = np.array([1.0, 0.2 * math.sin(0.7 * k)], np.float32)
            obs, *_ = e.step(action)
            out.append(obs)
        return out
    finally:
        e.close()


@pytest.fixture(scope="module")
def rollout_seed7():
    return _rollout(7)


def test_same_seed_same_observations_bit_for_bit(rollout_seed7):
    again = _rollout(7)
    assert len(again) == len(rollout_seed7)
    for step, (a, b) in enumerate(zip(rollout_seed7, again)):
        assert a.keys() == b.keys()
        for key in a:
            assert a[key].dtype == b[key].dtype
            assert np.array_equal(a[key], b[key]), f"obs[{key!r}] differs at step {step}"


def test_different_seed_different_depth_noise(rollout_seed7):
    other = _rollout(8, n_steps=0)
    a, b = rollout_seed7[0]["depth"], other[0]["depth"]
    assert a.shape == b.shape
    # Same start pose (explicit options), so the difference is sensor noise only.
    assert not np.array_equal(a, b)
    valid = (a > 0) & (b > 0)
    assert np.mean(a[valid] != b[valid]) > 0.05


# -- bad input --------------------------------------------------------------------------

def test_unknown_reset_option_is_named(env):
    with pytest.raises(ValueError, match="speeed"):
        env.reset(seed=0, options={"speeed": 1.0})


@pytest.mark.parametrize("kwargs, name", [
    ({"camera_widht": 1}, "camera_widht"),
    ({"lidarn_beams": 360}, "lidarn_beams"),
    ({"nonsense": True}, "nonsense"),
])
def test_unknown_constructor_kwarg_is_named(kwargs, name):
    with pytest.raises(ValueError, match=name):
        gym.make("RACF/QCar2-v4", **kwargs)


@pytest.mark.parametrize("kwargs, name", [
    ({"camera_width": 5}, "width"),
    ({"lidar_n_beams": 1}, "n_beams"),
    ({"control_hz": 0}, "control_hz"),
    ({"lidar_noise_rel": -0.1}, "noise_rel"),
    ({"camera_depth_dropout": 1.5}, "depth_dropout"),
    ({"max_episode_s": 0.0}, "max_episode_s"),
    ({"lidar_hz": 7}, "lidar_hz"),
    ({"vehicle_max_speed_mps": 10.0}, "max_speed_mps"),
    ({"localisation": "perfect"}, r"localisation must be one of \('qcar2', 'true'\)"),
    ({"localiser_noise_xy_m": -1.0}, "noise_xy_m"),
    ({"odometry_m_per_count": 0.0}, "m_per_count"),
])
def test_out_of_range_config_value_is_named(kwargs, name):
    with pytest.raises(ValueError, match=name):
        EnvConfig.from_kwargs(**kwargs)
    with pytest.raises(ValueError, match=name):
        gym.make("RACF/QCar2-v4", **kwargs)


def test_nan_action_rejected(env):
    env.reset(seed=0, options={"sign": 0})
    with pytest.raises(ValueError, match="action"):
        env.step(np.array([np.nan, 0.0], np.float32))
    with pytest.raises(ValueError, match="action"):
        env.step(np.array([0.5, np.inf], np.float32))


@pytest.mark.parametrize("action", [np.zeros(3, np.float32), np.zeros((1, 2), np.float32), np.float32(0.5)])
def test_wrong_action_shape_rejected(env, action):
    env.reset(seed=0, options={"sign": 0})
    with pytest.raises(ValueError, match="action"):
        env.step(action)


@pytest.mark.parametrize("options, name", [
    ({"sign": 7}, "sign"),
    ({"sign": -1}, "sign"),
    ({"sign": 0, "cruise_speed": -1.0}, "cruise_speed"),
    ({"sign": 0, "cruise_speed": float("nan")}, "cruise_speed"),
    ({"sign": 2, "run_up_m": 100.0}, "run_up_m"),
])
def test_out_of_range_reset_option_is_named(env, options, name):
    with pytest.raises(ValueError, match=name):
        env.reset(seed=0, options=options)


def test_non_integer_sign_raises_value_error(env):
    with pytest.raises(ValueError, match="sign"):
        env.reset(seed=0, options={"sign": 2.5 - 0.5})


def test_string_sign_raises_value_error(env):
    with pytest.raises(ValueError, match="sign"):
        env.reset(seed=0, options={"sign": "2"})


def test_numpy_scalar_reset_options_accepted(env):
    obs, info = env.reset(seed=0, options={"sign": np.int64(2), "cruise_speed": np.float32(1.0),
                                           "run_up_m": np.float32(0.8)})
    assert info["target_sign"] == 2
    assert info["dist_to_stop_line"] == pytest.approx(0.8, abs=1e-6)


@pytest.mark.parametrize("kwargs, name", [({"camera_width": 160.5}, "width"), ({"lidar_n_beams": 90.5}, "n_beams")])
def test_non_integer_sizes_raise_value_error(kwargs, name):
    with pytest.raises(ValueError, match=name):
        e = gym.make("RACF/QCar2-v4", **kwargs)
        e.reset(seed=0)


def test_bad_render_mode_rejected():
    from racf.sim.env.qcar2_env import QCar2Env

    with pytest.raises(ValueError, match="render_mode"):
        QCar2Env(render_mode="rgb", **SMALL)


# -- render -----------------------------------------------------------------------------

def test_render_rgb_array():
    e = gym.make("RACF/QCar2-v4", render_mode="rgb_array", **SMALL)
    try:
        e.reset(seed=0, options={"sign": 2, "cruise_speed": 1.0})
        e.step(np.array([1.0, 0.0], np.float32))
        frame = e.render()
        assert isinstance(frame, np.ndarray)
        assert frame.shape == (480, 640, 3)
        assert frame.dtype == np.uint8
        assert frame.std() > 5.0
        assert len(np.unique(frame.reshape(-1, 3), axis=0)) > 50
    finally:
        e.close()


def test_render_without_mode_returns_none(env):
    env.reset(seed=0, options={"sign": 0})
    assert env.render() is None


# -- episode end ------------------------------------------------------------------------

def test_driving_into_the_wall_terminates_with_collision(env):
    # Sign 2 from 1 m: the car starts in the bend heading north-east; driving straight
    # instead of following the bend runs it into the east wall.
    obs, info = env.reset(seed=0, options={"sign": 2, "cruise_speed": 1.0, "run_up_m": 1.0})
    assert not info["collision"] and not info["off_road"]
    for _ in range(100):
        obs, reward, terminated, truncated, info = env.step(np.array([1.0, 0.0], np.float32))
        if terminated or truncated:
            break
    assert terminated and not truncated
    assert info["collision"]
    assert reward < -9.0
    x_max = sim.world.map_facts.WALL_BOUNDS_M[1]
    assert info["pose"][0] > x_max - 0.4


def test_time_limit_truncates():
    e = gym.make("RACF/QCar2-v4", max_episode_s=0.2, **SMALL)
    try:
        e.reset(seed=0, options={"sign": 3, "cruise_speed": 0.0, "run_up_m": 1.0})
        flags = [e.step(np.zeros(2, np.float32))[2:4] for _ in range(10)]
        assert flags[-1] == (False, True)
        assert all(f == (False, False) for f in flags[:-1])
    finally:
        e.close()


def test_stopped_car_reward_and_info(env):
    obs, info = env.reset(seed=0, options={"sign": 3, "cruise_speed": 0.0, "run_up_m": 1.0})
    assert info["dist_to_stop_line"] == pytest.approx(1.0, abs=1e-6)
    assert abs(info["lateral_error"]) < 1e-3
    assert info["speed"] == pytest.approx(0.0, abs=1e-6)
    for _ in range(5):
        obs, reward, terminated, truncated, info = env.step(np.zeros(2, np.float32))
    assert not terminated and not truncated
    assert abs(reward) < 0.01
    assert info["dist_to_stop_line"] == pytest.approx(1.0, abs=0.01)
    assert info["time"] == pytest.approx(5 / 50)
