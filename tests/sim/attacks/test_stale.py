"""``StaleData`` (``delay``): LiDAR scans replayed late, depth frozen at the attack's start."""

import numpy as np
import pytest

from racf.sim.attacks import ATTACKS, StaleData

SIGN_BEAM = 30  # the stub's LiDAR sees the sign on this beam


def test_lidar_scans_arrive_k_scans_late(stub_env):
    # The stub delivers a new scan every step (and one at reset), so k scans late is k steps late.
    env = StaleData(stub_env(), sensor="lidar", frames=3, duration_s=5.0, trigger="always")
    first, _ = env.reset(seed=0, options={"cruise_speed": 1.0, "run_up_m": 1.5})
    clean_scans = [first["lidar"].copy()]
    for step in range(1, 13):
        obs, _, _, _, info = env.step(np.array([1.0, 0.0], np.float32))
        clean = env.unwrapped.sensor_observation()
        clean_scans.append(clean["lidar"].copy())
        np.testing.assert_array_equal(obs["lidar"], clean_scans[max(0, step - 3)])
        np.testing.assert_array_equal(obs["depth"], clean["depth"])
        assert info["attack"] == ("delay",)
    # Late by 3 steps at 1 m/s: the sign's return reads 3 x 2 cm too far.
    assert obs["lidar"][SIGN_BEAM] == pytest.approx(clean["lidar"][SIGN_BEAM] + 0.06, abs=1e-5)


def test_depth_freezes_at_the_attacks_start_and_thaws_after_it(stub_env, drive):
    env = StaleData(stub_env(), sensor="depth", duration_s=0.1, cooldown_s=10.0, trigger="always")
    frames = list(drive(env, 12))
    attacked = [k for k, (_, _, info) in enumerate(frames) if info["attack_active"]]
    assert attacked == list(range(attacked[0], attacked[0] + 5))  # 0.1 s at 50 Hz
    frozen = frames[attacked[0]][1]["depth"]
    for k in attacked:
        np.testing.assert_array_equal(frames[k][0]["depth"], frozen)
        np.testing.assert_array_equal(frames[k][0]["lidar"], frames[k][1]["lidar"])
    assert not np.array_equal(frames[attacked[-1]][1]["depth"], frozen)  # the car moved on
    after = attacked[-1] + 1
    np.testing.assert_array_equal(frames[after][0]["depth"], frames[after][1]["depth"])


def test_the_same_seed_gives_the_same_bytes_and_the_attack_is_registered(stub_env, drive):
    assert ATTACKS["delay"] is StaleData
    runs = [[obs["lidar"].tobytes() for obs, _, _ in drive(StaleData(stub_env(), frames=2, trigger="always"), 8)]
            for _ in range(2)]
    assert runs[0] == runs[1]


@pytest.mark.parametrize("kwargs,match", [({"sensor": "gps"}, "sensor"), ({"frames": 0}, "frames"),
                                          ({"frames": 2.5}, "frames"), ({"region": "sky"}, "region")])
def test_bad_parameters_are_value_errors_naming_what_is_allowed(kwargs, match, stub_env):
    with pytest.raises(ValueError, match=match):
        StaleData(stub_env(), **kwargs)
