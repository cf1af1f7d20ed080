"""Synthetic series to pretrain the temporal prior (no real or simulator data needed).

Four families, mixed: kinematic approach curves (distance to an obstacle while cruising,
braking and stopping, with depth-camera-like noise and dropouts), kernel-synth style
series (random sums of smooth, periodic and trend components), piecewise-constant steps,
and AR(1) noise. Lengths 160-400 samples; everything comes from the given generator.
"""

from __future__ import annotations

import numpy as np

__all__ = ["synthetic_series", "approach_curve"]

DT = 0.02


def approach_curve(rng: np.random.Generator, n: int) -> np.ndarray:
    """Distance to an obstacle for a car cruising, braking and stopping, with sensor noise."""
    v = rng.uniform(0.5, 2.5)
    d = rng.uniform(1.0, 4.0)
    brake_at = rng.uniform(0.3, 1.5)
    decel = rng.uniform(1.0, 6.0)
    out = np.empty(n)
    for i in range(n):
        if d < brake_at + v * v / (2 * decel) and v > 0:
            v = max(0.0, v - decel * DT)
        d -= v * DT
        out[i] = d
    out = out + rng.normal(0, 1, n) * rng.uniform(0.001, 0.006) * out**2
    out[rng.random(n) < rng.uniform(0.0, 0.05)] = np.nan
    # The target often comes into view late (nothing measured before) or leaves it for a while.
    if rng.random() < 0.5:
        out[:int(rng.integers(0, n // 2))] = np.nan
    if rng.random() < 0.3:
        start = int(rng.integers(0, n - 10))
        out[start:start + int(rng.integers(5, 40))] = np.nan
    return out


def _kernel_synth(rng: np.random.Generator, n: int) -> np.ndarray:
    t = np.arange(n) * DT
    y = rng.normal(0, 1) + rng.normal(0, 0.3) * t
    for _ in range(rng.integers(1, 5)):
        period = rng.uniform(0.3, 8.0)
        y += rng.normal(0, 0.5) * np.sin(2 * np.pi * t / period + rng.uniform(0, 2 * np.pi))
    return y + rng.normal(0, rng.uniform(0.005, 0.1), n)


def _steps(rng: np.random.Generator, n: int) -> np.ndarray:
    y = np.zeros(n)
    level = rng.normal(0, 1)
    for i in range(n):
        if rng.random() < 0.02:
            level += rng.normal(0, 1)
        y[i] = level
    return y + rng.normal(0, rng.uniform(0.005, 0.05), n)


def _ar1(rng: np.random.Generator, n: int) -> np.ndarray:
    phi = rng.uniform(0.5, 0.99)
    y = np.zeros(n)
    for i in range(1, n):
        y[i] = phi * y[i - 1] + rng.normal(0, 0.1)
    return y + rng.normal(0, 1)


def synthetic_series(n_series: int, seed: int, min_len: int = 160, max_len: int = 400) -> list[np.ndarray]:
    """``n_series`` float32 series: 4/7 approach curves, the rest kernel-synth, steps and AR(1)."""
    rng = np.random.default_rng(seed)
    makers = (approach_curve, approach_curve, approach_curve, approach_curve, _kernel_synth, _steps, _ar1)
    out = []
    for _ in range(n_series):
        n = int(rng.integers(min_len, max_len + 1))
        out.append(makers[int(rng.integers(len(makers)))](rng, n).astype(np.float32))
    return out
