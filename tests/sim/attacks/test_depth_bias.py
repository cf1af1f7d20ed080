"""``DepthBias``: a constant offset on the sign's valid depth pixels during its window."""

import numpy as np
import pytest

from racf.sim.attacks import DepthBias


def test_bias_shifts_the_sign_depth_by_the_drawn_offset(stub_env, drive, grown):
    env = DepthBias(stub_env(), bias_m=0.7, direction=1, duration_s=5.0, trigger="always")
    for obs, clean, info in drive(env, 10):
        region = grown(info["sign_mask"], 1) & (clean["depth"][..., 0] > 0)
        assert region.sum() > 50
        np.testing.assert_allclose(obs["depth"][region], clean["depth"][region] + 0.7, atol=1e-5)
        # Elsewhere, and the sign's pixels with no return, unchanged.
        np.testing.assert_array_equal(obs["depth"][~region], clean["depth"][~region])
        np.testing.assert_array_equal(obs["rgb"], clean["rgb"])


def test_a_bias_that_reaches_zero_reads_as_no_return(stub_env, drive):
    env = DepthBias(stub_env(), bias_m=5.0, direction=-1, duration_s=5.0, trigger="always")
    for obs, clean, info in drive(env, 3):
        sign = info["sign_mask"]
        assert (clean["depth"][sign] > 0).any() and (obs["depth"][sign] == 0).all()


def test_random_direction_draws_one_sign_per_episode_and_both_occur(stub_env):
    env = DepthBias(stub_env(), bias_m=0.4, direction=0, duration_s=5.0, trigger="always")
    offsets = set()
    for seed in range(12):
        env.reset(seed=seed)
        for _ in range(3):
            obs, _, _, _, info = env.step(np.array([1.0, 0.0], np.float32))
            clean = env.unwrapped.sensor_observation()
            valid = info["sign_mask"] & (clean["depth"][..., 0] > 0)
            shift = np.unique(np.round(obs["depth"][valid] - clean["depth"][valid], 4))
            assert shift.size == 1  # one offset over the sign and the episode
            offsets.add(round(float(shift[0]), 4))
    assert offsets == {0.4, -0.4}


@pytest.mark.parametrize("kwargs, match", [
    ({"direction": 2}, "direction"),
    ({"bias_m": -0.5}, "bias_m"),
    ({"region": "everywhere"}, "region"),
])
def test_bad_parameters_are_value_errors(kwargs, match, stub_env):
    with pytest.raises(ValueError, match=match):
        DepthBias(stub_env(), **kwargs)
