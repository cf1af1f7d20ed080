"""The A2M12 as delivered and the sensor profiles: sweep, beam times, camera rate, determinism, bad settings."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from racf import sim  # noqa: F401  (registers the env)
from racf.sim.env.config import EnvConfig
from racf.sim.sensors.a2m12 import A2M12Config, A2M12Lidar, material_of

SMALL = {"camera_width": 160, "camera_height": 120}


@pytest.fixture(scope="module")
def env():
    e = gym.make(sim.ENV_ID, **SMALL)
    yield e
    e.close()


def _revolution(env, config: A2M12Config, seed: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """One revolution of a fresh sensor on the env's current (unchanging) state: ranges and beam times."""
    u = env.unwrapped
    lidar = A2M12Lidar(config, rev_hz=10.0, physics_dt_s=u.config.physics_dt_s)
    lidar.reset(np.random.default_rng(0))
    for substep in range(1, 51):  # 0.1 s of physics steps, the scene held still
        lidar.sweep(u.model, u.data, substep)
    assert lidar.has_new_scan()
    return lidar.read(u.model, u.data, np.random.default_rng(seed)), lidar.beam_times


def test_swept_scan_of_a_static_scene_is_the_one_instant_scan(env):
    env.reset(seed=0, options={"sign": 1, "cruise_speed": 0.0, "run_up_m": 1.5})
    swept, swept_times = _revolution(env, A2M12Config(sweep=True))
    instant, instant_times = _revolution(env, A2M12Config(sweep=False))
    assert swept.tobytes() == instant.tobytes()
    assert np.isfinite(swept).mean() > 0.5  # a real scan of the map, not an empty one
    # Only the times tell them apart: the swept beams span the revolution, the instant ones do not.
    assert np.ptp(instant_times) == 0.0
    assert 0.09 <= np.ptp(swept_times) <= 0.1


def test_the_road_ahead_is_seen_half_a_revolution_before_the_scan_completes(env):
    obs, _ = env.reset(seed=1, options={"sign": 2, "cruise_speed": 1.0})
    for _ in range(5):
        obs, *_ = env.step(np.array([1.0, 0.0], np.float32))
    scan_time = obs["timestamps"][2]
    times = obs["lidar_beam_times"]
    assert scan_time == pytest.approx(0.1)
    assert np.all(times <= scan_time + 1e-12) and np.all(times > scan_time - 0.1)
    # Bin 0 looks forward; the LiDAR, mounted backwards, starts its revolution at the car's rear.
    assert times[0] == pytest.approx(scan_time - 0.05, abs=0.004)
    assert times[180] == pytest.approx(scan_time - 0.1, abs=0.004) or times[180] == pytest.approx(scan_time, abs=0.004)


def test_ranges_are_quantised_and_none_is_nearer_than_the_minimum(env):
    env.reset(seed=0, options={"sign": 0, "cruise_speed": 0.0})
    # One sample per degree and a read of all of them: every bin is a sample, not an interpolation.
    cfg = A2M12Config(samples_per_rev=360, read_per_rev=360, sub_rays=1, range_min_m=0.5)
    scan, _ = _revolution(env, cfg)
    finite = scan[np.isfinite(scan)].astype(np.float64)
    assert finite.size > 100
    assert np.allclose(np.round(finite / 0.001) * 0.001, finite, atol=2e-6)  # float32 of whole millimetres
    assert finite.min() >= 0.5


def test_dropout_follows_the_material(env):
    env.reset(seed=0, options={"sign": 0, "cruise_speed": 0.0})
    never = dict(dropout_sign=0.0, dropout_pole=0.0, dropout_wall=0.0, dropout_crate=0.0, dropout_other=0.0,
                 grazing_start_deg=89.0, grazing_end_deg=90.0)
    full, _ = _revolution(env, A2M12Config(**never))
    no_walls, _ = _revolution(env, A2M12Config(**{**never, "dropout_wall": 1.0, "dropout_other": 1.0}))
    blind, _ = _revolution(env, A2M12Config(**{k: (1.0 if k.startswith("dropout") else v) for k, v in never.items()}))
    assert np.isfinite(full).sum() > np.isfinite(no_walls).sum()
    assert not np.isfinite(blind).any()


