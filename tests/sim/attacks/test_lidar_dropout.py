"""``LidarDropout``: no return (inf) on a share of the beams at the sign (or of all beams), nothing else."""

import numpy as np
import pytest

from racf.sim.attacks import LidarDropout

SIGN_BEAM = 30  # the stub's LiDAR sees the sign on this beam (beam i points i degrees CCW of forward)


def _angle_to_sign_deg(n_beams=360):
    return np.abs((np.arange(n_beams) - SIGN_BEAM + 180) % 360 - 180)


def test_dropout_removes_the_beams_at_the_sign_and_leaves_the_rest(stub_env, drive):
    env = LidarDropout(stub_env(), share=1.0, margin_deg=0.0, duration_s=5.0, trigger="always")
    for obs, clean, info in drive(env, 5):
        dropped = obs["lidar"] != clean["lidar"]
        assert dropped[SIGN_BEAM] and np.isinf(obs["lidar"][dropped]).all()
        assert (_angle_to_sign_deg()[dropped] <= 3).all()  # the plate is a few degrees wide from 2 m
        np.testing.assert_array_equal(obs["depth"], clean["depth"])
        np.testing.assert_array_equal(obs["rgb"], clean["rgb"])


def test_margin_widens_the_sector(stub_env, drive):
    env = LidarDropout(stub_env(), share=1.0, margin_deg=10.0, duration_s=5.0, trigger="always")
    for obs, clean, _ in drive(env, 3):
        off = np.isinf(obs["lidar"]) & np.isfinite(clean["lidar"])
        angle = _angle_to_sign_deg()
        assert off[angle <= 10].all() and not off[angle > 13].any()


def test_share_of_all_beams_is_removed_at_random(stub_env, drive):
    env = LidarDropout(stub_env(), share=0.5, sector="all", duration_s=5.0, trigger="always")
    removed = []
    for obs, clean, _ in drive(env, 10):
        returns = np.isfinite(clean["lidar"])
        removed.append(np.isinf(obs["lidar"][returns]))
        np.testing.assert_array_equal(obs["lidar"][~np.isinf(obs["lidar"])], clean["lidar"][~np.isinf(obs["lidar"])])
    assert abs(np.mean(removed) - 0.5) < 0.05
    assert not all(np.array_equal(removed[0], r) for r in removed[1:])  # new beams each step


def test_dropout_on_the_real_env_touches_only_the_sign_beams(real_env, drive):
    drop = LidarDropout(real_env(), share=1.0, margin_deg=0.0, duration_s=5.0, trigger="always")
    for obs, clean, info in drive(drop, 5, options={"sign": 0}):
        beams = drop.sign_beams(obs["lidar"].size)
        assert np.isinf(obs["lidar"][beams]).all()
        np.testing.assert_array_equal(obs["lidar"][~beams], clean["lidar"][~beams])


@pytest.mark.parametrize("kwargs, match", [
    ({"share": 2.0}, "share"),
    ({"sector": "front"}, "sector"),
    ({"margin_deg": -1.0}, "margin_deg"),
])
def test_bad_parameters_are_value_errors(kwargs, match, stub_env):
    with pytest.raises(ValueError, match=match):
        LidarDropout(stub_env(), **kwargs)
