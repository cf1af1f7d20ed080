"""``DepthBlackout``: no depth return on the sign's region (or the frame) during its window, nothing else."""

import numpy as np
import pytest

from racf.sim.attacks import DepthBlackout


def test_blackout_invalidates_depth_only_inside_its_window_and_region(stub_env, drive, grown):
    env = DepthBlackout(stub_env(), duration_s=0.2, window_s=5.0, stable_steps=2)
    active_steps = 0
    for obs, clean, info in drive(env, 40):
        if info["attack_active"]:
            active_steps += 1
            region = grown(info["sign_mask"], env.margin_px)
            assert (obs["depth"][region] == 0).all()
            np.testing.assert_array_equal(obs["depth"][~region], clean["depth"][~region])
        else:
            np.testing.assert_array_equal(obs["depth"], clean["depth"])
        np.testing.assert_array_equal(obs["rgb"], clean["rgb"])
        np.testing.assert_array_equal(obs["lidar"], clean["lidar"])
    assert active_steps == 10  # 0.2 s at 50 Hz
    (start, end), = env.schedule.windows
    assert end - start == pytest.approx(0.2)


def test_margin_grows_the_blacked_out_region(stub_env, drive, grown):
    env = DepthBlackout(stub_env(), margin_px=5, duration_s=5.0, trigger="always")
    for obs, clean, info in drive(env, 3):
        region = grown(info["sign_mask"], 5)
        assert region.sum() > info["sign_mask"].sum()
        assert (obs["depth"][region] == 0).all()
        np.testing.assert_array_equal(obs["depth"][~region], clean["depth"][~region])


def test_frame_region_blacks_out_the_whole_image(stub_env, drive):
    env = DepthBlackout(stub_env(), region="frame", duration_s=5.0, trigger="always")
    for obs, clean, _ in drive(env, 3):
        assert (clean["depth"] > 0).any() and (obs["depth"] == 0).all()


@pytest.mark.parametrize("kwargs, match", [
    ({"region": "everywhere"}, "region"),
    ({"margin_px": -1}, "margin_px"),
    ({"margin_px": 1.5}, "margin_px"),
])
def test_bad_parameters_are_value_errors(kwargs, match, stub_env):
    with pytest.raises(ValueError, match=match):
        DepthBlackout(stub_env(), **kwargs)
