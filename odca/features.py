"""Delta-head inputs from the latest observation, the prior's (mu, sigma) and the vehicle state.

All features are causal and use measurements only (no feedback of ODCA's own output), so
a whole series is featurised in one vectorised pass and the online step gives the same
numbers. Invalid inputs are sanitised first: depth or LiDAR that is NaN, inf, <= 0 or
beyond ``MAX_RANGE_M`` is missing; confidence is clipped to [0, 1] (NaN -> 0); speed is
clipped to +-10 m/s (NaN -> 0).
"""

from __future__ import annotations

import numpy as np

__all__ = ["FEATURE_NAMES", "MAX_RANGE_M", "sanitize", "usable_forecast", "features", "base_distance"]

MAX_RANGE_M = 50.0
FEATURE_NAMES = ("base_minus_mu", "sigma", "confidence", "depth_missing", "lidar_available",
                 "base_minus_lidar", "speed", "kinematic_residual", "prior_available", "lidar_minus_mu")


def sanitize(depth, confidence, lidar, speed):
    """(depth, confidence, lidar, speed) as float arrays with the module's conventions."""
    d = np.asarray(depth, float)
    l = np.asarray(lidar, float)
    d = np.where(np.isfinite(d) & (d > 0) & (d <= MAX_RANGE_M), d, np.nan)
    l = np.where(np.isfinite(l) & (l > 0) & (l <= MAX_RANGE_M), l, np.nan)
    c = np.clip(np.nan_to_num(np.asarray(confidence, float), nan=0.0, posinf=1.0, neginf=0.0), 0.0, 1.0)
    v = np.clip(np.nan_to_num(np.asarray(speed, float), nan=0.0, posinf=10.0, neginf=-10.0), -10.0, 10.0)
    return d, c, l, v


def usable_forecast(mean, std):
    """The prior's (mean, std) where they can describe a distance, NaN elsewhere.

    A mean outside (0, ``MAX_RANGE_M``] or a std that is not finite is a forecast the prior
    got wrong: the shipped tiny prior can blow up on a context unlike its training series
    (a -15 m mean with a 25 m std was seen on a test drive). The head then treats the prior
    as missing, as it does before the first context, and repairs from the LiDAR or the hold.
    """
    mean, std = np.asarray(mean, float), np.asarray(std, float)
    ok = np.isfinite(mean) & (mean > 0) & (mean <= MAX_RANGE_M) & np.isfinite(std)
    return np.where(ok, mean, np.nan), np.where(ok, std, np.nan)


def base_distance(d, mu, l_al, hold):
    """What the repair adds to: the depth, else the prior's mean, else the aligned LiDAR, else the last depth held."""
    return np.where(np.isfinite(d), d, np.where(np.isfinite(mu), mu, np.where(np.isfinite(l_al), l_al, hold)))


def features(d, c, l_al, v, mu, sigma, d_prev, hold, dt):
    """(N, 10) features; every entry finite. Arguments are (N,) arrays (already sanitised)."""
    base = base_distance(d, mu, l_al, hold)
    mu_ok = np.isfinite(mu)
    l_ok = np.isfinite(l_al)
    kin = np.where(np.isfinite(d) & np.isfinite(d_prev), d - d_prev + v * dt, 0.0)
    cols = (np.where(mu_ok, base - mu, 0.0), np.where(np.isfinite(sigma), sigma, 0.0), c,
            (~np.isfinite(d)).astype(float), l_ok.astype(float), np.where(l_ok, base - l_al, 0.0), v, kin,
            mu_ok.astype(float), np.where(l_ok & mu_ok, l_al - mu, 0.0))
    x = np.stack([np.asarray(col, float) for col in cols], axis=-1)
    # Bound every feature: a wild input must not blow the head up.
    return np.clip(np.nan_to_num(x, nan=0.0, posinf=0.0, neginf=0.0), -MAX_RANGE_M, MAX_RANGE_M)
