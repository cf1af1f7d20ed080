"""``LidarSpoof``: the beams at the sign return a fake range, the others are untouched."""

import numpy as np
import pytest

from racf.sim.attacks import LidarSpoof

SIGN_BEAM = 30  # the stub's LiDAR sees the sign on this beam (beam i points i degrees CCW of forward)


def test_spoof_sets_the_beams_at_the_sign_to_the_fake_range(stub_env, drive):
    env = LidarSpoof(stub_env(), range_m=2.5, duration_s=5.0, trigger="always")
    for obs, clean, info in drive(env, 5):
        spoofed = obs["lidar"] != clean["lidar"]
        assert obs["lidar"][SIGN_BEAM] == np.float32(2.5)
        assert (obs["lidar"][spoofed] == np.float32(2.5)).all()
        angle = np.abs((np.flatnonzero(spoofed) - SIGN_BEAM + 180) % 360 - 180)
        assert spoofed.any() and (angle <= 3).all()
        np.testing.assert_array_equal(obs["depth"], clean["depth"])
        np.testing.assert_array_equal(obs["rgb"], clean["rgb"])


def test_a_range_interval_draws_one_fake_range_per_episode(stub_env):
    env = LidarSpoof(stub_env(), range_m=(1.0, 4.0), duration_s=5.0, trigger="always")
    drawn = []
    for seed in range(5):
        env.reset(seed=seed)
        ranges = {float(env.step(np.array([1.0, 0.0], np.float32))[0]["lidar"][SIGN_BEAM]) for _ in range(3)}
        assert len(ranges) == 1 and 1.0 <= ranges.pop() <= 4.0
        drawn.append(env.range_m)
    assert len(set(drawn)) == 5


def test_spoof_on_the_real_env_replaces_the_returns_off_the_plate(real_env, drive):
    spoof = LidarSpoof(real_env(), range_m=2.5, duration_s=5.0, trigger="always")
    for obs, clean, info in drive(spoof, 5, options={"sign": 0}):
        beams = spoof.sign_beams(obs["lidar"].size)
        assert (obs["lidar"][beams] == np.float32(2.5)).all()
        # The plate is hit by the beams the wrapper picked: the clean returns there are near the sign.
        assert np.isfinite(clean["lidar"][beams]).any()
        np.testing.assert_array_equal(obs["lidar"][~beams], clean["lidar"][~beams])


@pytest.mark.parametrize("range_m", [0.0, 20.0, (3.0, 1.0)])
def test_bad_range_is_a_value_error(range_m, stub_env):
    with pytest.raises(ValueError, match="range_m"):
        LidarSpoof(stub_env(), range_m=range_m)
