"""The EKF baseline: closed-form cases, missing measurements and causality."""

import math

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from racf.controllers.ekf import DistanceEKF, EKFConfig


def test_first_update_is_the_measurement_and_equal_noise_fuses_to_the_mean():
    f = DistanceEKF(EKFConfig(depth_std_m=0.03, lidar_std_m=0.03))
    # First depth initialises (variance 0.03^2); an equally noisy LiDAR value then averages with it.
    assert f.step(1.00, 1.0, 1.10, speed=0.0, dt=0.02) == pytest.approx(1.05)
    assert f.P[0, 0] == pytest.approx(0.03 ** 2 / 2)


def test_prediction_follows_odometry_without_measurements():
    f = DistanceEKF()
    f.step(2.0, 1.0, math.nan, speed=1.0, dt=0.02)
    for _ in range(10):
        d = f.step(math.nan, 0.0, math.nan, speed=1.0, dt=0.02)
    assert d == pytest.approx(2.0 - 10 * 0.02, abs=1e-9)  # r stays 0: pure dead reckoning


def test_low_confidence_depth_counts_for_less():
    a, b = DistanceEKF(), DistanceEKF()
    for f in (a, b):
        f.step(math.nan, 0.0, 1.0, speed=0.0, dt=0.02)
    sure = a.step(1.2, 1.0, math.nan, speed=0.0, dt=0.02)
    unsure = b.step(1.2, 0.1, math.nan, speed=0.0, dt=0.02)
    assert 1.0 < unsure < sure < 1.2


def test_nan_before_any_measurement_and_after_the_drop_time():
    f = DistanceEKF(EKFConfig(drop_after_s=0.1))
    assert math.isnan(f.step(math.nan, 0.0, math.nan, 1.0, 0.02))
    f.step(1.0, 1.0, math.nan, 1.0, 0.02)
    outs = [f.step(math.nan, 0.0, math.nan, 1.0, 0.02) for _ in range(10)]
    assert math.isfinite(outs[0]) and math.isnan(outs[-1])
    with pytest.raises(ValueError, match="dt"):
        f.step(1.0, 1.0, 1.0, 1.0, 0.0)
    with pytest.raises(ValueError, match="lidar_std_m"):
        EKFConfig(lidar_std_m=-1.0)


@settings(max_examples=25, deadline=None)
@given(st.lists(st.floats(0.2, 3.0), min_size=6, max_size=30), st.integers(1, 5))
def test_changing_the_future_does_not_change_the_past(depths, cut):
    cut = min(cut, len(depths) - 1)
    def run(ds):
        f = DistanceEKF()
        return np.array([f.step(d, 0.9, d + 0.01, 1.0, 0.02) for d in ds])
    future = list(depths[:cut]) + [9.0] * (len(depths) - cut)
    np.testing.assert_array_equal(run(depths)[:cut], run(future)[:cut])


def test_without_process_noise_the_filter_is_the_batch_least_squares_estimate():
    # With (almost) no process noise and the car at rest, the state [d, r] is constant but for
    # d drifting by r per second, so the filter's estimate must equal the closed-form
    # regularised least-squares fit of d0 + r t to the measurements, with the filter's prior
    # on r (N(0, init_rate_std^2)) as the regulariser.
    cfg = EKFConfig(depth_std_m=0.05, accel_std_mps2=1e-9, init_rate_std_mps=0.3)
    rng = np.random.default_rng(4)
    dt, n = 0.02, 40
    t = np.arange(n) * dt
    z = 2.0 - 0.4 * t + rng.normal(0, 0.05, n)
    f = DistanceEKF(cfg)
    out = [f.step(zk, 1.0, math.nan, speed=0.0, dt=dt) for zk in z]
    # Prior: d0 ~ N(z0, R) (the first measurement initialises), r ~ N(0, s^2); then z1..z_{n-1}.
    R, s2 = cfg.depth_std_m ** 2, cfg.init_rate_std_mps ** 2
    A = np.column_stack([np.ones(n), t])
    prior_precision = np.diag([0.0, 1.0 / s2])
    theta = np.linalg.solve(A.T @ A / R + prior_precision, A.T @ z / R)
    assert out[-1] == pytest.approx(theta[0] + theta[1] * t[-1], abs=1e-6)