@pytest.mark.parametrize(("name", "material"), [("stop_sign_2_face", "sign"), ("stop_sign_2_pole", "pole"),
                                                ("wall_north", "wall"), ("obstacle_1", "crate"), ("", "other")])
def test_geoms_are_named_into_materials(name, material):
    assert material_of(name) == material


def test_camera_at_30_hz_holds_its_frame_between_new_ones(env):
    obs, _ = env.reset(seed=0, options={"sign": 1, "cruise_speed": 1.0})
    stamps, frames = [obs["timestamps"][0]], [obs["rgb"]]
    for _ in range(10):
        obs, *_ = env.step(np.array([1.0, 0.0], np.float32))
        stamps.append(obs["timestamps"][0])
        frames.append(obs["rgb"])
    # Frame k at k/30 s, taken at the end of the physics step (2 ms) its time falls in.
    expected = [0.0, 0.0, 0.034, 0.034, 0.068, 0.1, 0.1, 0.134, 0.134, 0.168, 0.2]
    assert stamps == pytest.approx(expected, abs=1e-9)
    for k in range(1, len(stamps)):
        same = stamps[k] == stamps[k - 1]
        assert np.array_equal(frames[k], frames[k - 1]) == same


@pytest.mark.parametrize("profile", ["qcar2", "ideal"])
def test_same_seed_same_bytes(profile):
    def run() -> bytes:
        e = gym.make(sim.ENV_ID, sensor_profile=profile, **SMALL)
        try:
            obs, _ = e.reset(seed=11, options={"sign": 3, "cruise_speed": 1.5})
            out = [obs[k].tobytes() for k in sorted(obs)]
            for _ in range(12):
                obs, *_ = e.step(np.array([1.5, 0.05], np.float32))
                out += [obs[k].tobytes() for k in sorted(obs)]
            return b"".join(out)
        finally:
            e.close()

    assert run() == run()


def test_profiles_set_their_sensors_and_explicit_settings_win():
    q, ideal = EnvConfig(), EnvConfig(sensor_profile="ideal")
    assert (q.lidar_model, q.camera_hz, q.localisation) == ("a2m12", 30.0, "qcar2")
    assert (ideal.lidar_model, ideal.camera_hz, ideal.localisation) == ("ideal", 50.0, "true")
    mixed = EnvConfig.from_kwargs(sensor_profile="ideal", camera_hz=25.0, localisation="qcar2")
    assert (mixed.camera_hz, mixed.localisation) == (25.0, "qcar2")


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"sensor_profile": "real"}, r"sensor_profile must be one of \('qcar2', 'ideal'\), got 'real'"),
    ({"camera_hz": 60.0}, r"camera_hz must be in \(0, control_hz=50.0\] Hz, got 60.0"),
    ({"a2m12_samples_per_rev": 4}, r"samples_per_rev must be an integer in \[8, 20000\], got 4"),
    ({"a2m12_read_per_rev": 2000}, r"read_per_rev must be an integer in \[1, samples_per_rev=1600\], got 2000"),
    ({"a2m12_dropout_pole": 1.5}, r"dropout_pole must be in \[0.0, 1.0\], got 1.5"),
    ({"a2m12_n_bins": 361}, r"n_bins must be even"),
    ({"a2m12_grazing_start_deg": 80.0, "a2m12_grazing_end_deg": 70.0}, r"grazing_end_deg must exceed"),
    ({"a2m12_beams": 3}, r"unknown env option 'a2m12_beams'; allowed: .*a2m12_sub_rays"),
])
def test_bad_sensor_settings_fail_before_any_work_naming_what_is_allowed(kwargs, message):
    with pytest.raises(ValueError, match=message):
        EnvConfig.from_kwargs(**kwargs)
