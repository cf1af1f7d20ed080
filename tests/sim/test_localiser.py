"""The localisation fix: drift bound, period and y delay, determinism, white noise, exact mode, config checks."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from racf.sim.sensors import LocalisationFix, LocaliserConfig, Sensor

MAX = 0.07 / math.sqrt(2)


class _Car:
    """Stands in for QCar2: only ``state(data)`` is read."""

    def __init__(self, x=0.0, y=0.0, yaw=0.0):
        self.pose = SimpleNamespace(x=x, y=y, yaw=yaw)

    def state(self, data):
        return self.pose


def _fix(seed=0, config=None, **kwargs):
    fix = LocalisationFix(_Car(), config, **kwargs)
    fix.reset(np.random.default_rng(seed))
    return fix


def _drifts(fix, times):
    return np.array([fix.drift(t) for t in times])


def _sign_changes(values, times):
    """Times where ``values`` changes sign (first sample after the change)."""
    s = np.sign(values)
    return times[1:][s[1:] * s[:-1] < 0]


def test_is_a_sensor_with_the_gps_space():
    fix = LocalisationFix(_Car())
    assert isinstance(fix, Sensor)
    assert (fix.name, fix.shape, fix.dtype) == ("gps", (3,), np.float32)


def test_drift_never_exceeds_the_saturation_bound():
    times = np.arange(0.0, 600.0, 0.7)
    peak = 0.0
    for seed in range(30):
        d = _drifts(_fix(seed), times)
        assert np.abs(d).max() <= MAX
        peak = max(peak, np.abs(d).max())
    assert peak > 0.5 * MAX  # the bound is approached, not trivially met
    # A huge noise power saturates the amplitude: the drift reaches the bound and never passes it.
    loud = LocaliserConfig(drift_noise_power=1.0, drift_rate_limit=10.0)
    for seed in range(5):
        d = _drifts(_fix(seed, loud), times)
        assert np.abs(d).max() <= loud.drift_max_m
        assert np.abs(d).max() == pytest.approx(loud.drift_max_m, rel=1e-3)


def test_drift_has_the_sine_period():
    times = np.arange(0.0, 300.0, 0.05)
    for seed in range(5):
        d = _drifts(_fix(seed), times)
        for axis in (0, 1):
            gaps = np.diff(_sign_changes(d[:, axis], times))
            assert len(gaps) >= 18
            np.testing.assert_allclose(gaps, 15.0, atol=0.1)  # zero crossings every half period


def test_amplitude_is_abs_noise_of_variance_power_over_sample_time():
    # At the sine's peaks (midway between zero crossings) |drift| is the amplitude:
    # min(|N(0, power / sample time)|, drift_max) on average, 0.02 m std by default.
    times = np.arange(0.0, 16.0, 0.02)
    peaks = []
    for seed in range(20):
        fix = _fix(seed)
        for axis in (0, 1):
            first = _sign_changes(_drifts(fix, times)[:, axis], times)[0]
            peaks += [abs(fix.drift(t)[axis]) for t in first + 7.5 + 15.0 * np.arange(20)]
    want = np.minimum(np.abs(np.random.default_rng(0).standard_normal(10**6)) * math.sqrt(0.002 / 5.0), MAX).mean()
    assert np.mean(peaks) == pytest.approx(want, rel=0.1)


def test_amplitude_changes_no_faster_than_the_rate_limit():
    cfg = LocaliserConfig(drift_rate_limit=1e-3)
    omega, h = 2 * math.pi / cfg.drift_period_s, 0.01
    times = np.arange(-0.005, 200.0, 0.25)  # some steps straddle a new noise sample (every 5 s)
    for seed in range(5):
        fix = _fix(seed, cfg)
        step = np.abs(_drifts(fix, times + h) - _drifts(fix, times))
        # |d drift/dt| <= |amplitude'| + amplitude * omega
        assert step.max() <= cfg.drift_rate_limit * h + cfg.drift_max_m * omega * h + 1e-12


def _zero(fix, axis, lo, hi):
    """The time in [lo, hi] where the axis's drift changes sign, by bisection to 1e-10 s."""
    f_lo = fix.drift(lo)[axis]
    while hi - lo > 1e-10:
        mid = 0.5 * (lo + hi)
        if np.sign(fix.drift(mid)[axis]) == np.sign(f_lo):
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def _y_lag(fix):
    """How far y's drift trails x's: the gap from an x zero crossing to the next y one, s."""
    times = np.arange(10.0, 40.0, 0.05)
    d = _drifts(fix, times)
    tx = _sign_changes(d[:, 0], times)[0]
    ty = _sign_changes(d[:, 1], times)
    ty = ty[ty > tx][0]
    return _zero(fix, 1, ty - 0.05, ty) - _zero(fix, 0, tx - 0.05, tx)


@pytest.mark.parametrize("fix_period_s", [0.1, 0.2])
def test_y_drift_trails_x_by_whole_fix_samples(fix_period_s):
    # The sine's zeros do not depend on the amplitude, so y's zero crossings trail x's by
    # exactly the delay (mod the half period): a whole number of fix samples in the range.
    samples = set()
    for seed in range(6):
        lag = _y_lag(_fix(seed, fix_period_s=fix_period_s)) / fix_period_s
        assert lag == pytest.approx(round(lag), abs=1e-6)
        assert 45 <= round(lag) <= 75
        samples.add(round(lag))
    assert len(samples) > 1  # drawn per episode


def test_same_seed_same_drift_in_any_order():
    times = np.linspace(0.0, 200.0, 101)
    a = _drifts(_fix(7), times)
    b = _drifts(_fix(7), times[::-1])[::-1]
    np.testing.assert_array_equal(a, b)
    assert not np.allclose(a, _drifts(_fix(8), times))
    assert np.abs(a[0]).max() > 0  # a random phase: episodes don't all start at zero drift


def test_exact_mode_is_the_true_pose_without_draws():
    car = _Car(1.25, -0.5, math.radians(170))
    fix = LocalisationFix(car, exact=True)
    rng = np.random.default_rng(0)
    fix.reset(rng)
    out = fix.read(None, SimpleNamespace(time=12.3), rng)
    assert out.dtype == np.float32
    np.testing.assert_allclose(out, [1.25, -0.5, math.radians(170)], atol=1e-6)
    np.testing.assert_array_equal(fix.drift(12.3), [0.0, 0.0])
    assert rng.random() == np.random.default_rng(0).random()  # nothing drawn


def test_white_noise_std_and_yaw_wrap():
    cfg = LocaliserConfig(noise_xy_m=0.01, noise_yaw_rad=0.02)
    car = _Car(0.3, 0.4, math.pi - 0.001)
    fix = LocalisationFix(car, cfg)
    rng = np.random.default_rng(1)
    fix.reset(rng)
    times = np.arange(4000) * 0.1
    reads = np.array([fix.read(None, SimpleNamespace(time=t), rng) for t in times], np.float64)
    err = reads[:, :2] - np.array([0.3, 0.4]) - _drifts(fix, times)
    np.testing.assert_allclose(err.std(axis=0), 0.01, rtol=0.1)
    assert np.abs(err.mean(axis=0)).max() < 1e-3
    assert (reads[:, 2] > -math.pi - 1e-6).all() and (reads[:, 2] <= math.pi + 1e-6).all()
    assert (reads[:, 2] < 0).any()  # headings past pi wrap round
    yaw_err = np.angle(np.exp(1j * (reads[:, 2] - car.pose.yaw)))
    assert yaw_err.std() == pytest.approx(0.02, rel=0.1)


@pytest.mark.parametrize("field, value", [
    ("drift_period_s", 0.0), ("drift_noise_power", -1e-3), ("drift_sample_s", math.nan),
    ("drift_rate_limit", 0.0), ("drift_max_m", 2.0), ("y_delay_samples", (75, 45)),
    ("y_delay_samples", (1.0, 2.0)), ("noise_xy_m", -0.01), ("noise_yaw_rad", 4.0),
])
def test_bad_config_names_the_field(field, value):
    with pytest.raises(ValueError, match=field):
        LocaliserConfig(**{field: value})


def test_bad_fix_period_names_it():
    with pytest.raises(ValueError, match="fix_period_s"):
        LocalisationFix(_Car(), fix_period_s=0.0)
